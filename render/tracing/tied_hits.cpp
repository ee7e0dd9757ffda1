#include "render/tracing/tied_hits.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <tuple>

#include "render/shading/sampler.hpp"

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

TiedHits::TiedHits(const Scene& scene) : scene_(scene) {
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

  // Vertices by position: equal coordinates, one position (a mesh may repeat a vertex for each face), numbered in
  // the order they first appear. An open-addressing table of the first vertex seen at each place (sorting the
  // vertices took twice as long).
  const auto vertices = scene.vertices();
  auto bits = [](float f) {
    uint32_t b;
    const float positive_zero = f + 0.0f;  // -0 and 0 are one place
    std::memcpy(&b, &positive_zero, sizeof b);
    return uint64_t{b};
  };
  size_t slots = 16;
  while (slots < 2 * vertices.size()) slots *= 2;
  std::vector<uint32_t> first_at(slots, UINT32_MAX);
  position_of_vertex_.assign(vertices.size(), 0);
  uint32_t positions = 0;
  for (uint32_t i = 0; i < vertices.size(); ++i) {
    const Vec3 p = vertices[i];
    size_t slot = splitmix64((bits(p.x) | bits(p.y) << 32) ^ (bits(p.z) * 0x9e3779b97f4a7c15ull)) & (slots - 1);
    while (first_at[slot] != UINT32_MAX) {
      const Vec3 q = vertices[first_at[slot]];
      if (q.x == p.x && q.y == p.y && q.z == p.z) break;
      slot = (slot + 1) & (slots - 1);
    }
    if (first_at[slot] == UINT32_MAX) {
      first_at[slot] = i;
      position_of_vertex_[i] = positions++;
    } else {
      position_of_vertex_[i] = position_of_vertex_[first_at[slot]];
    }
  }
  fan_first_.assign(positions + 1, 0);
  const auto triangles = scene.triangles();
  for (uint32_t t = 0; t < n; ++t)
    for (int c = 0; c < 3; ++c) ++fan_first_[position_of_vertex_[triangles[t][c]] + 1];
  for (uint32_t p = 0; p < positions; ++p) fan_first_[p + 1] += fan_first_[p];
  fan_.resize(fan_first_[positions]);
  std::vector<uint32_t> filled(fan_first_.begin(), fan_first_.end() - 1);
  for (uint32_t t = 0; t < n; ++t)
    for (int c = 0; c < 3; ++c) fan_[filled[position_of_vertex_[triangles[t][c]]]++] = t;
}

size_t TiedHits::tied_triangles() const {
  size_t count = 0;
  for (size_t t = 0; t + 1 < first_.size(); ++t) count += first_[t + 1] > first_[t] ? 1 : 0;
  return count;
}

std::vector<uint32_t> TiedHits::partners(uint32_t t) const {
  return {partners_.begin() + first_[t], partners_.begin() + first_[t + 1]};
}

std::vector<uint32_t> TiedHits::fan(uint32_t t, int corner) const {
  const uint32_t p = position_of_vertex_[scene_.triangles()[t][corner]];
  return {fan_.begin() + fan_first_[p], fan_.begin() + fan_first_[p + 1]};
}

namespace {

// Moeller-Trumbore, the same formula for every face and every tracer: whether the ray meets face c within `slack`
// (in barycentrics) of it, where (u, v: corners 1 and 2) and at what distance t.
bool meets(const Scene& scene, const Ray& ray, uint32_t c, float slack, float& u, float& v, float& t) {
  const Vec3 v0 = scene.vertex(c, 0), e1 = scene.vertex(c, 1) - v0, e2 = scene.vertex(c, 2) - v0;
  const Vec3 p = cross(ray.direction, e2);
  const float det = dot(e1, p);
  if (det == 0) return false;
  const float inv = 1.0f / det;
  const Vec3 s = ray.origin - v0;
  u = dot(s, p) * inv;
  const Vec3 q = cross(s, e1);
  v = dot(ray.direction, q) * inv;
  t = dot(e2, q) * inv;
  return u >= -slack && v >= -slack && u + v <= 1 + slack && t > 0;
}

}  // namespace

