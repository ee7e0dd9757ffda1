#pragma once
// The "shade" operation's bodies (docs/PROTOCOL.md):
//   request: { n: count, p: f32[3n], nrm?: f32[3n], wo: f32[3n], m?: u32[n], k: u64[n], tri?: u32[n] }
//            (little-endian bins). nrm and m may be left out when tri is there and the receiver takes them from
//            the scene (a "lean" input): they are then surface_at(scene, tri, p, wo).ns and the triangle's material.
//            A renderer's request to a lean input may also carry o: f32[3] and t: f32[n] instead of p (p = o - wo t)
//            and tile: [x0, y0, x1, y1, spp] and s: u32[n] instead of k (the tile's s-th sample's key).
//            Such a request may also say fold: true, and then holds whole pixels (no pixel's points are split
//            between two requests): its reply holds one value per run of consecutive points in one pixel, their
//            radiance summed (fold_by_pixel), instead of one per point.
//   reply:   { n: count, L: f32[3n] }
#include <cstdint>
#include <optional>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/lightops/lightop.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {

// Points [begin, end) as a request body. With `derive_from` (the receiver holds that scene and takes what it can
// from it), nrm and m are left out where every point's value is exactly the one its triangle gives.
Value encode_shade_request(const ShadingPoints& points, size_t begin, size_t end, const Scene* derive_from = nullptr);
// A renderer's points [begin, end) of a tile to a lean input: as encode_shade_request with the scene, and where
// they are exactly that, positions as distances along the camera rays (o, t) and sample keys as the tile's sample
// indices (tile, s), which the receiver turns back into the same bits. 24 bytes a point instead of 52. With
// `fold` (points [begin, end) are whole pixels), the reply is asked for folded by pixel where the keys travel as
// sample indices: the body then says fold: true.
Value encode_camera_request(const TileWork& work, size_t begin, size_t end, const Scene& scene, SamplerKind sampler,
                            int64_t image_width, bool fold = false);
// How a lean input rebuilds sample keys from a tile's sample indices: the image's width and sampler.
struct PixelKeys {
  int64_t image_width = 0;
  SamplerKind sampler = SamplerKind::independent;
};
// With `scene`, a request without nrm or m gets them from its triangles; without, both must be there. With
// `keys`, one may carry tile and s instead of k; o and t instead of p need nothing more.
Result<ShadingPoints> decode_shade_request(const Value& body, size_t material_count,
                                           size_t triangle_count = SIZE_MAX, const Scene* scene = nullptr,
                                           const PixelKeys* keys = nullptr);
// What a request asking for a folded reply (fold: true) is folded by: each point's sample index in its tile and
// the tile's samples per pixel. std::nullopt for a request that wants one value a point.
struct PixelFold {
  std::vector<uint32_t> samples;
  int spp = 1;
  size_t runs() const { return pixel_runs(samples, spp); }
};
Result<std::optional<PixelFold>> decode_pixel_fold(const Value& body);
// Points [begin, end) of a request body, cut from its arrays as bytes (no decoding, nothing dropped): a pool
// splits a request this way. Refuses a body whose arrays do not hold n entries each.
Result<Value> slice_shade_request(const Value& body, size_t begin, size_t end);
Value encode_radiance(std::span<const RGB> radiance);
Result<std::vector<RGB>> decode_radiance(const Value& body, size_t expected_count);

}  // namespace lf
