#include "render/scene/scene_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zlib.h>

#include <cstring>

#include "render/byte_io.hpp"

namespace lf {

namespace {

constexpr std::string_view kMagic = "LFSCENE11";  // 4: metallic and roughness; 5: the environment; 6: their maps;
                                                  // 7: normal maps; 8: emission maps; 9: spot lights;
                                                  // 10: transmission; 11: corner tangents
using bytes::put;
using bytes::put_rgb;
using bytes::Reader;
using bytes::maps_within;
using bytes::put_material;
using bytes::read_material;

}  // namespace

std::string scene_to_bytes(const Scene& scene) {
  std::string out(kMagic);
  put<uint32_t>(out, static_cast<uint32_t>(scene.textures().size()));
  for (const Texture& t : scene.textures()) {
    put<uint32_t>(out, static_cast<uint32_t>(t.path.size()));
    out += t.path;
    put<uint32_t>(out, t.width);
    put<uint32_t>(out, t.height);
    put<uint32_t>(out, t.channels);
    out.push_back(t.linear ? 1 : 0);
    uLongf size = compressBound(t.texels.size());
    std::string deflated(size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(deflated.data()), &size, t.texels.data(), t.texels.size(), 6) != Z_OK)
      throw std::runtime_error("zlib cannot deflate the texture '" + t.path + "'");
    put<uint32_t>(out, static_cast<uint32_t>(size));
    out.append(deflated.data(), size);
  }
  put<uint32_t>(out, static_cast<uint32_t>(scene.materials().size()));
  for (const Material& m : scene.materials()) put_material(out, m);
  const auto n = static_cast<uint32_t>(scene.triangle_count());
  put<uint32_t>(out, n);
  for (uint32_t t = 0; t < n; ++t)
    for (int c = 0; c < 3; ++c) {
      const Vec3 v = scene.vertex(t, c);
      put<float>(out, v.x);
      put<float>(out, v.y);
      put<float>(out, v.z);
    }
  for (uint32_t t = 0; t < n; ++t) put<uint32_t>(out, scene.material_of(t));
  out.push_back(scene.has_shading_normals() ? 1 : 0);
  if (scene.has_shading_normals())
    for (uint32_t t = 0; t < n; ++t)
      for (int c = 0; c < 3; ++c) put_rgb(out, scene.corner_normal(t, c));
  out.push_back(scene.has_uvs() ? 1 : 0);
  if (scene.has_uvs())
    for (uint32_t t = 0; t < n; ++t)
      for (int c = 0; c < 3; ++c) {
        put<float>(out, scene.corner_uv(t, c).u);
        put<float>(out, scene.corner_uv(t, c).v);
      }
  out.push_back(scene.has_tangents() ? 1 : 0);
  if (scene.has_tangents())
    for (uint32_t t = 0; t < n; ++t)
      for (int c = 0; c < 3; ++c) {
        put_rgb(out, scene.corner_tangent(t, c).direction);
        put<float>(out, scene.corner_tangent(t, c).sign);
      }
  put<uint32_t>(out, static_cast<uint32_t>(scene.point_lights().size()));
  for (const PointLight& p : scene.point_lights()) bytes::put_point_light(out, p);
  std::string environment;
  if (scene.environment()) scene.environment()->write(environment);
  put<uint32_t>(out, static_cast<uint32_t>(environment.size()));
  out += environment;
  return out;
}

