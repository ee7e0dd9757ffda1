#pragma once
// The "trace" operation's bodies (docs/PROTOCOL.md), between an actor that traces through a partitioned scene and a
// geometry actor holding one part (render/tracing/partition.hpp):
//   request: { n: count, r: f32[8n] (per ray: origin xyz, direction xyz, tnear, tfar), any: bool }
//   reply:   any = false: { n, tri: u32[n] (0xffffffff: no hit in this part), t: f32[n] }
//            any = true:  { n, hit: u8[n] (1: something of this part lies on the ray) }
// The answer is the part's own: the asker visits the parts along each ray and settles ties (render/tracing/tied_hits.hpp).
#include <cstdint>
#include <span>
#include <vector>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

struct TraceRequest {
  std::vector<Ray> rays;
  bool any = false;  // occlusion: is anything on the ray, rather than the nearest hit
};

Value encode_trace_request(std::span<const Ray> rays, bool any);
// Refuses what a BVH should not see: counts that disagree, and origins or directions that are not finite.
Result<TraceRequest> decode_trace_request(const Value& body, size_t max_rays);
Value encode_hits(std::span<const Hit> hits);
Result<std::vector<Hit>> decode_hits(const Value& body, size_t expected, size_t triangle_count);
Value encode_occlusion(std::span<const uint8_t> occluded);
Result<std::vector<uint8_t>> decode_occlusion(const Value& body, size_t expected);

}  // namespace lf
