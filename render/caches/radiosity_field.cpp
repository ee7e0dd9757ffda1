#include "render/caches/radiosity_field.hpp"

#include <cstring>

namespace lf {

namespace {
void put(std::string& out, const void* data, size_t n) { out.append(static_cast<const char*>(data), n); }
}  // namespace

std::string RadiosityField::to_bytes() const {
  static_assert(sizeof(Vec3) == 12, "Vec3 is three packed floats");
  std::string out = "LFRF";
  const uint32_t head[3] = {1, static_cast<uint32_t>(position.size()), static_cast<uint32_t>(triangles.size())};
  put(out, head, sizeof head);
  put(out, position.data(), position.size() * sizeof(Vec3));
  put(out, radiosity.data(), radiosity.size() * sizeof(Vec3));
  put(out, emission.data(), emission.size() * sizeof(Vec3));
  put(out, triangles.data(), triangles.size() * sizeof(triangles[0]));
  return out;
}

Result<RadiosityField> RadiosityField::from_bytes(const std::string& bytes) {
  uint32_t head[3];
  if (bytes.size() < 4 + sizeof head || bytes.compare(0, 4, "LFRF") != 0)
    return make_error("radiosity solution: not a solution (bad header)");
  std::memcpy(head, bytes.data() + 4, sizeof head);
  if (head[0] != 1) return make_error("radiosity solution: version " + std::to_string(head[0]) + ", expected 1");
  const size_t v = head[1], t = head[2];
  const size_t need = 4 + sizeof head + 3 * v * sizeof(Vec3) + t * 3 * sizeof(uint32_t);
  if (bytes.size() != need)
    return make_error("radiosity solution: " + std::to_string(bytes.size()) + " bytes, expected " + std::to_string(need));
  RadiosityField f;
  const char* at = bytes.data() + 4 + sizeof head;
  auto take = [&](auto& vec, size_t n) {
    vec.resize(n);
    std::memcpy(vec.data(), at, n * sizeof(vec[0]));
    at += n * sizeof(vec[0]);
  };
  take(f.position, v);
  take(f.radiosity, v);
  take(f.emission, v);
  take(f.triangles, t);
  for (const auto& tri : f.triangles)
    for (uint32_t i : tri)
      if (i >= v) return make_error("radiosity solution: a triangle names vertex " + std::to_string(i) + " of " + std::to_string(v));
  return f;
}

}  // namespace lf
