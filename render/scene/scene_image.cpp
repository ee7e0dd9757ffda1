#include "render/scene/scene_image.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <numeric>

#include "core/log.hpp"
#include "render/byte_io.hpp"
#include "render/scene/scene_file.hpp"

namespace lf {

namespace {

constexpr char kMagic[8] = {'L', 'F', 'I', 'M', 'A', 'G', 'E', '2'};
constexpr uint32_t kByteOrderMark = 0x01020304;
constexpr uint32_t kVersion = 12;  // 3: kr and tf; 4: metallic and roughness; 5: the environment; 6: their maps;
                                   // 7: normal maps; 8: emission maps; 9: spot lights; 10: transmission;
                                   // 11: corner tangents; 12: the opaque-first order
constexpr size_t kAlign = 64;
constexpr size_t kVertexSlack = 16;

enum Array { kVertices, kTriangles, kMaterialIds, kNormals, kAreas, kLightPdf, kCornerNormals, kCornerUvs, kCornerTangents,
             kOpaqueFirst, kOpaqueFirstCorners, kTexels, kSmall, kArrays };

struct Header {
  char magic[8];
  uint32_t byte_order;
  uint32_t version;
  char hash[16];
  uint64_t triangles;
  uint64_t vertices;
  uint32_t materials;
  uint32_t point_lights;
  uint32_t emitters;
  uint32_t textures;
  uint32_t corner_normals;  // 1 when every triangle has 3 vertex normals, else 0
  uint32_t corner_uvs;      // the same for texture coordinates
  uint32_t corner_tangents;  // and for tangents
  uint64_t texel_bytes;
  float lo[3], hi[3];
  float epsilon;
  uint64_t offset[kArrays];
  uint64_t small_size;
  uint32_t opaque_first;  // 1 when the scene has cut-outs and so the opaque-first order (Scene::opaque_first), else 0
  uint64_t opaque_count;  // how many of that order's triangles are opaque everywhere
};
constexpr size_t kHeaderSize = (sizeof(Header) + kAlign - 1) / kAlign * kAlign;

size_t aligned(size_t n) { return (n + kAlign - 1) / kAlign * kAlign; }

template <class T>
void append_array(std::string& out, std::span<const T> items, size_t slack = 0) {
  out.append(reinterpret_cast<const char*>(items.data()), items.size_bytes());
  out.append(slack, '\0');
  out.resize(aligned(out.size()), '\0');
}

// A read-only shared mapping of a whole file, unmapped when the last scene using it goes.
std::shared_ptr<const void> map_file(const std::string& path, size_t& size, std::string& why) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    why = std::strerror(errno);
    return nullptr;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size < static_cast<off_t>(kHeaderSize)) {
    ::close(fd);
    why = "shorter than its header";
    return nullptr;
  }
  size = static_cast<size_t>(st.st_size);
  void* at = ::mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (at == MAP_FAILED) {
    why = std::strerror(errno);
    return nullptr;
  }
  return std::shared_ptr<const void>(at, [size](const void* p) { ::munmap(const_cast<void*>(p), size); });
}

}  // namespace

