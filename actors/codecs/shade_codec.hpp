#pragma once
// The "shade" operation's bodies (docs/PROTOCOL.md):
//   request: { n: count, p: f32[3n], nrm: f32[3n], wo: f32[3n], m: u32[n], k: u64[n], tri?: u32[n] }
//            (little-endian bins; tri optional)
//   reply:   { n: count, L: f32[3n] }
#include <cstdint>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/lightop.hpp"

namespace lf {

Value encode_shade_request(const ShadingPoints& points, size_t begin, size_t end);
Result<ShadingPoints> decode_shade_request(const Value& body, size_t material_count,
                                           size_t triangle_count = SIZE_MAX);
Value encode_radiance(std::span<const RGB> radiance);
Result<std::vector<RGB>> decode_radiance(const Value& body, size_t expected_count);

}  // namespace lf
