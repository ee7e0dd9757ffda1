#pragma once
// Lean shade requests: what a receiver that holds the scene (a built-in LightOp; a "lean" input) rebuilds bit for
// bit, so that its sender leaves it out. A normal is its triangle's shading normal at the point (surface_at), a
// material its triangle's, a position point_on_ray(origin, wo, t), a key tile_sample_key(sampler, image width,
// tile, spp, s). The sender asks fields_to_send and lays the request out with the shade codec; the receiver reads
// it with read_shade_request. The codec itself only lays out bytes.
#include <cstdint>

#include "actors/codecs/shade_codec.hpp"

namespace lf {

// The fields points [begin, end) must carry for a receiver holding `scene` (the same scene as the sender's):
// normals and materials unless every point's is exactly its triangle's.
PointFields fields_to_send(const ShadingPoints& points, size_t begin, size_t end, const Scene& scene);
// As above for a renderer's tile, and positions as distances along its camera rays, keys as its sample indices,
// where every point's are exactly those (trace_tile's points are, by construction: work.rebuildable).
PointFields fields_to_send(const TileWork& work, size_t begin, size_t end, const Scene& scene, SamplerKind sampler,
                           int64_t image_width);

// How a lean receiver rebuilds sample keys from a tile's sample indices: the image's width and sampler.
struct PixelKeys {
  int64_t image_width = 0;
  SamplerKind sampler = SamplerKind::independent;
};
// A request's points, whole. With `scene`, normals and materials left out are taken from the points' triangles;
// without, both must be there. With `keys`, keys may come as a tile's sample indices. Checks every index against
// the scene's materials and triangles.
Result<ShadingPoints> read_shade_request(const Value& body, size_t material_count, size_t triangle_count = SIZE_MAX,
                                         const Scene* scene = nullptr, const PixelKeys* keys = nullptr);

}  // namespace lf