std::string SceneImage::encode(const Scene& scene, const std::string& hash) {
  Header h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.byte_order = kByteOrderMark;
  h.version = kVersion;
  std::memcpy(h.hash, hash.data(), std::min(hash.size(), sizeof h.hash));
  h.triangles = scene.triangle_count();
  h.vertices = scene.vertices().size();
  h.materials = static_cast<uint32_t>(scene.materials().size());
  h.point_lights = static_cast<uint32_t>(scene.point_lights().size());
  h.emitters = static_cast<uint32_t>(scene.emitters().size());
  h.textures = static_cast<uint32_t>(scene.textures().size());
  h.corner_normals = scene.has_shading_normals() ? 1 : 0;
  h.corner_uvs = scene.has_uvs() ? 1 : 0;
  h.corner_tangents = scene.has_tangents() ? 1 : 0;
  const Bounds& b = scene.bounds();
  const float lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
  std::memcpy(h.lo, lo, sizeof lo);
  std::memcpy(h.hi, hi, sizeof hi);
  h.epsilon = scene.epsilon();

  std::string out(kHeaderSize, '\0');
  h.offset[kVertices] = out.size();
  append_array(out, scene.vertices(), kVertexSlack);
  h.offset[kTriangles] = out.size();
  append_array(out, scene.triangles());
  h.offset[kMaterialIds] = out.size();
  append_array(out, scene.material_view_);
  h.offset[kNormals] = out.size();
  append_array(out, scene.normal_view_);
  h.offset[kAreas] = out.size();
  append_array(out, scene.area_view_);
  h.offset[kLightPdf] = out.size();
  append_array(out, scene.light_pdf_view_);
  h.offset[kCornerNormals] = out.size();
  append_array(out, scene.corner_normal_view_);
  h.offset[kCornerUvs] = out.size();
  append_array(out, scene.corner_uv_view_);
  h.offset[kCornerTangents] = out.size();
  append_array(out, scene.corner_tangent_view_);
  // The tracer's split, made once here rather than by every actor (a few milliseconds, and 16 bytes a triangle).
  std::vector<uint32_t> order;
  std::vector<std::array<uint32_t, 3>> corners;
  if (scene.has_cutouts()) {
    order.resize(scene.triangle_count());
    std::iota(order.begin(), order.end(), 0u);
    h.opaque_first = 1;
    h.opaque_count = scene.put_opaque_first(order);
    corners.reserve(order.size());
    for (uint32_t t : order) corners.push_back(scene.triangles()[t]);
  }
  h.offset[kOpaqueFirst] = out.size();
  append_array(out, std::span<const uint32_t>(order));
  h.offset[kOpaqueFirstCorners] = out.size();
  append_array(out, std::span<const std::array<uint32_t, 3>>(corners));
  h.offset[kTexels] = out.size();
  std::vector<uint64_t> texel_offsets;
  for (const Texture& t : scene.textures()) {
    texel_offsets.push_back(out.size() - h.offset[kTexels]);
    out.append(reinterpret_cast<const char*>(t.texels.data()), t.texels.size());
  }
  h.texel_bytes = out.size() - h.offset[kTexels];
  out.resize(aligned(out.size()), '\0');
  h.offset[kSmall] = out.size();
  for (size_t i = 0; i < scene.textures().size(); ++i) {
    const Texture& t = scene.textures()[i];
    bytes::put(out, static_cast<uint32_t>(t.path.size()));
    out += t.path;
    bytes::put(out, t.width);
    bytes::put(out, t.height);
    bytes::put(out, t.channels);
    bytes::put<uint8_t>(out, t.linear ? 1 : 0);
    bytes::put(out, texel_offsets[i]);
  }
  for (const Material& m : scene.materials()) bytes::put_material(out, m);
  for (const PointLight& p : scene.point_lights()) bytes::put_point_light(out, p);
  for (uint32_t e : scene.emitters_) bytes::put(out, e);
  for (float c : scene.emitter_cdf_) bytes::put(out, c);
  for (float p : scene.emitter_pdf_) bytes::put(out, p);
  std::string environment;
  if (scene.environment()) scene.environment()->write(environment);
  bytes::put(out, static_cast<uint64_t>(environment.size()));
  out += environment;
  h.small_size = out.size() - h.offset[kSmall];
  std::memcpy(out.data(), &h, sizeof h);
  return out;
}

