#include "render/caches/directional_cache.hpp"

#include <algorithm>
#include <cmath>

namespace lf {

void direction_to_map(Vec3 d, float& u, float& v) {
  u = std::clamp((d.z + 1) * 0.5f, 0.0f, std::nextafter(1.0f, 0.0f));
  float phi = std::atan2(d.y, d.x);
  if (phi < 0) phi += 6.28318531f;
  v = std::clamp(phi * 0.159154943f, 0.0f, std::nextafter(1.0f, 0.0f));
}

DirectionalCache::DirectionalCache(const Scene& scene, const DirectionalCacheOptions& options) : options_(options) {
  const Bounds b = scene.bounds();
  const Vec3 extent = b.hi - b.lo;
  const float longest = std::max({extent.x, extent.y, extent.z, 1e-6f});
  cell_size_ = longest / static_cast<float>(std::max(1, options_.cells));
  origin_ = b.lo;
  for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / cell_size_)));
  radius_ = options_.radius * cell_size_ * 0.8660254f;  // times the half-diagonal of a cube
}

uint32_t DirectionalCache::cell_of(Vec3 p) const {
  int idx[3];
  for (int a = 0; a < 3; ++a)
    idx[a] = std::clamp(static_cast<int>(std::floor((p[a] - origin_[a]) / cell_size_)), 0, dims_[a] - 1);
  return static_cast<uint32_t>((idx[2] * dims_[1] + idx[1]) * dims_[0] + idx[0]);
}

Vec3 DirectionalCache::centre_of(uint32_t cell) const {
  const int x = static_cast<int>(cell % static_cast<uint32_t>(dims_[0]));
  const int y = static_cast<int>((cell / static_cast<uint32_t>(dims_[0])) % static_cast<uint32_t>(dims_[1]));
  const int z = static_cast<int>(cell / static_cast<uint32_t>(dims_[0] * dims_[1]));
  return origin_ + Vec3{(static_cast<float>(x) + 0.5f) * cell_size_, (static_cast<float>(y) + 0.5f) * cell_size_,
                        (static_cast<float>(z) + 0.5f) * cell_size_};
}

float DirectionalCache::local_reach(uint32_t cell, Vec3 origin, Vec3 d) const {
  // The far root of |origin + t d - c| = r (d is unit); an origin outside the sphere (a cell's corner region) still
  // gets the far crossing, or 0 when the ray misses the sphere altogether.
  const Vec3 oc = origin - centre_of(cell);
  const float b = dot(oc, d);
  const float c = dot(oc, oc) - radius_ * radius_;
  const float disc = b * b - c;
  if (disc <= 0) return 0;
  return std::max(0.0f, -b + std::sqrt(disc));
}

uint32_t DirectionalCache::leaf_of(const std::vector<Node>& tree, float u, float v) {
  uint32_t at = 0;
  float u0 = 0, v0 = 0, size = 1;
  while (tree[at].first_child >= 0) {
    size *= 0.5f;
    const int qu = u >= u0 + size ? 1 : 0, qv = v >= v0 + size ? 1 : 0;
    u0 += static_cast<float>(qu) * size;
    v0 += static_cast<float>(qv) * size;
    at = static_cast<uint32_t>(tree[at].first_child + qu + 2 * qv);
  }
  return at;
}

bool DirectionalCache::answers(const Node& leaf) const {
  if (leaf.depth < options_.uniform_depth || leaf.count < static_cast<uint32_t>(options_.min_samples)) return false;
  if (leaf.depth >= options_.max_depth) return true;
  const float variance = leaf.luminance_m2 / static_cast<float>(leaf.count - 1);
  return std::sqrt(std::max(0.0f, variance)) <= options_.max_relative_spread * std::max(leaf.luminance_mean, 1e-6f);
}

bool DirectionalCache::lookup(uint32_t cell, Vec3 d, RGB& radiance) const {
  auto it = trees_.find(cell);
  if (it == trees_.end()) return false;
  float u, v;
  direction_to_map(d, u, v);
  const Node& leaf = it->second[leaf_of(it->second, u, v)];
  if (!answers(leaf)) return false;
  radiance = leaf.mean;
  return true;
}

void DirectionalCache::record(uint32_t cell, Vec3 d, RGB radiance) {
  if (frozen_) return;
  if (!(std::isfinite(radiance.x) && std::isfinite(radiance.y) && std::isfinite(radiance.z))) return;
  std::vector<Node>& tree = trees_[cell];
  if (tree.empty()) tree.push_back(Node{});
  float u, v;
  direction_to_map(d, u, v);
  const uint32_t at = leaf_of(tree, u, v);
  Node& n = tree[at];
  ++n.count;
  const float w = 1.0f / static_cast<float>(n.count);
  n.mean += (radiance - n.mean) * w;
  const float y = average(radiance);
  const float delta = y - n.luminance_mean;
  n.luminance_mean += delta * w;
  n.luminance_m2 += delta * (y - n.luminance_mean);
  if (n.count < static_cast<uint32_t>(options_.min_samples) || n.depth >= options_.max_depth) return;
  if (n.depth >= options_.uniform_depth) {
    const float spread = std::sqrt(std::max(0.0f, n.luminance_m2 / static_cast<float>(n.count - 1)));
    if (spread <= options_.max_relative_spread * std::max(n.luminance_mean, 1e-6f)) return;
  }
  // Split: four children start from this node's mean with a count of one.
  Node child;
  child.mean = n.mean;
  child.luminance_mean = n.luminance_mean;
  child.count = 1;
  child.depth = static_cast<uint8_t>(n.depth + 1);
  const int32_t first = static_cast<int32_t>(tree.size());
  tree[at].first_child = first;  // (n may move when the vector grows)
  for (int k = 0; k < 4; ++k) tree.push_back(child);
}

size_t DirectionalCache::nodes() const {
  size_t n = 0;
  for (const auto& [cell, tree] : trees_) n += tree.size();
  return n;
}

}  // namespace lf
