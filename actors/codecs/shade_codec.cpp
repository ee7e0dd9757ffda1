#include "actors/codecs/shade_codec.hpp"

#include <cstring>

namespace lf {

static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 arrays travel as packed float triples");

static Bytes vec3_bytes(const std::vector<Vec3>& v, size_t begin, size_t end) {
  return floats_to_bytes(std::span<const float>(reinterpret_cast<const float*>(v.data() + begin), 3 * (end - begin)));
}

Value encode_shade_request(const ShadingPoints& pts, size_t begin, size_t end) {
  Value body = map_of("n", static_cast<int64_t>(end - begin),                 //
                       "p", vec3_bytes(pts.position, begin, end),              //
                       "nrm", vec3_bytes(pts.normal, begin, end),              //
                       "wo", vec3_bytes(pts.wo, begin, end),                   //
                       "m", u32_to_bytes(std::span<const uint32_t>(pts.material.data() + begin, end - begin)),
                       "k", u64_to_bytes(std::span<const uint64_t>(pts.key.data() + begin, end - begin)));
  if (!pts.triangle.empty())
    body.as_map()["tri"] = u32_to_bytes(std::span<const uint32_t>(pts.triangle.data() + begin, end - begin));
  return body;
}

static Status read_vec3(const Value& body, const char* key, size_t n, std::vector<Vec3>& out) {
  const Value* v = body.find(key);
  if (!v || !v->is_bytes()) return make_error(std::string("shade request has no '") + key + "' array");
  if (v->as_bytes().data.size() != n * sizeof(Vec3))
    return make_error(std::string("shade request '") + key + "' holds " + std::to_string(v->as_bytes().data.size()) +
                      " bytes, expected " + std::to_string(n * sizeof(Vec3)));
  out.resize(n);
  if (n) std::memcpy(out.data(), v->as_bytes().data.data(), n * sizeof(Vec3));
  return Ok{};
}

static Result<size_t> read_count(const Value& body) {
  const Value* n = body.find("n");
  if (!n || !n->is_int() || n->as_int() < 0) return make_error("'n' (point count) missing or negative");
  return static_cast<size_t>(n->as_int());
}

Result<ShadingPoints> decode_shade_request(const Value& body, size_t material_count, size_t triangle_count) {
  auto n = read_count(body);
  if (!n) return make_error("shade request: " + n.error().message);
  ShadingPoints pts;
  for (auto [key, field] : {std::pair{"p", &pts.position}, {"nrm", &pts.normal}, {"wo", &pts.wo}})
    if (auto st = read_vec3(body, key, *n, *field); !st) return st.error();
  const Value* m = body.find("m");
  if (!m || !m->is_bytes() || !bytes_to_u32(m->as_bytes(), pts.material) || pts.material.size() != *n)
    return make_error("shade request 'm' must hold " + std::to_string(*n) + " u32 material ids");
  const Value* k = body.find("k");
  if (!k || !k->is_bytes() || !bytes_to_u64(k->as_bytes(), pts.key) || pts.key.size() != *n)
    return make_error("shade request 'k' must hold " + std::to_string(*n) + " u64 sample keys");
  if (const Value* t = body.find("tri")) {
    if (!t->is_bytes() || !bytes_to_u32(t->as_bytes(), pts.triangle) || pts.triangle.size() != *n)
      return make_error("shade request 'tri' must hold " + std::to_string(*n) + " u32 triangle ids");
  }
  if (std::string why = pts.check(material_count, triangle_count); !why.empty()) return make_error("shade request: " + why);
  return pts;
}

Value encode_radiance(std::span<const RGB> radiance) {
  return map_of("n", static_cast<int64_t>(radiance.size()),
                "L", floats_to_bytes(std::span<const float>(reinterpret_cast<const float*>(radiance.data()),
                                                            3 * radiance.size())));
}

Result<std::vector<RGB>> decode_radiance(const Value& body, size_t expected) {
  const Value* l = body.find("L");
  if (!l || !l->is_bytes()) return make_error("shade reply has no 'L' array", ErrorCode::bad_message);
  if (l->as_bytes().data.size() != expected * sizeof(RGB))
    return make_error("shade reply holds " + std::to_string(l->as_bytes().data.size() / sizeof(RGB)) +
                          " radiance values, expected " + std::to_string(expected),
                      ErrorCode::bad_message);
  // The count must agree too: a reply that says one thing and holds another is broken, whichever is right.
  const Value* n = body.find("n");
  if (!n || !n->is_int() || n->as_int() != static_cast<int64_t>(expected))
    return make_error("shade reply says n = " + (n && n->is_int() ? std::to_string(n->as_int()) : std::string("?")) +
                          " but holds " + std::to_string(expected) + " radiance values",
                      ErrorCode::bad_message);
  std::vector<RGB> out(expected);
  if (expected) std::memcpy(out.data(), l->as_bytes().data.data(), expected * sizeof(RGB));
  return out;
}

}  // namespace lf
