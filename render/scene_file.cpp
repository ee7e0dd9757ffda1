#include "render/scene_file.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>

namespace lf {

namespace {

constexpr std::string_view kMagic = "LFSCENE1";

void put_u32(std::string& out, uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  out.append(b, 4);
}
void put_f32(std::string& out, float v) {
  char b[4];
  std::memcpy(b, &v, 4);
  out.append(b, 4);
}
void put_rgb(std::string& out, const RGB& c) {
  put_f32(out, c.x);
  put_f32(out, c.y);
  put_f32(out, c.z);
}

// Reads from a byte range, failing (not throwing) on a short read.
class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  bool u32(uint32_t& v) { return take(&v, 4); }
  bool f32(float& v) { return take(&v, 4); }
  bool u8(uint8_t& v) { return take(&v, 1); }
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

}  // namespace

std::string scene_to_bytes(const Scene& scene) {
  std::string out(kMagic);
  put_u32(out, static_cast<uint32_t>(scene.materials().size()));
  for (const Material& m : scene.materials()) {
    put_u32(out, static_cast<uint32_t>(m.name.size()));
    out += m.name;
    put_rgb(out, m.kd);
    put_rgb(out, m.ke);
    put_rgb(out, m.ks);
    put_f32(out, m.ns);
    put_f32(out, m.ior);
    out.push_back(static_cast<char>(m.type));
  }
  const auto n = static_cast<uint32_t>(scene.triangle_count());
  put_u32(out, n);
  for (uint32_t t = 0; t < n; ++t)
    for (int c = 0; c < 3; ++c) {
      const Vec3 v = scene.vertex(t, c);
      put_f32(out, v.x);
      put_f32(out, v.y);
      put_f32(out, v.z);
    }
  for (uint32_t t = 0; t < n; ++t) put_u32(out, scene.material_of(t));
  put_u32(out, static_cast<uint32_t>(scene.point_lights().size()));
  for (const PointLight& p : scene.point_lights()) {
    put_f32(out, p.position.x);
    put_f32(out, p.position.y);
    put_f32(out, p.position.z);
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
    uint32_t len = 0;
    uint8_t type = 0;
    if (!r.u32(len) || !r.str(m.name, len)) return bad();
    if (!r.vec(m.kd) || !r.vec(m.ke) || !r.vec(m.ks) || !r.f32(m.ns) || !r.f32(m.ior) || !r.u8(type) || type > 3)
      return bad();
    m.type = static_cast<Material::Type>(type);
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
