#pragma once
// The "shade" operation's bodies (docs/PROTOCOL.md):
//   request: { n: count, p: f32[3n], nrm?: f32[3n], wo: f32[3n], m?: u32[n], k: u64[n], tri?: u32[n] }
//            (little-endian bins). nrm and m may be left out when tri is there and the receiver takes them from
//            the scene (a "lean" input): they are then the triangle's shading normal at p and its material.
//            A renderer's request to a lean input may also carry o: f32[3] and t: f32[n] instead of p (p = o - wo t)
//            and tile: [x0, y0, x1, y1, spp, first?] and s: u32[n] instead of k (the tile's s-th sample's key; first:
//            a time-limited frame's pass, the index its pixels' samples start from, 0 when absent).
//            Such a request may also say fold: true, and then holds whole pixels (no pixel's points are split
//            between two requests): its reply holds one value per run of consecutive points in one pixel, their
//            radiance summed (fold_by_pixel), instead of one per point.
//            A job's frames in flight: view: the number of the frame whose view the points are shaded for (as
//            PHASE frame gave it), when a receiver may hold two; absent: its latest view.
//   reply:   { n: count, L: f32[3n] }
#include <cstdint>
#include <optional>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/lightops/lightop.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {

// Which of a point's fields a request carries. The ones left out the receiver rebuilds from its scene and the
// tile; which those may be is decided in actors/runtime/lean_points.hpp, not here: this codec only lays out bytes.
struct PointFields {
  bool normal = true, material = true;
  bool position = true;  // else distances along the camera rays from one origin (o, t)
  bool key = true;       // else the tile's sample indices (tile, s)
};

// Points [begin, end) as a request body, with their normals and materials where `fields` says (a bare point set
// has no camera rays or tile: its positions and keys always travel).
Value encode_shade_request(const ShadingPoints& points, size_t begin, size_t end, PointFields fields = {});
// A renderer's points [begin, end) of a tile, each field as `fields` says. With `fold` (points [begin, end) are
// whole pixels) and keys as sample indices, the body says fold: true and the reply is asked for folded by pixel.
Value encode_tile_request(const TileWork& work, size_t begin, size_t end, PointFields fields, bool fold);

// A request's arrays as they came, each checked to hold n entries: what was left out is empty (or unset).
struct ShadeRequest {
  size_t n = 0;
  ShadingPoints points;          // wo always; position, normal, material, key and triangle where sent
  std::optional<Vec3> origin;    // positions as distances along camera rays from here (with `distance`)
  std::vector<float> distance;
  std::optional<TileRect> tile;  // keys as the sample indices (`samples`) of this tile with `spp` samples a pixel
  int spp = 0;
  std::vector<uint32_t> samples;
};
Result<ShadeRequest> decode_shade_request(const Value& body);

// What a request asking for a folded reply (fold: true) is folded by: each point's sample index in its tile and
// the tile's samples per pixel. std::nullopt for a request that wants one value a point.
struct PixelFold {
  std::vector<uint32_t> samples;
  int spp = 1;
  size_t runs() const { return pixel_runs(samples, spp); }
};
Result<std::optional<PixelFold>> decode_pixel_fold(const Value& body);
// The frame whose view a request's points are shaded for (`view`), or std::nullopt: the receiver's latest.
void set_shade_view(Value& body, int frame);
Result<std::optional<int>> decode_shade_view(const Value& body);
// Points [begin, end) of a request body, cut from its arrays as bytes (no decoding, nothing dropped): a pool
// splits a request this way. Refuses a body whose arrays do not hold n entries each.
Result<Value> slice_shade_request(const Value& body, size_t begin, size_t end);
Value encode_radiance(std::span<const RGB> radiance);
Result<std::vector<RGB>> decode_radiance(const Value& body, size_t expected_count);

}  // namespace lf
