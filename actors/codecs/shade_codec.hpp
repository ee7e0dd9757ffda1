#pragma once
// The "shade" operation's bodies (docs/PROTOCOL.md):
//   request: { n: count, p: f32[3n], nrm?: f32[3n], wo: f32[3n], m?: u32[n], k: u64[n], tri?: u32[n] }
//            (little-endian bins). nrm and m may be left out when tri is there and the receiver takes them from
//            the scene (a "lean" input): they are then surface_at(scene, tri, p, wo).ns and the triangle's material.
//   reply:   { n: count, L: f32[3n] }
#include <cstdint>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/lightop.hpp"

namespace lf {

// Points [begin, end) as a request body. With `derive_from` (the receiver holds that scene and takes what it can
// from it), nrm and m are left out where every point's value is exactly the one its triangle gives.
Value encode_shade_request(const ShadingPoints& points, size_t begin, size_t end, const Scene* derive_from = nullptr);
// With `scene`, a request without nrm or m gets them from its triangles; without, both must be there.
Result<ShadingPoints> decode_shade_request(const Value& body, size_t material_count,
                                           size_t triangle_count = SIZE_MAX, const Scene* scene = nullptr);
// Points [begin, end) of a request body, cut from its arrays as bytes (no decoding, nothing dropped): a pool
// splits a request this way. Refuses a body whose arrays do not hold n entries each.
Result<Value> slice_shade_request(const Value& body, size_t begin, size_t end);
Value encode_radiance(std::span<const RGB> radiance);
Result<std::vector<RGB>> decode_radiance(const Value& body, size_t expected_count);

}  // namespace lf
