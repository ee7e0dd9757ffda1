#include "render/scene_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>

#include "render/byte_io.hpp"

namespace lf {

namespace {

constexpr std::string_view kMagic = "LFSCENE1";
using bytes::put;
using bytes::put_rgb;
using bytes::Reader;
using bytes::put_material;
using bytes::read_material;

}  // namespace

std::string scene_to_bytes(const Scene& scene) {
  std::string out(kMagic);
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
  put<uint32_t>(out, static_cast<uint32_t>(scene.point_lights().size()));
  for (const PointLight& p : scene.point_lights()) {
    put<float>(out, p.position.x);
    put<float>(out, p.position.y);
    put<float>(out, p.position.z);
    put_rgb(out, p.intensity);
  }
  return out;
}

Result<Scene> scene_from_bytes(std::string_view bytes, const std::string& what) {
  if (bytes.substr(0, kMagic.size()) != kMagic) return make_error(what + ": not a lightfarm scene (no LFSCENE1)");
  Reader r(bytes.substr(kMagic.size()));
  auto bad = [&] { return make_error(what + ": the scene's bytes are truncated or inconsistent"); };
  Scene s;
  uint32_t materials = 0;
  if (!r.u32(materials) || !r.room(materials, 50)) return bad();
  for (uint32_t i = 0; i < materials; ++i) {
    Material m;
    if (!read_material(r, m)) return bad();
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
  uint32_t points = 0;
  if (!r.u32(points) || !r.room(points, 24)) return bad();
  for (uint32_t i = 0; i < points; ++i) {
    Vec3 p, c;
    if (!r.vec(p) || !r.vec(c)) return bad();
    s.add_point_light(p, c);
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