Result<Scene> SceneImage::map(const std::string& path, const std::string& hash, const std::string& what) {
  size_t size = 0;
  std::string why;
  auto mapping = map_file(path, size, why);
  if (!mapping) return make_error(what + ": cannot map the scene image '" + path + "': " + why);
  const char* base = static_cast<const char*>(mapping.get());
  auto bad = [&](const std::string& detail) {
    return make_error(what + ": the scene image '" + path + "' is damaged (" + detail + ")");
  };
  Header h;
  std::memcpy(&h, base, sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0 || h.byte_order != kByteOrderMark || h.version != kVersion)
    return bad("not an image of this version");
  if (hash.size() != sizeof h.hash || std::memcmp(h.hash, hash.data(), sizeof h.hash) != 0)
    return bad("made for another scene");

  // Each array must lie inside the file, aligned, and not run into the next.
  const uint64_t lengths[kArrays] = {h.vertices * sizeof(Vec3) + kVertexSlack,
                                     h.triangles * sizeof(std::array<uint32_t, 3>),
                                     h.triangles * sizeof(uint32_t),
                                     h.triangles * sizeof(Vec3),
                                     h.triangles * sizeof(float),
                                     h.triangles * sizeof(float),
                                     h.corner_normals * 3 * h.triangles * sizeof(Vec3),
                                     h.corner_uvs * 3 * h.triangles * sizeof(Vec2),
                                     h.corner_tangents * 3 * h.triangles * sizeof(CornerTangent),
                                     h.opaque_first * h.triangles * sizeof(uint32_t),
                                     h.opaque_first * h.triangles * sizeof(std::array<uint32_t, 3>),
                                     h.texel_bytes,
                                     h.small_size};
  if (h.triangles == 0 || h.triangles > size || h.vertices > size || h.corner_normals > 1 || h.corner_uvs > 1 || h.corner_tangents > 1 ||
      h.opaque_first > 1 || h.opaque_count > h.triangles || h.texel_bytes > size)
    return bad("impossible counts");
  uint64_t end = kHeaderSize;
  for (int a = 0; a < kArrays; ++a) {
    if (h.offset[a] % kAlign != 0 || h.offset[a] < end || h.offset[a] > size || lengths[a] > size - h.offset[a])
      return bad("array " + std::to_string(a) + " out of place");
    end = h.offset[a] + lengths[a];
  }

  Scene s;
  s.vertex_view_ = {reinterpret_cast<const Vec3*>(base + h.offset[kVertices]), h.vertices};
  s.triangle_view_ = {reinterpret_cast<const std::array<uint32_t, 3>*>(base + h.offset[kTriangles]), h.triangles};
  s.material_view_ = {reinterpret_cast<const uint32_t*>(base + h.offset[kMaterialIds]), h.triangles};
  s.normal_view_ = {reinterpret_cast<const Vec3*>(base + h.offset[kNormals]), h.triangles};
  s.area_view_ = {reinterpret_cast<const float*>(base + h.offset[kAreas]), h.triangles};
  s.light_pdf_view_ = {reinterpret_cast<const float*>(base + h.offset[kLightPdf]), h.triangles};
  s.corner_normal_view_ = {reinterpret_cast<const Vec3*>(base + h.offset[kCornerNormals]), h.corner_normals * 3 * h.triangles};
  s.corner_uv_view_ = {reinterpret_cast<const Vec2*>(base + h.offset[kCornerUvs]), h.corner_uvs * 3 * h.triangles};
  s.corner_tangent_view_ = {reinterpret_cast<const CornerTangent*>(base + h.offset[kCornerTangents]),
                            h.corner_tangents * 3 * h.triangles};

  bytes::Reader r(std::string_view(base + h.offset[kSmall], h.small_size));
  if (!r.room(h.textures, 24)) return bad("texture count");
  for (uint32_t i = 0; i < h.textures; ++i) {
    Texture t;
    uint32_t length = 0;
    uint64_t at = 0;
    uint8_t linear = 0;
    if (!r.u32(length) || !r.str(t.path, length) || !r.u32(t.width) || !r.u32(t.height) || !r.u32(t.channels) ||
        !r.u8(linear) || linear > 1 || !r.u64(at))
      return bad("textures");
    t.linear = linear != 0;
    if ((t.channels != 1 && t.channels != 3) || t.width == 0 || t.height == 0 || t.width > 65536 || t.height > 65536)
      return bad("a texture's size");
    const uint64_t bytes = Texture::pyramid_bytes(t.width, t.height, t.channels);
    if (at > h.texel_bytes ||
        bytes > h.texel_bytes - at)
      return bad("a texture out of place");
    t.texels = {reinterpret_cast<const uint8_t*>(base + h.offset[kTexels] + at), bytes};
    s.textures_.push_back(std::move(t));
  }
  if (!r.room(h.materials, 50)) return bad("material count");
  for (uint32_t i = 0; i < h.materials; ++i) {
    Material m;
    if (!bytes::read_material(r, m) || !bytes::maps_within(m, h.textures))
      return bad("materials");
    s.materials_.push_back(std::move(m));
  }
  if (!r.room(h.point_lights, bytes::kPointLightBytes)) return bad("point light count");
  for (uint32_t i = 0; i < h.point_lights; ++i) {
    PointLight p;
    if (!bytes::read_point_light(r, p)) return bad("point lights");
    s.point_lights_.push_back(p);
  }
  const uint64_t lights = uint64_t{h.emitters} + h.point_lights;
  if (h.emitters > h.triangles || !r.room(uint64_t{h.emitters} + 2 * lights, 4)) return bad("light counts");
  s.emitters_.resize(h.emitters);
  for (size_t i = 0; i < s.emitters_.size(); ++i)  // in increasing order, as finalize() lists them
    if (!r.u32(s.emitters_[i]) || s.emitters_[i] >= h.triangles || (i > 0 && s.emitters_[i] <= s.emitters_[i - 1]))
      return bad("emitters");
  s.emitter_cdf_.resize(lights);
  s.emitter_pdf_.resize(lights);
  for (float& c : s.emitter_cdf_) r.f32(c);
  for (float& p : s.emitter_pdf_) r.f32(p);
  uint64_t environment_size = 0;
  std::string environment;
  if (!r.u64(environment_size) || environment_size > h.small_size || !r.str(environment, static_cast<uint32_t>(environment_size)))
    return bad("the environment");
  if (environment_size > 0) {
    auto env = Environment::read(environment);
    if (!env) return bad(env.error().message);
    s.set_environment(std::move(*env));
  }
  if (!r.done() || (lights == 0 && environment_size == 0)) return bad("the small part");

  // Every index the renderer follows must stay inside its array.
  for (const auto& tri : s.triangle_view_)
    if (tri[0] >= h.vertices || tri[1] >= h.vertices || tri[2] >= h.vertices) return bad("a vertex index");
  for (uint32_t m : s.material_view_)
    if (m >= h.materials) return bad("a material index");
  // The opaque-first order: each triangle once, with its own corners (so its vertex indices were checked above).
  s.opaque_first_.triangles = {reinterpret_cast<const uint32_t*>(base + h.offset[kOpaqueFirst]), h.opaque_first * h.triangles};
  s.opaque_first_.corners = {reinterpret_cast<const std::array<uint32_t, 3>*>(base + h.offset[kOpaqueFirstCorners]),
                             h.opaque_first * h.triangles};
  s.opaque_first_.opaque = h.opaque_count;
  std::vector<bool> listed(s.opaque_first_.triangles.size());
  for (size_t i = 0; i < s.opaque_first_.triangles.size(); ++i) {
    const uint32_t t = s.opaque_first_.triangles[i];
    if (t >= h.triangles || listed[t] || s.opaque_first_.corners[i] != s.triangle_view_[t]) return bad("the opaque-first order");
    listed[t] = true;
  }

  s.bounds_ = Bounds{{h.lo[0], h.lo[1], h.lo[2]}, {h.hi[0], h.hi[1], h.hi[2]}};
  s.epsilon_ = h.epsilon;
  s.storage_ = std::move(mapping);
  s.light_tree_ = std::make_shared<const LightTree>(s);
  s.emitter_cutouts_ = std::make_shared<const EmitterCutouts>(s);
  s.settle_environment_share();
  s.settle_normal_maps();
  return s;
}

