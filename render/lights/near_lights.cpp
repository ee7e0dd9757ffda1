#include "render/lights/near_lights.hpp"

#include <algorithm>
#include <cmath>

#include "render/scene/scene.hpp"

namespace lf {

NearLights::NearLights(const Scene& scene, float reach) {
  for (const uint32_t t : scene.emitters()) {
    const Vec3 corners[3] = {scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2)};
    const Bounds box = bounds_of(corners);
    const float radius = reach * 0.5f * box.diagonal();
    if (radius > 0) zones_.push_back({(box.lo + box.hi) * 0.5f, radius * radius});
  }
  if (zones_.empty()) return;
  std::vector<float> radii;
  for (const Zone& z : zones_) radii.push_back(std::sqrt(z.radius2));
  std::nth_element(radii.begin(), radii.begin() + static_cast<ptrdiff_t>(radii.size() / 2), radii.end());
  inverse_cell_ = 1.0f / (2 * radii[radii.size() / 2]);
  origin_ = scene.bounds().lo;

  std::vector<std::pair<uint64_t, uint32_t>> entries;  // (cell key, zone), sorted into members_ below
  for (uint32_t z = 0; z < zones_.size(); ++z) {
    const float r = std::sqrt(zones_[z].radius2);
    const Vec3 c = zones_[z].centre;
    const int64_t x0 = cell_index(c.x - r, origin_.x), x1 = cell_index(c.x + r, origin_.x);
    const int64_t y0 = cell_index(c.y - r, origin_.y), y1 = cell_index(c.y + r, origin_.y);
    const int64_t z0 = cell_index(c.z - r, origin_.z), z1 = cell_index(c.z + r, origin_.z);
    if ((x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > kMostCells) {
      everywhere_.push_back(z);
      continue;
    }
    for (int64_t ix = x0; ix <= x1; ++ix)
      for (int64_t iy = y0; iy <= y1; ++iy)
        for (int64_t iz = z0; iz <= z1; ++iz) entries.emplace_back(key(ix, iy, iz), z);
  }
  std::sort(entries.begin(), entries.end());
  members_.reserve(entries.size());
  for (size_t i = 0; i < entries.size();) {
    size_t j = i;
    for (; j < entries.size() && entries[j].first == entries[i].first; ++j) members_.push_back(entries[j].second);
    cells_[entries[i].first] = {static_cast<uint32_t>(i), static_cast<uint32_t>(j)};
    i = j;
  }
}

int64_t NearLights::cell_index(float v, float lo) const {
  // Clamped to the 21 bits a key holds per axis: a point far outside the scene lands in an edge cell, where the
  // sphere test still decides.
  const double c = std::floor(static_cast<double>(v - lo) * inverse_cell_);
  return static_cast<int64_t>(std::clamp(c, -1048576.0, 1048575.0));
}

uint64_t NearLights::key(int64_t ix, int64_t iy, int64_t iz) const {
  auto bits = [](int64_t i) { return static_cast<uint64_t>(i + 1048576) & 0x1fffff; };
  return (bits(ix) << 42) | (bits(iy) << 21) | bits(iz);
}

bool NearLights::near(Vec3 x) const {
  for (const uint32_t z : everywhere_)
    if (inside(z, x)) return true;
  if (cells_.empty()) return false;
  const auto it = cells_.find(key(cell_index(x.x, origin_.x), cell_index(x.y, origin_.y), cell_index(x.z, origin_.z)));
  if (it == cells_.end()) return false;
  for (uint32_t i = it->second.first; i < it->second.second; ++i)
    if (inside(members_[i], x)) return true;
  return false;
}

}  // namespace lf