Result<Scene> scene_from_bytes(std::string_view bytes, const std::string& what) {
  if (bytes.substr(0, kMagic.size()) != kMagic) return make_error(what + ": not a lightfarm scene (no " + std::string(kMagic) + ")");
  Reader r(bytes.substr(kMagic.size()));
  auto bad = [&] { return make_error(what + ": the scene's bytes are truncated or inconsistent"); };
  Scene s;
  uint32_t textures = 0;
  if (!r.u32(textures) || !r.room(textures, 20)) return bad();
  for (uint32_t i = 0; i < textures; ++i) {
    Texture t;
    uint32_t length = 0, deflated = 0;
    uint8_t linear = 0;
    std::string packed;
    if (!r.u32(length) || !r.str(t.path, length) || !r.u32(t.width) || !r.u32(t.height) || !r.u32(t.channels) ||
        !r.u8(linear) || linear > 1 || !r.u32(deflated) || !r.str(packed, deflated))
      return bad();
    t.linear = linear != 0;
    // At most 64k x 64k texels (with their mip levels) of 1 or 3 channels, and no more than deflate can make of the bytes there (1032:1).
    const uint64_t size = Texture::pyramid_bytes(t.width, t.height, t.channels);
    if (t.width == 0 || t.height == 0 || t.width > 65536 || t.height > 65536 || (t.channels != 1 && t.channels != 3) ||
        size > uint64_t{deflated} * 1032)
      return bad();
    t.owned.resize(size);
    uLongf got = size;
    if (uncompress(t.owned.data(), &got, reinterpret_cast<const Bytef*>(packed.data()), deflated) != Z_OK || got != size)
      return bad();
    s.add_texture(std::move(t));
  }
  uint32_t materials = 0;
  if (!r.u32(materials) || !r.room(materials, 50)) return bad();
  for (uint32_t i = 0; i < materials; ++i) {
    Material m;
    if (!read_material(r, m) || !maps_within(m, textures))
      return bad();
    s.add_material(std::move(m));
  }
  uint32_t n = 0;
  if (!r.u32(n) || !r.room(n, 40)) return bad();
  std::vector<Vec3> corners(3 * static_cast<size_t>(n));
  for (auto& v : corners)
    if (!r.vec(v)) return bad();
  for (uint32_t t = 0; t < n; ++t) {
    uint32_t m = 0;
    if (!r.u32(m) || m >= materials) return bad();
    s.add_triangle(corners[3 * t], corners[3 * t + 1], corners[3 * t + 2], m);
  }
  uint8_t present = 0;
  std::vector<Vec3> normals;
  std::vector<Vec2> uvs;
  if (!r.u8(present) || present > 1 || (present && !r.room(9 * uint64_t{n}, 4))) return bad();
  normals.resize(present ? 3 * size_t{n} : 0);
  for (auto& v : normals)
    if (!r.vec(v)) return bad();
  if (!r.u8(present) || present > 1 || (present && !r.room(6 * uint64_t{n}, 4))) return bad();
  uvs.resize(present ? 3 * size_t{n} : 0);
  for (auto& v : uvs)
    if (!r.f32(v.u) || !r.f32(v.v)) return bad();
  std::vector<CornerTangent> tangents;
  if (!r.u8(present) || present > 1 || (present && !r.room(12 * uint64_t{n}, 4))) return bad();
  tangents.resize(present ? 3 * size_t{n} : 0);
  for (auto& v : tangents)
    if (!r.vec(v.direction) || !r.f32(v.sign)) return bad();
  if (s.triangle_count() != n) return bad();
  s.restore_corners(std::move(normals), std::move(uvs), std::move(tangents));
  uint32_t points = 0;
  if (!r.u32(points) || !r.room(points, bytes::kPointLightBytes)) return bad();
  for (uint32_t i = 0; i < points; ++i) {
    PointLight p;
    if (!bytes::read_point_light(r, p)) return bad();
    s.add_point_light(p);
  }
  uint32_t environment_size = 0;
  std::string environment;
  if (!r.u32(environment_size) || !r.str(environment, environment_size)) return bad();
  if (environment_size > 0) {
    auto env = Environment::read(environment);
    if (!env) return make_error(what + ": " + env.error().message);
    s.set_environment(std::move(*env));
  }
  if (!r.done() || s.triangle_count() != n) return bad();
  if (auto st = s.finalize(what); !st) return st.error();
  return s;
}

std::string content_hash(std::string_view bytes) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

Result<Scene> load_cached_scene(const std::string& path, const std::string& hash, const std::string& what) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return make_error(what + ": the cached scene '" + path + "' is missing: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size <= 0) {
    ::close(fd);
    return make_error(what + ": the cached scene '" + path + "' is empty");
  }
  const size_t size = static_cast<size_t>(st.st_size);
  void* map = ::mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (map == MAP_FAILED) return make_error(what + ": cannot map '" + path + "': " + std::strerror(errno));
  const std::string_view bytes(static_cast<const char*>(map), size);
  Result<Scene> scene = content_hash(bytes) == hash
                            ? scene_from_bytes(bytes, what)
                            : Result<Scene>(make_error(what + ": the cached scene '" + path + "' does not match its hash"));
  ::munmap(map, size);
  return scene;
}

}  // namespace lf
