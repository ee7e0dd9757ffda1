#include "actors/runtime/lean_points.hpp"

#include <cstring>

#include "render/scene/surface.hpp"

namespace lf {
namespace {

// Bitwise, so that -0 and +0 are not taken for each other.
bool normals_derivable(const ShadingPoints& pts, size_t begin, size_t end, const Scene& scene) {
  for (size_t i = begin; i < end; ++i) {
    const Vec3 ns = surface_at(scene, pts.triangle[i], pts.position[i], pts.wo[i]).ns;
    if (std::memcmp(&ns, &pts.normal[i], sizeof ns) != 0) return false;
  }
  return true;
}

bool materials_derivable(const ShadingPoints& pts, size_t begin, size_t end, const Scene& scene) {
  for (size_t i = begin; i < end; ++i)
    if (pts.material[i] != scene.material_of(pts.triangle[i])) return false;
  return true;
}

Status rebuild_keys(const ShadeRequest& req, const PixelKeys& keys, ShadingPoints& pts) {
  const TileRect& rect = *req.tile;
  if (rect.x1 > keys.image_width)
    return make_error("shade request has neither 'k' nor a tile [x0, y0, x1, y1, spp] inside an image " +
                      std::to_string(keys.image_width) + " pixels wide");
  // The tile's samples, in 64 bits (a hostile tile's pixels times its spp may not fit; s is 32 bits anyway).
  const uint64_t pixels = static_cast<uint64_t>(rect.width()) * static_cast<uint64_t>(rect.height());
  const uint64_t count = pixels > UINT32_MAX ? UINT64_MAX : pixels * static_cast<uint64_t>(req.spp);
  pts.key.resize(req.n);
  for (size_t i = 0; i < req.n; ++i) {
    if (req.samples[i] >= count)
      return make_error("shade request: point " + std::to_string(i) + " is sample " + std::to_string(req.samples[i]) +
                        " of a tile of " + std::to_string(count));
    pts.key[i] = tile_sample_key(keys.sampler, keys.image_width, rect, req.spp, req.samples[i]);
  }
  return Ok{};
}

Status rebuild_from_triangles(size_t n, size_t triangle_count, const Scene& scene, ShadingPoints& pts) {
  const size_t triangles = std::min(triangle_count, scene.triangle_count());
  for (size_t i = 0; i < n; ++i)
    if (pts.triangle[i] >= triangles)
      return make_error("shade request: point " + std::to_string(i) + " is on triangle " +
                        std::to_string(pts.triangle[i]) + " but the scene has " + std::to_string(triangles));
  if (pts.material.size() != n) {
    pts.material.resize(n);
    for (size_t i = 0; i < n; ++i) pts.material[i] = scene.material_of(pts.triangle[i]);
  }
  if (pts.normal.size() != n) {
    pts.normal.resize(n);
    for (size_t i = 0; i < n; ++i) pts.normal[i] = surface_at(scene, pts.triangle[i], pts.position[i], pts.wo[i]).ns;
  }
  return Ok{};
}

}  // namespace

PointFields fields_to_send(const ShadingPoints& pts, size_t begin, size_t end, const Scene& scene) {
  PointFields fields;
  if (pts.triangle.empty()) return fields;  // nothing to take a normal or material from
  fields.normal = !normals_derivable(pts, begin, end, scene);
  fields.material = !materials_derivable(pts, begin, end, scene);
  return fields;
}

PointFields fields_to_send(const TileWork& work, size_t begin, size_t end, const Scene& scene, SamplerKind sampler,
                           int64_t image_width) {
  const ShadingPoints& pts = work.points;
  // trace_tile's points are rebuildable by construction; others are checked point by point.
  const bool trusted = work.rebuildable && work.sampler == sampler && work.image_width == image_width;
  bool along_rays = work.distance.size() == pts.size();
  for (size_t i = begin; !trusted && along_rays && i < end; ++i) {
    const Vec3 p = point_on_ray(work.eye, pts.wo[i], work.distance[i]);
    along_rays = std::memcmp(&p, &pts.position[i], sizeof p) == 0;
  }
  bool tile_keys = work.sample_of_point.size() == pts.size() && work.rect.width() > 0 && work.spp > 0;
  for (size_t i = begin; !trusted && tile_keys && i < end; ++i)
    tile_keys = tile_sample_key(sampler, image_width, work.rect, work.spp, work.sample_of_point[i]) == pts.key[i];
  PointFields fields;
  fields.position = !along_rays;
  fields.key = !tile_keys;
  if (pts.triangle.empty()) return fields;
  const bool known = trusted && along_rays && tile_keys;
  fields.normal = !known && !normals_derivable(pts, begin, end, scene);
  fields.material = !known && !materials_derivable(pts, begin, end, scene);
  return fields;
}

Result<ShadingPoints> read_shade_request(const Value& body, size_t material_count, size_t triangle_count,
                                         const Scene* scene, const PixelKeys* keys) {
  auto req = decode_shade_request(body);
  if (!req) return req.error();
  const size_t n = req->n;
  ShadingPoints& pts = req->points;
  if (req->origin) {
    pts.position.resize(n);
    for (size_t i = 0; i < n; ++i) pts.position[i] = point_on_ray(*req->origin, pts.wo[i], req->distance[i]);
  }
  if (req->tile) {
    if (!keys) return make_error("shade request 'k' must hold " + std::to_string(n) + " u64 sample keys");
    if (auto st = rebuild_keys(*req, *keys, pts); !st) return st.error();
  }
  // Without the scene (or the triangles), there is nothing to take a left-out normal or material from.
  const bool derive = scene && pts.triangle.size() == n;
  if (!derive && pts.normal.size() != n) return make_error("shade request has no 'nrm' array");
  if (!derive && pts.material.size() != n)
    return make_error("shade request 'm' must hold " + std::to_string(n) + " u32 material ids");
  if (derive && (pts.normal.size() != n || pts.material.size() != n))
    if (auto st = rebuild_from_triangles(n, triangle_count, *scene, pts); !st) return st.error();
  if (std::string why = pts.check(material_count, triangle_count); !why.empty()) return make_error("shade request: " + why);
  return std::move(pts);
}

}  // namespace lf