Hit TiedHits::settle(const Ray& ray, Hit hit) const {
  if (!hit.valid()) return hit;
  const bool overlapped = first_[hit.triangle] != first_[hit.triangle + 1];
  // Whether the hit is next to an edge is decided on barycentrics worked out here, by one formula, so that every
  // tracer decides alike (a BVH's own differ in the last bits, which would move a hit at the band's border).
  float u = 1.0f / 3, v = 1.0f / 3, t = 0;
  constexpr float any = 1e30f;
  if (!meets(scene_, ray, hit.triangle, any, u, v, t)) u = v = 1.0f / 3;  // parallel: only partners can tie
  if (!overlapped && std::min({1 - u - v, u, v}) >= kEdgeBand) return hit;
  return settle_among_neighbours(ray, hit, u, v, t > 0 ? t : hit.t);
}

Hit TiedHits::settle(const Ray& ray, Hit hit, float u, float v) const {
  if (!hit.valid()) return hit;
  const bool overlapped = first_[hit.triangle] != first_[hit.triangle + 1];
  if (!overlapped && std::min({1 - u - v, u, v}) >= kCoarseBand) return hit;
  return settle(ray, hit);
}

Hit TiedHits::settle_among_neighbours(const Ray& ray, Hit hit, float u, float v, float distance) const {
  Hit best{};
  bool best_front = false;
  // A neighbour ties only where it meets the ray on its own edge at the same distance: a face with a corner at the
  // edge's end may also be met elsewhere along the ray (the floor beyond a wall's bottom edge), which is no tie. An
  // overlapping partner of a neighbour may hold the point inside it, so for it only the distance counts.
  enum class Kind { reported, neighbour, neighbours_partner };
  auto consider = [&](uint32_t c, Kind kind) {
    // A little slack at the edges, so that the face the BVH reported is not lost to rounding, and a neighbour the ray
    // meets on their shared edge is found from either side.
    constexpr float slack = 1e-5f;
    float cu = 0, cv = 0, t = 0;
    if (!meets(scene_, ray, c, slack, cu, cv, t)) return;
    if (kind != Kind::reported && !(std::fabs(t - distance) <= kSameDistance * distance)) return;
    if (kind == Kind::neighbour && std::min({1 - cu - cv, cu, cv}) >= kEdgeBand) return;
    if (!scene_.opaque(c, {1 - cu - cv, cu, cv})) return;
    const bool front = dot(scene_.normal(c), ray.direction) < 0;
    if (!best.valid() || (front && !best_front) || (front == best_front && c < best.triangle)) {
      best = Hit{c, t};
      best_front = front;
    }
  };
  consider(hit.triangle, Kind::reported);
  for (uint32_t k = first_[hit.triangle]; k < first_[hit.triangle + 1]; ++k) consider(partners_[k], Kind::reported);
  // The corners at the ends of the edges the hit is next to: every face with a corner there.
  const float weight[3] = {1 - u - v, u, v};
  bool corner_near[3] = {false, false, false};
  for (int j = 0; j < 3; ++j)
    if (weight[j] < kEdgeBand)
      for (int c = 0; c < 3; ++c) corner_near[c] = corner_near[c] || c != j;
  const auto& corners = scene_.triangles()[hit.triangle];
  for (int c = 0; c < 3; ++c) {
    if (!corner_near[c]) continue;
    const uint32_t p = position_of_vertex_[corners[c]];
    for (uint32_t k = fan_first_[p]; k < fan_first_[p + 1]; ++k) {
      const uint32_t f = fan_[k];
      consider(f, Kind::neighbour);
      for (uint32_t m = first_[f]; m < first_[f + 1]; ++m) consider(partners_[m], Kind::neighbours_partner);
    }
  }
  return best.valid() ? best : hit;
}

}  // namespace lf
