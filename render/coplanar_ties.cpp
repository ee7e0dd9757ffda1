#include "render/coplanar_ties.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace lf {

namespace {

using Key = std::array<int64_t, 4>;

struct Flat {
  uint32_t triangle;
  std::array<double, 2> corner[3];
  double lo[2], hi[2];
};

// Whether two triangles of one plane share area (not just an edge or a corner): no edge normal of either separates
// their projections by more than `touch`.
bool overlap(const Flat& a, const Flat& b, double touch) {
  for (const Flat* f : {&a, &b})
    for (int e = 0; e < 3; ++e) {
      const auto& p = f->corner[e];
      const auto& q = f->corner[(e + 1) % 3];
      const double ax = q[1] - p[1], ay = p[0] - q[0];
      const double len = std::hypot(ax, ay);
      if (len == 0) return false;  // a degenerate face covers no area
      double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
      for (int c = 0; c < 3; ++c) {
        const double pa = (a.corner[c][0] * ax + a.corner[c][1] * ay) / len;
        const double pb = (b.corner[c][0] * ax + b.corner[c][1] * ay) / len;
        amin = std::min(amin, pa);
        amax = std::max(amax, pa);
        bmin = std::min(bmin, pb);
        bmax = std::max(bmax, pb);
      }
      if (amax <= bmin + touch || bmax <= amin + touch) return false;
    }
  return true;
}

// The axis along which a normal is largest: its plane is then seen best in the other two.
int largest_axis(Vec3 n) {
  const float x = std::fabs(n.x), y = std::fabs(n.y), z = std::fabs(n.z);
  return x >= y && x >= z ? 0 : (y >= z ? 1 : 2);
}

}  // namespace

CoplanarTies::CoplanarTies(const Scene& scene) : scene_(scene) {
  const size_t n = scene.triangle_count();
  const double size = std::max(1e-6, static_cast<double>(scene.bounds().diagonal()));
  const double offset_step = 1e-4 * size, touch = 1e-7 * size;
  std::vector<std::pair<Key, uint32_t>> keyed;
  keyed.reserve(n);
  for (uint32_t t = 0; t < n; ++t) {
    Vec3 nrm = scene.normal(t);
    if (!(std::fabs(nrm.x) + std::fabs(nrm.y) + std::fabs(nrm.z) > 0)) continue;
    // One orientation per plane: the largest component positive (twins facing away from each other meet here).
    if (nrm[largest_axis(nrm)] < 0) nrm = -nrm;
    const double d = dot(nrm, scene.vertex(t, 0));
    keyed.push_back({Key{std::llround(nrm.x * 1e4), std::llround(nrm.y * 1e4), std::llround(nrm.z * 1e4),
                         std::llround(d / offset_step)},
                     t});
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  std::vector<Flat> flats;
  std::vector<size_t> active;
  for (size_t begin = 0; begin < keyed.size();) {
    size_t end = begin + 1;
    while (end < keyed.size() && keyed[end].first == keyed[begin].first) ++end;
    if (end - begin >= 2) {
      // In the plane: drop the normal's largest axis, then sweep along the first remaining one.
      const int drop = largest_axis(scene.normal(keyed[begin].second));
      const int u = drop == 0 ? 1 : 0, v = drop == 2 ? 1 : 2;
      flats.clear();
      for (size_t k = begin; k < end; ++k) {
        Flat f{keyed[k].second, {}, {1e300, 1e300}, {-1e300, -1e300}};
        for (int c = 0; c < 3; ++c) {
          const Vec3 p = scene.vertex(f.triangle, c);
          f.corner[c] = {p[u], p[v]};
          for (int a = 0; a < 2; ++a) {
            f.lo[a] = std::min(f.lo[a], f.corner[c][a]);
            f.hi[a] = std::max(f.hi[a], f.corner[c][a]);
          }
        }
        flats.push_back(f);
      }
      std::sort(flats.begin(), flats.end(), [](const Flat& a, const Flat& b) {
        return std::tie(a.lo[0], a.triangle) < std::tie(b.lo[0], b.triangle);
      });
      active.clear();
      for (size_t i = 0; i < flats.size(); ++i) {
        const Flat& f = flats[i];
        std::erase_if(active, [&](size_t j) { return flats[j].hi[0] <= f.lo[0] + touch; });
        for (size_t j : active) {
          const Flat& g = flats[j];
          if (g.hi[1] <= f.lo[1] + touch || f.hi[1] <= g.lo[1] + touch) continue;
          if (overlap(f, g, touch)) {
            pairs.push_back({f.triangle, g.triangle});
            pairs.push_back({g.triangle, f.triangle});
          }
        }
        active.push_back(i);
      }
    }
    begin = end;
  }
  std::sort(pairs.begin(), pairs.end());
  first_.assign(n + 1, 0);
  for (const auto& p : pairs) ++first_[p.first + 1];
  for (size_t t = 0; t < n; ++t) first_[t + 1] += first_[t];
  partners_.reserve(pairs.size());
  for (const auto& p : pairs) partners_.push_back(p.second);
}

size_t CoplanarTies::tied_triangles() const {
  size_t count = 0;
  for (size_t t = 0; t + 1 < first_.size(); ++t) count += first_[t + 1] > first_[t] ? 1 : 0;
  return count;
}

std::vector<uint32_t> CoplanarTies::partners(uint32_t t) const {
  return {partners_.begin() + first_[t], partners_.begin() + first_[t + 1]};
}

Hit CoplanarTies::settle(const Ray& ray, Hit hit) const {
  if (!hit.valid() || first_[hit.triangle] == first_[hit.triangle + 1]) return hit;
  Hit best{};
  bool best_front = false;
  auto consider = [&](uint32_t c) {
    // Moeller-Trumbore, the same formula for every face and every tracer; a little slack at the edges so that the
    // face the BVH reported is not lost to rounding.
    const Vec3 v0 = scene_.vertex(c, 0), e1 = scene_.vertex(c, 1) - v0, e2 = scene_.vertex(c, 2) - v0;
    const Vec3 p = cross(ray.direction, e2);
    const float det = dot(e1, p);
    if (det == 0) return;
    const float inv = 1.0f / det;
    const Vec3 s = ray.origin - v0;
    const float u = dot(s, p) * inv;
    const Vec3 q = cross(s, e1);
    const float v = dot(ray.direction, q) * inv;
    const float t = dot(e2, q) * inv;
    constexpr float slack = 1e-5f;
    if (u < -slack || v < -slack || u + v > 1 + slack || !(t > 0)) return;
    if (!scene_.opaque(c, {1 - u - v, u, v})) return;
    const bool front = dot(scene_.normal(c), ray.direction) < 0;
    if (!best.valid() || (front && !best_front) || (front == best_front && c < best.triangle)) {
      best = Hit{c, t};
      best_front = front;
    }
  };
  consider(hit.triangle);
  for (uint32_t k = first_[hit.triangle]; k < first_[hit.triangle + 1]; ++k) consider(partners_[k]);
  return best.valid() ? best : hit;
}

}  // namespace lf
