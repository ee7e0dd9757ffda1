#pragma once
// Where a ray met a triangle, as shading sees it: the geometric normal decides sides (offsets, which way light
// may come from), the shading normal (interpolated OBJ vertex normals) the cosines and the BSDF's frame.
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
  if (!scene.has_shading_normals()) return {ng, ng, front};
  Vec3 ns = scene.shading_normal(triangle, scene.barycentrics(triangle, p));
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
