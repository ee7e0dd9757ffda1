#include "render/shading/emitter_edges.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace lf {

size_t EmitterEdges::count() const { return static_cast<size_t>(std::count(marked.begin(), marked.end(), uint8_t{1})); }

namespace {

// Marks pixels on the image; points are in the camera's frame, in front of the eye.
class Marker {
 public:
  Marker(const Camera& camera, EmitterEdges& edges) : camera_(camera), edges_(edges) {}

  // The pixels within a pixel (and the lens's blur) of segment a-b.
  void segment(Vec3 a, Vec3 b) {
    const Vec2 pa = camera_.to_image(a), pb = camera_.to_image(b);
    float t0 = 0, t1 = 1;
    if (!clip_to_image(pa, pb, t0, t1)) return;
    const float dx = pb.u - pa.u, dy = pb.v - pa.v;
    const int steps = static_cast<int>(std::ceil(std::max(std::abs(dx), std::abs(dy)) * (t1 - t0) * 2)) + 1;
    for (int i = 0; i <= steps; ++i) {
      const float t = t0 + (t1 - t0) * static_cast<float>(i) / static_cast<float>(steps);
      // Depth along the projected segment: 1/z is linear in image space.
      const float depth = 1.0f / ((1 - t) / a.z + t / b.z);
      mark_around(pa.u + dx * t, pa.v + dy * t, 1.0f + camera_.blur_radius(depth));
    }
  }