Result<Scene> load_shared_scene(const std::string& shipped, const std::string& hash, const std::string& what) {
  const std::string image = shipped + ".image";
  // The lock makes concurrent actors wait for the one making the image, then map that same file.
  const std::string lock_path = shipped + ".lock";
  const int lock = ::open(lock_path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0600);
  if (lock >= 0) {
    while (::flock(lock, LOCK_EX) != 0 && errno == EINTR) {
    }
  }
  struct Unlock {
    int fd;
    ~Unlock() {
      if (fd >= 0) ::close(fd);  // closing releases the lock
    }
  } unlock{lock};

  if (auto mapped = SceneImage::map(image, hash, what)) return mapped;
  auto scene = load_cached_scene(shipped, hash, what);
  if (!scene) return scene;
  const std::string bytes = SceneImage::encode(*scene, hash);
  const std::string temp = image + ".tmp." + std::to_string(::getpid());
  // Why it could not be made, taken where it failed (errno would be overwritten by the clean-up).
  std::string why;
  const int fd = ::open(temp.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0644);
  if (fd < 0) why = std::strerror(errno);
  for (size_t at = 0; why.empty() && at < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + at, bytes.size() - at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) why = n < 0 ? std::strerror(errno) : "nothing written";
    else at += static_cast<size_t>(n);
  }
  if (fd >= 0 && ::close(fd) != 0 && why.empty()) why = std::strerror(errno);
  if (why.empty() && ::rename(temp.c_str(), image.c_str()) != 0) why = std::strerror(errno);
  if (why.empty()) {
    auto mapped = SceneImage::map(image, hash, what);
    if (mapped) return mapped;
    why = mapped.error().message;
  }
  ::unlink(temp.c_str());
  // Still correct, only not shared: this actor keeps its own copy.
  log_warn(what + ": cannot make the shared scene image '" + image + "' (" + why + "); this actor keeps a private copy");
  return scene;
}

}  // namespace lf
