#include "actors/codecs/shade_codec.hpp"

#include <cstdint>
#include <cstring>
#include <map>


namespace lf {

static_assert(sizeof(Vec3) == 3 * sizeof(float), "Vec3 arrays travel as packed float triples");

static Bytes vec3_bytes(const std::vector<Vec3>& v, size_t begin, size_t end) {
  return floats_to_bytes(std::span<const float>(reinterpret_cast<const float*>(v.data() + begin), 3 * (end - begin)));
}

// The arrays every request carries for points [begin, end), and nrm, m where `fields` says.
static Value encode_points(const ShadingPoints& pts, size_t begin, size_t end, PointFields fields) {
  Value body = map_of("n", static_cast<int64_t>(end - begin), "wo", vec3_bytes(pts.wo, begin, end));
  Value::Map& map = body.as_map();
  if (fields.normal) map["nrm"] = vec3_bytes(pts.normal, begin, end);
  if (fields.material) map["m"] = u32_to_bytes(std::span<const uint32_t>(pts.material.data() + begin, end - begin));
  if (!pts.triangle.empty())
    map["tri"] = u32_to_bytes(std::span<const uint32_t>(pts.triangle.data() + begin, end - begin));
  return body;
}

Value encode_shade_request(const ShadingPoints& pts, size_t begin, size_t end, PointFields fields) {
  Value body = encode_points(pts, begin, end, fields);
  Value::Map& map = body.as_map();
  map["p"] = vec3_bytes(pts.position, begin, end);
  map["k"] = u64_to_bytes(std::span<const uint64_t>(pts.key.data() + begin, end - begin));
  return body;
}

Value encode_tile_request(const TileWork& work, size_t begin, size_t end, PointFields fields, bool fold) {
  const ShadingPoints& pts = work.points;
  Value body = encode_points(pts, begin, end, fields);
  Value::Map& map = body.as_map();
  if (fields.position) {
    map["p"] = vec3_bytes(pts.position, begin, end);
  } else {
    map["o"] = floats_to_bytes(std::span<const float>(&work.eye.x, 3));
    map["t"] = floats_to_bytes(std::span<const float>(work.distance.data() + begin, end - begin));
  }
  if (fields.key) {
    map["k"] = u64_to_bytes(std::span<const uint64_t>(pts.key.data() + begin, end - begin));
  } else {
    Value::Array tile{int64_t{work.rect.x0}, int64_t{work.rect.y0}, int64_t{work.rect.x1}, int64_t{work.rect.y1},
                      int64_t{work.spp}};
    if (work.rect.first_sample > 0) tile.push_back(static_cast<int64_t>(work.rect.first_sample));
    map["tile"] = std::move(tile);
    map["s"] = u32_to_bytes(std::span<const uint32_t>(work.sample_of_point.data() + begin, end - begin));
    if (fold) map["fold"] = true;
  }
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

// The tile [x0, y0, x1, y1, spp, first?] a request's sample indices refer to; spp within [1, kMaxTileSide], first
// (a time-limited frame's pass: the pixels' first sample index, 0 when absent) within [0, 2^31).
constexpr int64_t kMaxTileSide = int64_t{1} << 24;  // beyond any image's pixels per side or samples per pixel

static bool read_tile(const Value& body, int64_t (&v)[6]) {
  const Value* tile = body.find("tile");
  const size_t size = tile && tile->is_array() ? tile->as_array().size() : 0;
  bool ok = size == 5 || size == 6;
  v[5] = 0;
  for (size_t i = 0; ok && i < size; ++i) {
    ok = tile->as_array()[i].is_int();
    if (ok) v[i] = tile->as_array()[i].as_int();
  }
  return ok && v[4] >= 1 && v[4] <= kMaxTileSide && v[5] >= 0 && v[5] <= INT32_MAX;
}

Result<std::optional<PixelFold>> decode_pixel_fold(const Value& body) {
  const Value* fold = body.find("fold");
  if (!fold || (fold->is_bool() && !fold->as_bool())) return std::optional<PixelFold>();
  if (!fold->is_bool()) return make_error("shade request 'fold' must be true or false");
  auto n = read_count(body);
  if (!n) return make_error("shade request: " + n.error().message);
  int64_t v[6] = {};
  if (!read_tile(body, v)) return make_error("shade request: 'fold' needs a tile [x0, y0, x1, y1, spp]");
  PixelFold out;
  out.spp = static_cast<int>(v[4]);
  const Value* s = body.find("s");
  if (!s || !s->is_bytes() || !bytes_to_u32(s->as_bytes(), out.samples) || out.samples.size() != *n)
    return make_error("shade request: 'fold' needs 's' with " + std::to_string(*n) + " u32 sample indices");
  return std::optional<PixelFold>(std::move(out));
}

Result<ShadeRequest> decode_shade_request(const Value& body) {
  auto n = read_count(body);
  if (!n) return make_error("shade request: " + n.error().message);
  ShadeRequest req;
  req.n = *n;
  ShadingPoints& pts = req.points;
  if (auto st = read_vec3(body, "wo", *n, pts.wo); !st) return st.error();
  if (body.find("p") || !body.find("o")) {
    if (auto st = read_vec3(body, "p", *n, pts.position); !st) return st.error();
  } else {
    const Value* o = body.find("o");
    const Value* t = body.find("t");
    std::vector<float> origin;
    if (!o->is_bytes() || !bytes_to_floats(o->as_bytes(), origin) || origin.size() != 3)
      return make_error("shade request has neither 'p' nor a ray origin 'o' of 3 floats");
    if (!t || !t->is_bytes() || !bytes_to_floats(t->as_bytes(), req.distance) || req.distance.size() != *n)
      return make_error("shade request 't' must hold " + std::to_string(*n) + " f32 distances");
    req.origin = Vec3{origin[0], origin[1], origin[2]};
  }
  if (body.find("nrm"))
    if (auto st = read_vec3(body, "nrm", *n, pts.normal); !st) return st.error();
  if (const Value* m = body.find("m"))
    if (!m->is_bytes() || !bytes_to_u32(m->as_bytes(), pts.material) || pts.material.size() != *n)
      return make_error("shade request 'm' must hold " + std::to_string(*n) + " u32 material ids");
  const Value* k = body.find("k");
  if (const Value* s = body.find("s"); !k && s) {
    int64_t v[6] = {};
    if (!read_tile(body, v) || v[0] < 0 || v[1] < 0 || v[0] >= v[2] || v[1] >= v[3] || v[2] > kMaxTileSide ||
        v[3] > kMaxTileSide)
      return make_error("shade request has neither 'k' nor a tile [x0, y0, x1, y1, spp]");
    if (!s->is_bytes() || !bytes_to_u32(s->as_bytes(), req.samples) || req.samples.size() != *n)
      return make_error("shade request 's' must hold " + std::to_string(*n) + " u32 sample indices");
    req.tile = TileRect{static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[2]), static_cast<int>(v[3]),
                        static_cast<uint32_t>(v[5])};
    req.spp = static_cast<int>(v[4]);
  } else if (!k || !k->is_bytes() || !bytes_to_u64(k->as_bytes(), pts.key) || pts.key.size() != *n) {
    return make_error("shade request 'k' must hold " + std::to_string(*n) + " u64 sample keys");
  }
  if (const Value* tri = body.find("tri"))
    if (!tri->is_bytes() || !bytes_to_u32(tri->as_bytes(), pts.triangle) || pts.triangle.size() != *n)
      return make_error("shade request 'tri' must hold " + std::to_string(*n) + " u32 triangle ids");
  return req;
}

void set_shade_view(Value& body, int frame) { body.as_map()["view"] = static_cast<int64_t>(frame); }

Result<std::optional<int>> decode_shade_view(const Value& body) {
  const Value* view = body.find("view");
  if (!view) return std::optional<int>();
  if (!view->is_int() || view->as_int() < INT32_MIN || view->as_int() > INT32_MAX)
    return make_error("shade request 'view' must be a frame number");
  return std::optional<int>(static_cast<int>(view->as_int()));
}

Result<Value> slice_shade_request(const Value& body, size_t begin, size_t end) {
  auto n = read_count(body);
  if (!n) return make_error("shade request: " + n.error().message);
  if (begin > end || end > *n) return make_error("shade request: slice out of range");
  Value::Map out{{"n", static_cast<int64_t>(end - begin)}};
  static const std::map<std::string, size_t, std::less<>> kWidth{{"p", 12}, {"nrm", 12}, {"wo", 12}, {"m", 4},
                                                                   {"k", 8},  {"tri", 4},  {"t", 4},   {"s", 4}};
  for (const auto& [key, value] : body.as_map()) {
    if (key == "n") continue;
    const auto width = kWidth.find(key);
    if (width == kWidth.end()) {
      out[key] = value;  // not per point (o, tile), or not the protocol's: the same for every piece
      continue;
    }
    if (!value.is_bytes() || value.as_bytes().data.size() != width->second * *n)
      return make_error("shade request '" + key + "' must hold " + std::to_string(*n) + " entries of " +
                        std::to_string(width->second) + " bytes");
    out[key] = Bytes{value.as_bytes().data.substr(begin * width->second, (end - begin) * width->second)};
  }
  return Value(std::move(out));
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