  // Every pixel whose centre a convex polygon (in the camera's frame) covers; its outline is marked apart.
  void fill(const std::vector<Vec3>& polygon) {
    std::vector<Vec2> p;
    for (const Vec3& v : polygon) p.push_back(camera_.to_image(v));
    float lo_u = p[0].u, hi_u = p[0].u, lo_v = p[0].v, hi_v = p[0].v;
    for (const Vec2& q : p) lo_u = std::min(lo_u, q.u), hi_u = std::max(hi_u, q.u), lo_v = std::min(lo_v, q.v), hi_v = std::max(hi_v, q.v);
    const int x0 = std::max(0, static_cast<int>(std::floor(lo_u))), x1 = std::min(edges_.width - 1, static_cast<int>(std::ceil(hi_u)));
    const int y0 = std::max(0, static_cast<int>(std::floor(lo_v))), y1 = std::min(edges_.height - 1, static_cast<int>(std::ceil(hi_v)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float cu = static_cast<float>(x) + 0.5f, cv = static_cast<float>(y) + 0.5f;
        bool left = false, right = false;
        for (size_t i = 0; i < p.size(); ++i) {
          const Vec2 a = p[i], b = p[(i + 1) % p.size()];
          const float side = (b.u - a.u) * (cv - a.v) - (b.v - a.v) * (cu - a.u);
          left = left || side > 0;
          right = right || side < 0;
        }
        if (!(left && right)) edges_.marked[static_cast<size_t>(y) * edges_.width + x] = 1;
      }
  }

 private:
  // Liang-Barsky against the image widened by a pixel: the part [t0, t1] of a-b that can mark a pixel.
  bool clip_to_image(Vec2 a, Vec2 b, float& t0, float& t1) const {
    const float d[2] = {b.u - a.u, b.v - a.v}, lo[2] = {-2, -2};
    const float hi[2] = {static_cast<float>(edges_.width) + 2, static_cast<float>(edges_.height) + 2}, s[2] = {a.u, a.v};
    for (int k = 0; k < 2; ++k) {
      if (!std::isfinite(s[k]) || !std::isfinite(d[k])) return false;
      if (d[k] == 0) {
        if (s[k] < lo[k] || s[k] > hi[k]) return false;
        continue;
      }
      float ta = (lo[k] - s[k]) / d[k], tb = (hi[k] - s[k]) / d[k];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    return t0 <= t1;
  }

  void mark_around(float u, float v, float radius) {
    const int r = static_cast<int>(std::ceil(std::min(radius, 64.0f)));
    const int cx = static_cast<int>(std::floor(u)), cy = static_cast<int>(std::floor(v));
    for (int y = std::max(0, cy - r); y <= std::min(edges_.height - 1, cy + r); ++y)
      for (int x = std::max(0, cx - r); x <= std::min(edges_.width - 1, cx + r); ++x)
        edges_.marked[static_cast<size_t>(y) * edges_.width + x] = 1;
  }

  const Camera& camera_;
  EmitterEdges& edges_;
};

// Where segment a-b (camera frame, one end on each side) crosses the plane z = near.
Vec3 at_near(Vec3 a, Vec3 b, float near) { return a + (b - a) * ((near - a.z) / (b.z - a.z)); }

// The part of a triangle (camera frame) in front of the plane z = near (Sutherland-Hodgman).
std::vector<Vec3> in_front(const std::array<Vec3, 3>& corners, float near) {
  std::vector<Vec3> out;
  for (size_t i = 0; i < 3; ++i) {
    const Vec3 a = corners[i], b = corners[(i + 1) % 3];
    if (a.z >= near) out.push_back(a);
    if ((a.z >= near) != (b.z >= near)) out.push_back(at_near(a, b, near));
  }
  return out;
}

// The same for a segment: false when none of it is in front.
bool in_front(Vec3& a, Vec3& b, float near) {
  if (a.z < near && b.z < near) return false;
  if (a.z < near) a = at_near(a, b, near);
  if (b.z < near) b = at_near(b, a, near);
  return true;
}

using EdgeKey = std::array<float, 7>;  // the material, then both corners in a fixed order

EdgeKey edge_key(uint32_t material, Vec3 a, Vec3 b) {
  if (std::tie(b.x, b.y, b.z) < std::tie(a.x, a.y, a.z)) std::swap(a, b);
  return {static_cast<float>(material), a.x, a.y, a.z, b.x, b.y, b.z};
}

}  // namespace

EmitterEdges emitter_edges(const Scene& scene, const Camera& camera, const ImageSpec& image) {
  EmitterEdges edges;
  edges.width = image.width;
  edges.height = image.height;
  if (image.edge_spp <= image.spp || scene.emitters().empty()) return edges;
  edges.samples = image.edge_spp;
  edges.marked.assign(static_cast<size_t>(image.width) * image.height, 0);
  // A point closer to the eye's plane than this projects far outside the image; such corners are clipped away.
  const float near = 1e-5f * std::max(scene.bounds().diagonal(), 1e-3f);
  std::vector<uint32_t> seen;  // emitter triangles whose front the camera may see
  for (uint32_t t : scene.emitters()) {
    const Vec3 n = scene.normal(t), eye = camera.eye();
    // Through a lens the eye is anywhere on it: a triangle almost edge-on may still show its front.
    if (dot(n, eye - scene.vertex(t, 0)) > -camera.lens_radius()) seen.push_back(t);
  }
  auto varies = [&](uint32_t t) {
    const Material& m = scene.material(scene.material_of(t));
    return scene.has_uvs() && (m.emission_map >= 0 || m.alpha_map >= 0);
  };
  std::map<EdgeKey, int> shared;
  for (uint32_t t : seen)
    if (!varies(t))
      for (int c = 0; c < 3; ++c) ++shared[edge_key(scene.material_of(t), scene.vertex(t, c), scene.vertex(t, (c + 1) % 3))];
  Marker marker(camera, edges);
  for (uint32_t t : seen) {
    const std::array<Vec3, 3> world{scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2)};
    const std::array<Vec3, 3> view{camera.to_view(world[0]), camera.to_view(world[1]), camera.to_view(world[2])};
    const bool whole = varies(t);
    if (whole) {
      const std::vector<Vec3> polygon = in_front(view, near);
      if (polygon.size() >= 3) marker.fill(polygon);
    }
    for (int c = 0; c < 3; ++c) {
      if (!whole && shared.at(edge_key(scene.material_of(t), world[c], world[(c + 1) % 3])) > 1) continue;
      Vec3 a = view[c], b = view[(c + 1) % 3];
      if (in_front(a, b, near)) marker.segment(a, b);
    }
  }
  return edges;
}

}  // namespace lf
