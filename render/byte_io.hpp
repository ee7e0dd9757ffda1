#pragma once
// Little helpers for binary forms (the scene's: scene_file, scene_image; a pool's learned lights): append plain
// values to a byte string,
// and read them back from a byte range without ever reading past its end.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "render/scene/scene.hpp"

namespace lf::bytes {

template <class T>
void put(std::string& out, const T& v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}
inline void put_rgb(std::string& out, const RGB& c) {
  put(out, c.x);
  put(out, c.y);
  put(out, c.z);
}

// Reads from a byte range, failing (not throwing) on a short read.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  bool u32(uint32_t& v) { return take(&v, 4); }
  bool f32(float& v) { return take(&v, 4); }
  bool u8(uint8_t& v) { return take(&v, 1); }
  bool u64(uint64_t& v) { return take(&v, 8); }
  bool f64(double& v) { return take(&v, 8); }
  bool vec(Vec3& v) { return f32(v.x) && f32(v.y) && f32(v.z); }
  bool str(std::string& s, uint32_t n) {
    if (bytes_.size() - at_ < n) return false;
    s.assign(bytes_.substr(at_, n));
    at_ += n;
    return true;
  }
  // Whether n items of `size` bytes can still be read (so a hostile count cannot make us allocate).
  bool room(uint64_t n, size_t size) const { return n <= (bytes_.size() - at_) / size; }
  bool done() const { return at_ == bytes_.size(); }

 private:
  bool take(void* out, size_t n) {
    if (bytes_.size() - at_ < n) return false;
    std::memcpy(out, bytes_.data() + at_, n);
    at_ += n;
    return true;
  }
  std::string_view bytes_;
  size_t at_ = 0;
};

// A material as both binary forms store it: u32 name length, name, f32 kd[3] ke[3] ks[3], f32 ns, f32 ior, u8 type,
// i32 kd_map, i32 alpha_map (-1: none; the reader of the whole form checks them against its texture count), f32 kr[3]
// tf[3], f32 metallic, f32 roughness, i32 metallic_map, i32 roughness_map, i32 normal_map, f32 normal_scale, i32 emission_map,
// f32 transmission.
inline void put_material(std::string& out, const Material& m) {
  put(out, static_cast<uint32_t>(m.name.size()));
  out += m.name;
  put_rgb(out, m.kd);
  put_rgb(out, m.ke);
  put_rgb(out, m.ks);
  put(out, m.ns);
  put(out, m.ior);
  out.push_back(static_cast<char>(m.type));
  put(out, m.kd_map);
  put(out, m.alpha_map);
  put_rgb(out, m.kr);
  put_rgb(out, m.tf);
  put(out, m.metallic);
  put(out, m.roughness);
  put(out, m.metallic_map);
  put(out, m.roughness_map);
  put(out, m.normal_map);
  put(out, m.normal_scale);
  put(out, m.emission_map);
  put(out, m.transmission);
}
// A point light as both binary forms store it: f32 position[3], intensity[3], axis[3], cos_inner, cos_outer.
inline void put_point_light(std::string& out, const PointLight& p) {
  put_rgb(out, p.position);
  put_rgb(out, p.intensity);
  put_rgb(out, p.axis);
  put(out, p.cos_inner);
  put(out, p.cos_outer);
}
inline bool read_point_light(Reader& r, PointLight& p) {
  if (!r.vec(p.position) || !r.vec(p.intensity) || !r.vec(p.axis) || !r.f32(p.cos_inner) || !r.f32(p.cos_outer))
    return false;
  // A spot's axis must be a direction, and its cones cosines.
  return !p.spot() || (std::abs(length(p.axis) - 1) < 1e-3f && p.cos_inner <= 1 && p.cos_outer <= p.cos_inner);
}
inline constexpr size_t kPointLightBytes = 44;

// Whether every texture a material names is one of `textures`.
inline bool maps_within(const Material& m, uint32_t textures) {
  const int32_t n = static_cast<int32_t>(textures);
  return m.kd_map < n && m.alpha_map < n && m.metallic_map < n && m.roughness_map < n && m.normal_map < n && m.emission_map < n;
}
inline bool read_material(Reader& r, Material& m) {
  uint32_t len = 0;
  uint8_t type = 0;
  if (!r.u32(len) || !r.str(m.name, len)) return false;
  if (!r.vec(m.kd) || !r.vec(m.ke) || !r.vec(m.ks) || !r.f32(m.ns) || !r.f32(m.ior) || !r.u8(type) ||
      type > static_cast<uint8_t>(Material::Type::metal_rough))
    return false;
  m.type = static_cast<Material::Type>(type);
  uint32_t kd_map = 0, alpha_map = 0;
  if (!r.u32(kd_map) || !r.u32(alpha_map)) return false;
  m.kd_map = static_cast<int32_t>(kd_map);
  m.alpha_map = static_cast<int32_t>(alpha_map);
  if (!r.vec(m.kr) || !r.vec(m.tf) || !r.f32(m.metallic) || !r.f32(m.roughness)) return false;
  uint32_t metallic_map = 0, roughness_map = 0, normal_map = 0, emission_map = 0;
  if (!r.u32(metallic_map) || !r.u32(roughness_map) || !r.u32(normal_map) || !r.f32(m.normal_scale) ||
      !r.u32(emission_map) || !r.f32(m.transmission))
    return false;
  m.emission_map = static_cast<int32_t>(emission_map);
  m.metallic_map = static_cast<int32_t>(metallic_map);
  m.roughness_map = static_cast<int32_t>(roughness_map);
  m.normal_map = static_cast<int32_t>(normal_map);
  return m.kd_map >= -1 && m.alpha_map >= -1 && m.metallic_map >= -1 && m.roughness_map >= -1 && m.normal_map >= -1 && m.emission_map >= -1 &&
         m.metallic >= 0 && m.metallic <= 1 && m.roughness >= 0 && m.roughness <= 1 && std::isfinite(m.normal_scale) &&
         m.transmission >= 0 && m.transmission <= 1 && std::isfinite(m.ior) && m.ior > 0;
}

}  // namespace lf::bytes
