#include "actors/codecs/trace_codec.hpp"

#include <cmath>
#include <cstring>

namespace lf {

static_assert(sizeof(Ray) == 8 * sizeof(float), "rays travel as 8 packed floats");
static_assert(sizeof(Hit) == 8, "a hit is a triangle id and a distance");

namespace {

Result<size_t> count_of(const Value& body, const char* what) {
  const Value* n = body.find("n");
  if (!n || !n->is_int() || n->as_int() < 0)
    return make_error(std::string(what) + ": 'n' (ray count) missing or negative", ErrorCode::bad_request);
  return static_cast<size_t>(n->as_int());
}

}  // namespace

Value encode_trace_request(std::span<const Ray> rays, bool any) {
  return map_of("n", static_cast<int64_t>(rays.size()),
                "r", floats_to_bytes(std::span<const float>(reinterpret_cast<const float*>(rays.data()), 8 * rays.size())),
                "any", any);
}

Result<TraceRequest> decode_trace_request(const Value& body, size_t max_rays) {
  auto n = count_of(body, "trace request");
  if (!n) return n.error();
  if (*n > max_rays)
    return make_error("trace request: " + std::to_string(*n) + " rays, more than the " + std::to_string(max_rays) +
                          " a request may hold",
                      ErrorCode::bad_request);
  const Value* r = body.find("r");
  if (!r || !r->is_bytes() || r->as_bytes().data.size() != *n * sizeof(Ray))
    return make_error("trace request 'r' must hold " + std::to_string(*n) + " rays of 8 floats", ErrorCode::bad_request);
  const Value* any = body.find("any");
  if (any && !any->is_bool()) return make_error("trace request 'any' must be true or false", ErrorCode::bad_request);
  TraceRequest out;
  out.any = any && any->as_bool();
  out.rays.resize(*n);
  if (*n) std::memcpy(out.rays.data(), r->as_bytes().data.data(), *n * sizeof(Ray));
  for (size_t i = 0; i < out.rays.size(); ++i) {
    const Ray& ray = out.rays[i];
    const float values[6] = {ray.origin.x, ray.origin.y, ray.origin.z, ray.direction.x, ray.direction.y, ray.direction.z};
    for (float v : values)
      if (!std::isfinite(v))
        return make_error("trace request: ray " + std::to_string(i) + " has a coordinate that is not finite",
                          ErrorCode::bad_request);
    if (std::isnan(ray.tnear) || std::isnan(ray.tfar))
      return make_error("trace request: ray " + std::to_string(i) + " has a NaN extent", ErrorCode::bad_request);
  }
  return out;
}

Value encode_hits(std::span<const Hit> hits) {
  std::vector<uint32_t> tri(hits.size());
  std::vector<float> t(hits.size());
  for (size_t i = 0; i < hits.size(); ++i) {
    tri[i] = hits[i].triangle;
    t[i] = hits[i].t;
  }
  return map_of("n", static_cast<int64_t>(hits.size()), "tri", u32_to_bytes(tri), "t", floats_to_bytes(t));
}

Result<std::vector<Hit>> decode_hits(const Value& body, size_t expected, size_t triangle_count) {
  auto n = count_of(body, "trace reply");
  if (!n) return make_error(n.error().message, ErrorCode::bad_message);
  std::vector<uint32_t> tri;
  std::vector<float> t;
  const Value* tv = body.find("tri");
  const Value* dv = body.find("t");
  if (*n != expected || !tv || !tv->is_bytes() || !bytes_to_u32(tv->as_bytes(), tri) || tri.size() != expected || !dv ||
      !dv->is_bytes() || !bytes_to_floats(dv->as_bytes(), t) || t.size() != expected)
    return make_error("trace reply must hold 'tri' and 't' for " + std::to_string(expected) + " rays",
                      ErrorCode::bad_message);
  std::vector<Hit> hits(expected);
  for (size_t i = 0; i < expected; ++i) {
    if (tri[i] != Hit::kNone && tri[i] >= triangle_count)
      return make_error("trace reply names triangle " + std::to_string(tri[i]) + ", which the scene does not have",
                        ErrorCode::bad_message);
    hits[i] = Hit{tri[i], t[i]};
  }
  return hits;
}

Value encode_occlusion(std::span<const uint8_t> occluded) {
  return map_of("n", static_cast<int64_t>(occluded.size()),
                "hit", Bytes{std::string(reinterpret_cast<const char*>(occluded.data()), occluded.size())});
}

Result<std::vector<uint8_t>> decode_occlusion(const Value& body, size_t expected) {
  auto n = count_of(body, "trace reply");
  if (!n) return make_error(n.error().message, ErrorCode::bad_message);
  const Value* h = body.find("hit");
  if (*n != expected || !h || !h->is_bytes() || h->as_bytes().data.size() != expected)
    return make_error("trace reply must hold 'hit' for " + std::to_string(expected) + " rays", ErrorCode::bad_message);
  const std::string& bytes = h->as_bytes().data;
  return std::vector<uint8_t>(bytes.begin(), bytes.end());
}

}  // namespace lf
