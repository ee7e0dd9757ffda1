#pragma once
// Where a ray met a triangle, as shading sees it: the geometric normal decides sides (offsets, which way light
// may come from), the shading normal (interpolated vertex normals, turned by a normal map) the cosines and the
// BSDF's frame.
#include "render/math.hpp"
#include "render/scene/scene.hpp"

namespace lf {

struct SurfacePoint {
  Vec3 ng;      // geometric normal, on wo's side
  Vec3 ns;      // shading normal, on wo's side (ng without vertex normals)
  bool front;   // wo is on the side the winding faces
};

inline SurfacePoint surface_at(const Scene& scene, uint32_t triangle, Vec3 p, Vec3 wo) {
  const Vec3 n = scene.normal(triangle);
  const bool front = dot(n, wo) > 0;
  const Vec3 ng = front ? n : -n;
  const bool mapped = scene.has_normal_maps() && scene.material(scene.material_of(triangle)).normal_map >= 0;
  if (!scene.has_shading_normals() && !mapped) return {ng, ng, front};
  const Vec3 b = scene.barycentrics(triangle, p);
  Vec3 ns = scene.has_shading_normals() ? scene.shading_normal(triangle, b) : n;
  if (mapped) ns = scene.normal_mapped(triangle, b, ns);
  if (!front) ns = -ns;
  // At silhouettes the interpolated normal can turn away from the viewer, which would shade black: the face's
  // normal then.
  if (dot(ns, wo) <= 0) ns = ng;
  return {ng, ns, front};
}

// Light arriving from wi counts only when wi is above both the shading and the geometric surface: a direction the
// shading normal allows but the face does not would come through the surface (a leak).
inline bool above_both(Vec3 wi, Vec3 ns, Vec3 ng) { return dot(wi, ns) > 0 && dot(wi, ng) > 0; }

}  // namespace lf
