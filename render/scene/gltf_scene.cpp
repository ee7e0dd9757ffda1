// glTF 2.0 scenes (.gltf, .glb) through tinygltf: the default scene's node tree with its transforms, triangle
// primitives with normals and texture coordinates, metal-roughness materials with their base colour textures and
// emission, transmission and index of refraction (KHR_materials_transmission, KHR_materials_ior: rough glass, or
// smooth glass where it is smooth), and KHR_lights_punctual lights. What is not supported is a warning that names
// the file and the element (docs/lua-api.md, "Materials").
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <span>

#include "core/log.hpp"
#include "render/scene/scene.hpp"

namespace lf {

namespace {

struct Mat4 {
  double m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // column-major, as glTF stores it
  Mat4 operator*(const Mat4& o) const {
    Mat4 r;
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += m[k * 4 + row] * o.m[c * 4 + k];
        r.m[c * 4 + row] = s;
      }
    return r;
  }
  Vec3 point(Vec3 p) const {
    return {static_cast<float>(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12]),
            static_cast<float>(m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13]),
            static_cast<float>(m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14])};
  }
  Vec3 vector(Vec3 v) const {
    return {static_cast<float>(m[0] * v.x + m[4] * v.y + m[8] * v.z), static_cast<float>(m[1] * v.x + m[5] * v.y + m[9] * v.z),
            static_cast<float>(m[2] * v.x + m[6] * v.y + m[10] * v.z)};
  }
  double determinant3() const {
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) + m[8] * (m[1] * m[6] - m[5] * m[2]);
  }
};

// How a node's transform carries normals: the inverse transpose of its upper 3x3 (its cofactors, signed by the
// determinant so that they keep pointing out), made once per node.
struct NormalTransform {
  double c[9];
  explicit NormalTransform(const Mat4& t) {
    const double* m = t.m;
    const double s = t.determinant3() < 0 ? -1 : 1;
    const double cof[9] = {m[5] * m[10] - m[9] * m[6], m[8] * m[6] - m[4] * m[10], m[4] * m[9] - m[8] * m[5],
                           m[9] * m[2] - m[1] * m[10], m[0] * m[10] - m[8] * m[2], m[8] * m[1] - m[0] * m[9],
                           m[1] * m[6] - m[5] * m[2], m[4] * m[2] - m[0] * m[6], m[0] * m[5] - m[4] * m[1]};
    for (int i = 0; i < 9; ++i) c[i] = s * cof[i];
  }
  Vec3 operator()(Vec3 n) const {
    return normalize(Vec3{static_cast<float>(c[0] * n.x + c[1] * n.y + c[2] * n.z),
                          static_cast<float>(c[3] * n.x + c[4] * n.y + c[5] * n.z),
                          static_cast<float>(c[6] * n.x + c[7] * n.y + c[8] * n.z)});
  }
};

// A node's translation, rotation (a unit quaternion x, y, z, w) and scale.
struct Trs {
  std::array<double, 4> t{0, 0, 0, 0}, r{0, 0, 0, 1}, s{1, 1, 1, 0};
  Mat4 matrix() const {
    Mat4 translate, rotate, scale;
    for (int i = 0; i < 3; ++i) translate.m[12 + i] = t[static_cast<size_t>(i)];
    const double x = r[0], y = r[1], z = r[2], w = r[3];
    const double m[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; ++c)
      for (int row = 0; row < 3; ++row) rotate.m[c * 4 + row] = m[c * 3 + row];
    for (int i = 0; i < 3; ++i) scale.m[i * 5] = s[static_cast<size_t>(i)];
    return translate * rotate * scale;
  }
};

Trs trs_of(const tinygltf::Node& node) {
  Trs v;
  if (node.translation.size() == 3) std::copy(node.translation.begin(), node.translation.end(), v.t.begin());
  if (node.rotation.size() == 4) std::copy(node.rotation.begin(), node.rotation.end(), v.r.begin());
  if (node.scale.size() == 3) std::copy(node.scale.begin(), node.scale.end(), v.s.begin());
  return v;
}

Mat4 local_transform(const tinygltf::Node& node) {
  Mat4 t;
  if (node.matrix.size() == 16) {
    std::copy(node.matrix.begin(), node.matrix.end(), t.m);
    return t;
  }
  return trs_of(node).matrix();
}

// An accessor's elements as floats (`width` components each), checked against its buffer: an accessor that reaches
// past its buffer, or of a type this reader does not take, is an error.
class AccessorReader {
 public:
  AccessorReader(const tinygltf::Model& model, std::string where) : model_(model), where_(std::move(where)) {}

  Result<std::vector<float>> floats(int index, int width, const std::string& what) const {
    auto view = checked(index, width, what);
    if (!view) return view.error();
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    std::vector<float> out(a.count * static_cast<size_t>(width));
    for (size_t e = 0; e < a.count; ++e)
      for (int c = 0; c < width; ++c) {
        const uint8_t* at = view->data + e * view->stride + static_cast<size_t>(c) * view->component;
        float v = 0;
        switch (a.componentType) {
          case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, at, 4); break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *at / 255.0f; break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t u;
            std::memcpy(&u, at, 2);
            v = u / 65535.0f;
            break;
          }
          default: return make_error(where_ + ": " + what + " has components of a type glTF does not allow there");
        }
        out[e * static_cast<size_t>(width) + static_cast<size_t>(c)] = v;
      }
    return out;
  }

  Result<std::vector<uint32_t>> indices(int index, size_t vertex_count, const std::string& what) const {
    auto view = checked(index, 1, what);
    if (!view) return view.error();
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    std::vector<uint32_t> out(a.count);
    for (size_t e = 0; e < a.count; ++e) {
      const uint8_t* at = view->data + e * view->stride;
      uint32_t v = 0;
      if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) {
        v = *at;
      } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        uint16_t u;
        std::memcpy(&u, at, 2);
        v = u;
      } else if (a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
        std::memcpy(&v, at, 4);
      } else {
        return make_error(where_ + ": " + what + " are not unsigned integers");
      }
      if (v >= vertex_count) return make_error(where_ + ": " + what + " name a vertex that does not exist");
      out[e] = v;
    }
    return out;
  }

 private:
  struct View {
    const uint8_t* data;
    size_t stride, component;
  };
  Result<View> checked(int index, int width, const std::string& what) const {
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
      return make_error(where_ + ": " + what + " name an accessor that does not exist");
    const tinygltf::Accessor& a = model_.accessors[static_cast<size_t>(index)];
    const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
    const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
    if (components != width || size <= 0) return make_error(where_ + ": " + what + " have the wrong type");
    if (a.sparse.isSparse) return make_error(where_ + ": " + what + " are sparse, which this reader does not take");
    if (a.bufferView < 0 || static_cast<size_t>(a.bufferView) >= model_.bufferViews.size())
      return make_error(where_ + ": " + what + " have no buffer view");
    const tinygltf::BufferView& v = model_.bufferViews[static_cast<size_t>(a.bufferView)];
    if (v.buffer < 0 || static_cast<size_t>(v.buffer) >= model_.buffers.size())
      return make_error(where_ + ": " + what + "' buffer view names no buffer");
    const auto& bytes = model_.buffers[static_cast<size_t>(v.buffer)].data;
    const size_t element = static_cast<size_t>(components) * static_cast<size_t>(size);
    const size_t stride = v.byteStride ? v.byteStride : element;
    // The view lies within its buffer, and the accessor's last element within the view.
    bool fits = stride >= element && v.byteOffset <= bytes.size() && v.byteLength <= bytes.size() - v.byteOffset &&
                a.byteOffset <= v.byteLength;
    if (fits && a.count > 0) {
      const size_t room = v.byteLength - a.byteOffset;
      fits = element <= room && a.count - 1 <= (room - element) / stride;
    }
    if (!fits) return make_error(where_ + ": " + what + " reach past their buffer");
    return View{bytes.data() + v.byteOffset + a.byteOffset, stride, static_cast<size_t>(size)};
  }
  const tinygltf::Model& model_;
  std::string where_;
};

// Depth first through the default scene's node tree, each node with its transform to the world and its chain: the
// node indices from the scene's root down to it, itself last. A node index that does not exist, or a tree deeper
// than 64 (a cycle, in a hostile file), stops the walk with an error.
Status for_each_node(const tinygltf::Model& model, const std::string& where,
                     const std::function<Status(const tinygltf::Node&, const Mat4&, std::span<const int>)>& visit) {
  std::vector<int> chain;
  std::function<Status(int, const Mat4&)> walk = [&](int index, const Mat4& parent) -> Status {
    if (index < 0 || static_cast<size_t>(index) >= model.nodes.size() || chain.size() > 64)
      return make_error(where + ": a node tree that names a node that does not exist, or deeper than 64");
    const tinygltf::Node& node = model.nodes[static_cast<size_t>(index)];
    const Mat4 world = parent * local_transform(node);
    chain.push_back(index);
    if (auto st = visit(node, world, chain); !st) return st;
    for (int child : node.children)
      if (auto st = walk(child, world); !st) return st;
    chain.pop_back();
    return Ok{};
  };
  const int scene_index = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (static_cast<size_t>(scene_index) < model.scenes.size())
    for (int root : model.scenes[static_cast<size_t>(scene_index)].nodes)
      if (auto st = walk(root, Mat4{}); !st) return st;
  return Ok{};
}

// The image texture `t` samples, and the name it goes by; null without one.
const tinygltf::Image* texture_image(const tinygltf::Model& model, int t, std::string& name) {
  if (t < 0 || static_cast<size_t>(t) >= model.textures.size()) return nullptr;
  const int source = model.textures[static_cast<size_t>(t)].source;
  if (source < 0 || static_cast<size_t>(source) >= model.images.size()) return nullptr;
  const tinygltf::Image& image = model.images[static_cast<size_t>(source)];
  name = image.name.empty() ? "image" + std::to_string(source) : image.name;
  return &image;
}

// The image a material's base colour texture samples, and the name it goes by; null without one.
const tinygltf::Image* base_color_image(const tinygltf::Model& model, const tinygltf::Material& material,
                                        std::string& name) {
  return texture_image(model, material.pbrMetallicRoughness.baseColorTexture.index, name);
}

std::string material_name(const tinygltf::Material& m, size_t index) {
  return m.name.empty() ? "material" + std::to_string(index) : m.name;
}

// The names glTF's materials get in the scene: theirs, or "materialN"; a name used twice gets its index appended.
std::vector<std::string> material_names(const tinygltf::Model& model) {
  std::vector<std::string> names;
  std::set<std::string> used;
  for (size_t i = 0; i < model.materials.size(); ++i) {
    std::string name = material_name(model.materials[i], i);
    if (!used.insert(name).second) {
      name.append(".").append(std::to_string(i));
      used.insert(name);
    }
    names.push_back(name);
  }
  return names;
}

// From a file, or (`bytes` given) from memory with `path` naming it and its folder the one external buffers and
// images are read from. `images`: decode them (a catalogue, read while the script runs, needs none).
Result<tinygltf::Model> read_model(const std::string& path, std::vector<std::string>& warnings,
                                   const std::string* bytes = nullptr, bool images = true) {
  std::error_code ec;
  if (!bytes && !std::filesystem::is_regular_file(path, ec)) return make_error("scene file '" + path + "' not found");
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  if (!images)
    loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                             void*) { return true; },
                          nullptr);
  std::string error, warning;
  bool ok = false;
  if (bytes) {
    const std::string dir = std::filesystem::path(path).parent_path().string();
    ok = bytes->rfind("glTF", 0) == 0
             ? loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes->data()),
                                           static_cast<unsigned int>(bytes->size()), dir)
             : loader.LoadASCIIFromString(&model, &error, &warning, bytes->data(), static_cast<unsigned int>(bytes->size()), dir);
  } else {
    ok = std::filesystem::path(path).extension() == ".glb" ? loader.LoadBinaryFromFile(&model, &error, &warning, path)
                                                           : loader.LoadASCIIFromFile(&model, &error, &warning, path);
  }
  // tinygltf ends its messages with a newline.
  while (!warning.empty() && std::isspace(static_cast<unsigned char>(warning.back()))) warning.pop_back();
  while (!error.empty() && std::isspace(static_cast<unsigned char>(error.back()))) error.pop_back();
  if (!warning.empty()) warnings.push_back("scene file '" + path + "': " + warning);
  if (!ok) return make_error("scene file '" + path + "': not a glTF file tinygltf can read (" + error + ")");
  return model;
}

// KHR_texture_transform's matrix (offset x rotation x scale, in glTF's texture coordinates, v down), applied to
// texture coordinates: u' = a u + b v + c, v' = d u + e v + f.
struct UvTransform {
  double a = 1, b = 0, c = 0, d = 0, e = 1, f = 0;
  bool operator==(const UvTransform&) const = default;
  Vec2 apply(float u, float v) const {
    return {static_cast<float>(a * u + b * v + c), static_cast<float>(d * u + e * v + f)};
  }
};

// A texture reference's KHR_texture_transform (the identity without one).
template <class Info>
UvTransform uv_transform_of(const Info& info) {
  UvTransform t;
  const auto it = info.extensions.find("KHR_texture_transform");
  if (it == info.extensions.end()) return t;
  const tinygltf::Value& x = it->second;
  auto number = [&](const tinygltf::Value& v, double fallback) { return v.IsNumber() ? v.GetNumberAsDouble() : fallback; };
  double ox = 0, oy = 0, sx = 1, sy = 1, r = 0;
  if (x.Has("offset") && x.Get("offset").ArrayLen() == 2)
    ox = number(x.Get("offset").Get(0), 0), oy = number(x.Get("offset").Get(1), 0);
  if (x.Has("scale") && x.Get("scale").ArrayLen() == 2)
    sx = number(x.Get("scale").Get(0), 1), sy = number(x.Get("scale").Get(1), 1);
  if (x.Has("rotation")) r = number(x.Get("rotation"), 0);
  // The extension's matrices: T [1 0 ox; 0 1 oy] R [cos sin; -sin cos] S [sx 0; 0 sy].
  const double cr = std::cos(r), sr = std::sin(r);
  t.a = cr * sx, t.b = sr * sy, t.c = ox;
  t.d = -sr * sx, t.e = cr * sy, t.f = oy;
  return t;
}

// A texture of `channels` channels from an 8-bit image with at least `components`: channel c of texel i is
// texel(the image's pixel i, c). nullopt for an image of another kind, or one whose data is short.
template <class Texel>
std::optional<Texture> image_texture(const tinygltf::Image& image, int components, uint32_t channels, bool linear,
                                     const std::string& name, Texel texel) {
  if (image.width <= 0 || image.height <= 0 || image.bits != 8 || image.component < components ||
      image.image.size() < static_cast<size_t>(image.width) * static_cast<size_t>(image.height) * static_cast<size_t>(image.component))
    return std::nullopt;
  Texture t;
  t.path = name;
  t.width = static_cast<uint32_t>(image.width);
  t.height = static_cast<uint32_t>(image.height);
  t.channels = channels;
  t.linear = linear;
  const size_t n = static_cast<size_t>(t.width) * t.height, from = static_cast<size_t>(image.component);
  t.owned.resize(n * channels);
  for (size_t i = 0; i < n; ++i)
    for (uint32_t c = 0; c < channels; ++c) t.owned[i * channels + c] = texel(&image.image[i * from], c);
  t.build_pyramid();
  return t;
}

// A base colour texture as the scene keeps it: RGB, sRGB-encoded, with the material's base colour factor (which
// glTF multiplies in linear values) applied to its texels.
std::optional<Texture> base_color_texture(const tinygltf::Image& image, RGB factor, const std::string& name) {
  const bool scaled = factor.x != 1 || factor.y != 1 || factor.z != 1;
  return image_texture(image, 3, 3, false, name, [&](const unsigned char* px, uint32_t c) {
    const uint8_t v = px[c];
    if (!scaled) return v;
    const float f = c == 0 ? factor.x : c == 1 ? factor.y : factor.z;
    return static_cast<uint8_t>(std::lround(std::clamp(srgb_encode(srgb_decode(v / 255.0f) * f), 0.0f, 1.0f) * 255.0f));
  });
}

// An image whose channels are data (a normal map's x, y, z), kept as they are: a `linear` texture.
std::optional<Texture> data_texture(const tinygltf::Image& image, const std::string& name) {
  return image_texture(image, 3, 3, true, name, [](const unsigned char* px, uint32_t c) { return px[c]; });
}

// One channel of an image as a linear one-channel texture (a metallic-roughness texture's blue: metallic, its
// green: roughness).
std::optional<Texture> channel_texture(const tinygltf::Image& image, int channel, const std::string& name) {
  return image_texture(image, channel + 1, 1, false, name,
                       [channel](const unsigned char* px, uint32_t) { return px[channel]; });
}

// A cut-out as the scene keeps it (one linear channel, absent below one half) from a base colour texture's alpha
// times the factor's: scaled so that the material's alphaCutoff falls on one half.
std::optional<Texture> coverage_texture(const tinygltf::Image& image, float factor, float cutoff, const std::string& name) {
  const float scale = factor * 0.5f / std::max(cutoff, 1e-3f);
  return image_texture(image, 4, 1, false, name + " (alpha)", [scale](const unsigned char* px, uint32_t) {
    return static_cast<uint8_t>(std::lround(std::clamp(px[3] * scale, 0.0f, 255.0f)));
  });
}

// The view of a perspective camera at a node whose transform to the world is `world`: a glTF camera looks down its
// node's -z with +y up. None where the transform flattens that (a zero scale).
std::optional<CameraSpec> view_from(const Mat4& world, const tinygltf::Camera& cam) {
  const Vec3 eye = world.point({0, 0, 0}), ahead = world.vector({0, 0, -1}), up = world.vector({0, 1, 0});
  if (!(length(ahead) > 0) || !(length(up) > 0) || !(length(cross(ahead, up)) > 0)) return std::nullopt;
  const Vec3 at = eye + normalize(ahead), u = normalize(up);
  CameraSpec view;
  view.eye = {eye.x, eye.y, eye.z};
  view.at = {at.x, at.y, at.z};
  view.up = {u.x, u.y, u.z};
  view.fov = std::clamp(cam.perspective.yfov * 180.0 / kPi, 0.1, 179.0);
  return view;
}

// A perspective camera of the default scene: the nodes from the scene's root down to its node, and its view at rest.
struct CameraNode {
  std::string name;
  std::vector<int> chain;
  const tinygltf::Camera* camera = nullptr;
  CameraSpec view;
};

// The default scene's perspective cameras in node order; a broken node tree ends the list where it breaks (loading
// the scene says what is wrong).
std::vector<CameraNode> camera_nodes(const tinygltf::Model& model) {
  std::vector<CameraNode> out;
  (void)for_each_node(model, "", [&](const tinygltf::Node& node, const Mat4& world, std::span<const int> chain) -> Status {
    if (node.camera >= 0 && static_cast<size_t>(node.camera) < model.cameras.size()) {
      const tinygltf::Camera& cam = model.cameras[static_cast<size_t>(node.camera)];
      if (auto view = view_from(world, cam); view && cam.type == "perspective" && cam.perspective.yfov > 0)
        out.push_back({!node.name.empty() ? node.name : !cam.name.empty() ? cam.name : "camera" + std::to_string(out.size()),
                       {chain.begin(), chain.end()}, &cam, *view});
    }
    return Ok{};
  });
  return out;
}

// One animation channel on a node's translation (path 0), rotation (1) or scale (2): its key times, ascending, and
// values, 3 or 4 a key (CUBICSPLINE: in-tangent, value, out-tangent a key).
struct Channel {
  int node = 0, path = 0;
  enum class Interpolation { step, linear, cubic } interpolation = Interpolation::linear;
  std::vector<float> times, values;

  std::array<double, 4> at(double t) const {
    const size_t width = path == 1 ? 4 : 3, per_key = interpolation == Interpolation::cubic ? 3 : 1;
    auto value = [&](size_t key, size_t part) {  // part: 0 in-tangent, 1 value, 2 out-tangent (cubic); 0 otherwise
      std::array<double, 4> v{0, 0, 0, 0};
      for (size_t c = 0; c < width; ++c) v[c] = values[(key * per_key + part) * width + c];
      return v;
    };
    const size_t mid = per_key == 3 ? 1 : 0;
    const size_t n = times.size();
    if (n == 1 || t <= times.front()) return finish(value(0, mid));
    if (t >= times.back()) return finish(value(n - 1, mid));
    const size_t k = static_cast<size_t>(std::upper_bound(times.begin(), times.end(), static_cast<float>(t)) - times.begin()) - 1;
    const double dt = static_cast<double>(times[k + 1]) - times[k], u = dt > 0 ? (t - times[k]) / dt : 0;
    std::array<double, 4> a = value(k, mid), b = value(k + 1, mid), r{0, 0, 0, 0};
    if (interpolation == Interpolation::step) return finish(a);
    if (interpolation == Interpolation::cubic) {
      const std::array<double, 4> out_a = value(k, 2), in_b = value(k + 1, 0);
      const double u2 = u * u, u3 = u2 * u;
      for (size_t c = 0; c < width; ++c)
        r[c] = (2 * u3 - 3 * u2 + 1) * a[c] + (u3 - 2 * u2 + u) * dt * out_a[c] + (-2 * u3 + 3 * u2) * b[c] + (u3 - u2) * dt * in_b[c];
      return finish(r);
    }
    if (path != 1) {
      for (size_t c = 0; c < 3; ++c) r[c] = a[c] + u * (b[c] - a[c]);
      return r;
    }
    // Rotations: spherical, the shorter way round.
    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    if (dot < 0) {
      for (double& c : b) c = -c;
      dot = -dot;
    }
    double wa = 1 - u, wb = u;
    if (dot < 0.9995) {
      const double angle = std::acos(std::min(dot, 1.0));
      wa = std::sin((1 - u) * angle) / std::sin(angle), wb = std::sin(u * angle) / std::sin(angle);
    }
    for (size_t c = 0; c < 4; ++c) r[c] = wa * a[c] + wb * b[c];
    return finish(r);
  }

 private:
  std::array<double, 4> finish(std::array<double, 4> v) const {
    if (path != 1) return v;
    const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
    if (norm > 0)
      for (double& c : v) c /= norm;
    else
      v = {0, 0, 0, 1};
    return v;
  }
};

// Every channel of every animation that moves one of `chain`'s nodes (their translation, rotation or scale; morph
// weights move no camera). An error names a channel that cannot be played: a sampler or accessor that does not
// exist or reaches past its buffer, key times that are not ascending, values that do not match them, a node given
// by a matrix (glTF animates only nodes given by translation, rotation and scale).
Result<std::vector<Channel>> channels_moving(const tinygltf::Model& model, const std::vector<int>& chain, const std::string& path) {
  std::vector<Channel> out;
  const AccessorReader read(model, "scene file '" + path + "'");
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Animation& anim = model.animations[a];
    for (size_t c = 0; c < anim.channels.size(); ++c) {
      const tinygltf::AnimationChannel& ch = anim.channels[c];
      if (std::find(chain.begin(), chain.end(), ch.target_node) == chain.end()) continue;
      const int which = ch.target_path == "translation" ? 0 : ch.target_path == "rotation" ? 1 : ch.target_path == "scale" ? 2 : -1;
      if (which < 0) continue;
      const std::string what = "animation " + std::to_string(a) + "'s channel " + std::to_string(c);
      if (model.nodes[static_cast<size_t>(ch.target_node)].matrix.size() == 16)
        return make_error("scene file '" + path + "': " + what + " animates a node given by a matrix");
      if (ch.sampler < 0 || static_cast<size_t>(ch.sampler) >= anim.samplers.size())
        return make_error("scene file '" + path + "': " + what + " names a sampler that does not exist");
      const tinygltf::AnimationSampler& sampler = anim.samplers[static_cast<size_t>(ch.sampler)];
      Channel out_ch;
      out_ch.node = ch.target_node, out_ch.path = which;
      out_ch.interpolation = sampler.interpolation == "STEP"          ? Channel::Interpolation::step
                             : sampler.interpolation == "CUBICSPLINE" ? Channel::Interpolation::cubic
                                                                      : Channel::Interpolation::linear;
      auto times = read.floats(sampler.input, 1, what + "'s key times");
      if (!times) return times.error();
      const int width = which == 1 ? 4 : 3;
      auto values = read.floats(sampler.output, width, what + "'s values");
      if (!values) return values.error();
      const size_t per_key = out_ch.interpolation == Channel::Interpolation::cubic ? 3 : 1;
      bool ascending = !times->empty();
      for (size_t k = 0; ascending && k < times->size(); ++k)
        ascending = std::isfinite((*times)[k]) && (k == 0 || (*times)[k] > (*times)[k - 1]);
      if (!ascending) return make_error("scene file '" + path + "': " + what + "'s key times are not ascending");
      if (values->size() != times->size() * per_key * static_cast<size_t>(width))
        return make_error("scene file '" + path + "': " + what + " has " + std::to_string(values->size() / static_cast<size_t>(width)) +
                          " values for " + std::to_string(times->size()) + " keys");
      for (float v : *values)
        if (!std::isfinite(v)) return make_error("scene file '" + path + "': " + what + " has a value that is no number");
      out_ch.times = std::move(*times), out_ch.values = std::move(*values);
      out.push_back(std::move(out_ch));
    }
  }
  return out;
}

}  // namespace

bool Scene::is_gltf_path(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext == ".gltf" || ext == ".glb";
}

Result<ObjCatalogue> Scene::catalogue_gltf(const std::string& path, const std::string* bytes) {
  ObjCatalogue out;
  auto model = read_model(path, out.warnings, bytes, /*images=*/false);
  if (!model) return model.error();
  out.material_names = material_names(*model);
  // Broken animations leave the cameras still here (asking for their views says what is wrong).
  for (const CameraNode& c : camera_nodes(*model)) {
    ObjCatalogue::FileCamera fc{c.name, c.view};
    if (auto channels = channels_moving(*model, c.chain, path); channels && !channels->empty()) {
      fc.animated = true;
      for (const Channel& ch : *channels) fc.animation_seconds = std::max(fc.animation_seconds, static_cast<double>(ch.times.back()));
    }
    out.cameras.push_back(std::move(fc));
  }
  return out;
}

Result<std::vector<CameraSpec>> Scene::gltf_camera_views(const std::string& path, size_t index,
                                                         const std::vector<double>& seconds, const std::string* bytes) {
  std::vector<std::string> warnings;
  auto model = read_model(path, warnings, bytes, /*images=*/false);
  if (!model) return model.error();
  const std::vector<CameraNode> cameras = camera_nodes(*model);
  if (index >= cameras.size()) return make_error("scene file '" + path + "' has no camera " + std::to_string(index));
  const CameraNode& camera = cameras[index];
  auto channels = channels_moving(*model, camera.chain, path);
  if (!channels) return channels.error();
  std::vector<CameraSpec> views;
  for (double t : seconds) {
    Mat4 world;
    for (int n : camera.chain) {
      const tinygltf::Node& node = model->nodes[static_cast<size_t>(n)];
      Trs local = trs_of(node);
      bool moved = false;
      for (const Channel& ch : *channels)
        if (ch.node == n) (ch.path == 0 ? local.t : ch.path == 1 ? local.r : local.s) = ch.at(t), moved = true;
      world = world * (moved ? local.matrix() : local_transform(node));
    }
    auto view = view_from(world, *camera.camera);
    if (!view) return make_error("scene file '" + path + "': camera '" + camera.name + "' at " + std::to_string(t) +
                                 " s of its animation looks nowhere (a zero scale)");
    views.push_back(*view);
  }
  return views;
}

Result<Scene> Scene::load_gltf_unlit(const std::string& path) { return parse_gltf_unlit(path, nullptr); }

Result<Scene> Scene::parse_gltf_unlit(const std::string& path, const std::string* bytes) {
  std::vector<std::string> read_warnings;  // tinygltf's: the catalogue reports them (catalogue_file)
  auto loaded = read_model(path, read_warnings, bytes);
  if (!loaded) return loaded.error();
  const tinygltf::Model& model = *loaded;
  const std::string where = "scene file '" + path + "'";
  std::set<std::string> warned;
  auto warn = [&](const std::string& what) {
    if (warned.insert(what).second) log_warn(where + ": " + what);
  };
  for (const auto& e : model.extensionsUsed)
    if (e != "KHR_lights_punctual" && e != "KHR_materials_emissive_strength" && e != "KHR_texture_transform" &&
        e != "KHR_materials_transmission" && e != "KHR_materials_ior")
      warn("extension " + e + " is not supported; what it adds is left out");

  Scene s;
  const std::vector<std::string> names = material_names(model);
  // Each material's texture transform, applied to its primitives' texture coordinates as they are read: every
  // texture of a material shares the triangle's coordinates here, so they share one transform.
  std::vector<UvTransform> uv_transforms(model.materials.size());
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const tinygltf::Material& g = model.materials[i];
    const auto& pbr = g.pbrMetallicRoughness;
    Material m{names[i], {}, {}};
    {
      std::vector<std::pair<int, UvTransform>> used;  // (texture index, transform) of each texture it names
      for (const auto& [index, transform] :
           {std::pair{pbr.baseColorTexture.index, uv_transform_of(pbr.baseColorTexture)},
            {pbr.metallicRoughnessTexture.index, uv_transform_of(pbr.metallicRoughnessTexture)},
            {g.normalTexture.index, uv_transform_of(g.normalTexture)},
            {g.emissiveTexture.index, uv_transform_of(g.emissiveTexture)}})
        if (index >= 0) used.emplace_back(index, transform);
      if (!used.empty()) uv_transforms[i] = used.front().second;
      for (const auto& u : used)
        if (!(u.second == used.front().second))
          warn("material '" + names[i] + "': its textures have different KHR_texture_transforms; the first one's "
               "(base colour, metallic-roughness, normal, emissive in that order) is used for all");
    }
    m.type = Material::Type::metal_rough;
    RGB factor{1, 1, 1};
    if (pbr.baseColorFactor.size() == 4)
      factor = {static_cast<float>(pbr.baseColorFactor[0]), static_cast<float>(pbr.baseColorFactor[1]),
                static_cast<float>(pbr.baseColorFactor[2])};
    m.kd = {std::clamp(factor.x, 0.0f, 1.0f), std::clamp(factor.y, 0.0f, 1.0f), std::clamp(factor.z, 0.0f, 1.0f)};
    m.metallic = std::clamp(static_cast<float>(pbr.metallicFactor), 0.0f, 1.0f);
    m.roughness = std::clamp(static_cast<float>(pbr.roughnessFactor), 0.0f, 1.0f);
    float strength = 1;
    if (auto it = g.extensions.find("KHR_materials_emissive_strength"); it != g.extensions.end())
      if (it->second.Has("emissiveStrength")) strength = static_cast<float>(it->second.Get("emissiveStrength").GetNumberAsDouble());
    if (g.emissiveFactor.size() == 3)
      m.ke = RGB{static_cast<float>(g.emissiveFactor[0]), static_cast<float>(g.emissiveFactor[1]),
                 static_cast<float>(g.emissiveFactor[2])} * std::max(0.0f, strength);
    const std::string which = "material '" + m.name + "'";
    if (auto it = g.extensions.find("KHR_materials_ior"); it != g.extensions.end() && it->second.Has("ior")) {
      const double ior = it->second.Get("ior").GetNumberAsDouble();
      if (ior >= 1 && ior <= 3) m.ior = static_cast<float>(ior);
      else warn(which + ": KHR_materials_ior " + std::to_string(ior) + " is outside [1, 3]; 1.5 is used");
    }
    if (auto it = g.extensions.find("KHR_materials_transmission"); it != g.extensions.end()) {
      if (it->second.Has("transmissionFactor"))
        m.transmission = std::clamp(static_cast<float>(it->second.Get("transmissionFactor").GetNumberAsDouble()), 0.0f, 1.0f);
      if (it->second.Has("transmissionTexture"))
        warn(which + ": its transmissionTexture is left out; transmissionFactor holds everywhere");
    }
    // Whole transmission through a smooth dielectric is the `glass` material, a single direction (the `specular`
    // op's): at roughness 0.02 (alpha 4e-4) the lobe is narrower than a pixel of any usual view, and a microfacet
    // lobe that sharp only makes light sampling noisy. glTF tints at each crossing by the base colour, `glass` once
    // where light enters (Tf): the base colour squared is the same for light that enters and leaves.
    const bool smooth_glass = m.transmission >= 1 && m.metallic <= 0 && m.roughness <= 0.02f &&
                              pbr.metallicRoughnessTexture.index < 0 && pbr.baseColorTexture.index < 0;
    if (smooth_glass) {
      m.type = Material::Type::glass;
      m.tf = m.kd * m.kd;
      m.kd = {};
      m.transmission = 0;
    }
    std::string image_name;
    const tinygltf::Image* image = base_color_image(model, g, image_name);
    if (pbr.baseColorTexture.index >= 0) {
      std::optional<Texture> tex;
      if (image) tex = base_color_texture(*image, m.kd, image_name);
      if (tex) m.kd_map = static_cast<int32_t>(s.add_texture(std::move(*tex)));
      else warn(which + ": its base colour texture cannot be read (8-bit RGB or RGBA); the material stays flat");
      if (pbr.baseColorTexture.texCoord != 0) warn(which + ": a texture on TEXCOORD_" + std::to_string(pbr.baseColorTexture.texCoord) + " is read with TEXCOORD_0");
    }
    if (pbr.metallicRoughnessTexture.index >= 0) {
      std::string mr_name;
      const tinygltf::Image* mr = texture_image(model, pbr.metallicRoughnessTexture.index, mr_name);
      std::optional<Texture> metallic, roughness;
      if (mr) metallic = channel_texture(*mr, 2, mr_name + " (metallic)"), roughness = channel_texture(*mr, 1, mr_name + " (roughness)");
      if (metallic && roughness) {
        m.metallic_map = static_cast<int32_t>(s.add_texture(std::move(*metallic)));
        m.roughness_map = static_cast<int32_t>(s.add_texture(std::move(*roughness)));
      } else {
        warn(which + ": its metallicRoughnessTexture cannot be read (8-bit RGB or RGBA); its factors hold everywhere");
      }
      if (pbr.metallicRoughnessTexture.texCoord != 0) warn(which + ": a texture on TEXCOORD_" + std::to_string(pbr.metallicRoughnessTexture.texCoord) + " is read with TEXCOORD_0");
    }
    if (g.normalTexture.index >= 0) {
      std::string normal_name;
      const tinygltf::Image* normals = texture_image(model, g.normalTexture.index, normal_name);
      std::optional<Texture> tex;
      if (normals) tex = data_texture(*normals, normal_name);
      if (tex) {
        m.normal_map = static_cast<int32_t>(s.add_texture(std::move(*tex)));
        m.normal_scale = static_cast<float>(g.normalTexture.scale);
      } else {
        warn(which + ": its normalTexture cannot be read (8-bit RGB or RGBA); its surface stays smooth");
      }
      if (g.normalTexture.texCoord != 0) warn(which + ": a texture on TEXCOORD_" + std::to_string(g.normalTexture.texCoord) + " is read with TEXCOORD_0");
    }
    if (g.emissiveTexture.index >= 0 && m.emissive()) {
      std::string emission_name;
      const tinygltf::Image* glow = texture_image(model, g.emissiveTexture.index, emission_name);
      std::optional<Texture> tex;
      if (glow) tex = base_color_texture(*glow, RGB{1, 1, 1}, emission_name);  // sRGB colour, as base colour is
      if (tex) m.emission_map = static_cast<int32_t>(s.add_texture(std::move(*tex)));
      else warn(which + ": its emissiveTexture cannot be read (8-bit RGB or RGBA); emissiveFactor holds everywhere");
      if (g.emissiveTexture.texCoord != 0) warn(which + ": a texture on TEXCOORD_" + std::to_string(g.emissiveTexture.texCoord) + " is read with TEXCOORD_0");
    }
    if (g.occlusionTexture.index >= 0) warn(which + ": occlusionTexture is left out (a path tracer computes occlusion)");
    if (g.alphaMode == "MASK" || g.alphaMode == "BLEND") {
      // BLEND has no cut-out: the approximation is a cut-out at coverage one half (what lightfarm does with MTL
      // map_d), so leaves and fences are right and glass-like blending is not.
      if (g.alphaMode == "BLEND") warn(which + ": alphaMode BLEND is read as MASK with alphaCutoff 0.5");
      const float cutoff = g.alphaMode == "MASK" ? static_cast<float>(g.alphaCutoff) : 0.5f;
      const float factor = pbr.baseColorFactor.size() == 4 ? static_cast<float>(pbr.baseColorFactor[3]) : 1.0f;
      std::optional<Texture> cut;
      if (image) cut = coverage_texture(*image, factor, cutoff, image_name);
      if (cut) m.alpha_map = static_cast<int32_t>(s.add_texture(std::move(*cut)));
      else if (factor < cutoff) warn(which + ": its alpha " + std::to_string(factor) + " is below its cutoff, but without an RGBA base colour texture the surface stays whole");
    }
    s.add_material(std::move(m));
  }
  const auto fallback = s.add_material({"(default)", {0.5f, 0.5f, 0.5f}, {}});

  const AccessorReader read(model, where);
  const auto* lights = [&]() -> const tinygltf::Value* {
    auto it = model.extensions.find("KHR_lights_punctual");
    return it != model.extensions.end() && it->second.Has("lights") ? &it->second.Get("lights") : nullptr;
  }();
  bool has_sun = false;
  const Status status = for_each_node(model, where, [&](const tinygltf::Node& node, const Mat4& world, std::span<const int>) -> Status {
    if (auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end() && lights && it->second.Has("light")) {
      const int li = it->second.Get("light").GetNumberAsInt();
      if (li >= 0 && static_cast<size_t>(li) < lights->ArrayLen()) {
        const tinygltf::Value& light = lights->Get(li);
        const std::string type = light.Has("type") ? light.Get("type").Get<std::string>() : "";
        const std::string name = light.Has("name") ? light.Get("name").Get<std::string>() : "light" + std::to_string(li);
        RGB colour{1, 1, 1};
        if (light.Has("color") && light.Get("color").ArrayLen() == 3)
          colour = {static_cast<float>(light.Get("color").Get(0).GetNumberAsDouble()),
                    static_cast<float>(light.Get("color").Get(1).GetNumberAsDouble()),
                    static_cast<float>(light.Get("color").Get(2).GetNumberAsDouble())};
        // glTF's lights are photometric (candela, lux); lightfarm's radiometric (W/sr, W/m^2): 683 lm/W.
        const float photometric = light.Has("intensity") ? static_cast<float>(light.Get("intensity").GetNumberAsDouble()) : 1.0f;
        const RGB radiometric = colour * std::max(0.0f, photometric / 683.0f);
        const Vec3 towards = world.vector({0, 0, 1});  // a directional light shines along its node's -z
        if (type == "point") {
          s.add_point_light(world.point({0, 0, 0}), radiometric);
        } else if (type == "spot" && length(world.vector({0, 0, -1})) > 0) {
          // A spot shines along its node's -z; its cone angles (radians) default to 0 and pi / 4.
          PointLight spot{world.point({0, 0, 0}), radiometric};
          spot.axis = normalize(world.vector({0, 0, -1}));
          double inner = 0, outer = kPi / 4;
          if (light.Has("spot")) {
            const tinygltf::Value& cone = light.Get("spot");
            if (cone.Has("innerConeAngle")) inner = cone.Get("innerConeAngle").GetNumberAsDouble();
            if (cone.Has("outerConeAngle")) outer = cone.Get("outerConeAngle").GetNumberAsDouble();
          }
          outer = std::clamp(outer, 1e-4, static_cast<double>(kPi) / 2);
          inner = std::clamp(inner, 0.0, outer);
          spot.cos_outer = static_cast<float>(std::cos(outer));
          spot.cos_inner = static_cast<float>(std::cos(inner));
          s.add_point_light(spot);
        } else if (type == "directional" && !has_sun && length(towards) > 0) {
          // The sun of the scene, 0.526 degrees across (glTF gives a directional light no size).
          Environment sky;
          Sun sun;
          sun.direction = normalize(towards);
          sun.irradiance = radiometric;
          sky.set_sun(sun);
          s.set_environment(std::move(sky));
          has_sun = true;
        } else if (type == "directional") {
          warn("light '" + name + "' (directional): only the first directional light is read, as the scene's sun");
        } else {
          warn("light '" + name + "' (" + type + ") is not supported; point, spot and directional lights are read");
        }
      }
    }
    if (node.mesh >= 0) {
      if (static_cast<size_t>(node.mesh) >= model.meshes.size())
        return make_error(where + ": node '" + node.name + "' names a mesh that does not exist");
      const tinygltf::Mesh& mesh = model.meshes[static_cast<size_t>(node.mesh)];
      const bool mirrored = world.determinant3() < 0;  // a mirroring transform turns the winding around
      const NormalTransform normal_of(world);
      for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
        const tinygltf::Primitive& prim = mesh.primitives[pi];
        const std::string what = "mesh '" + mesh.name + "' primitive " + std::to_string(pi);
        if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
          warn(what + ": mode " + std::to_string(prim.mode) + " is not triangles; left out");
          continue;
        }
        auto find = [&](const char* key) {
          auto it = prim.attributes.find(key);
          return it == prim.attributes.end() ? -1 : it->second;
        };
        auto positions = read.floats(find("POSITION"), 3, what + " positions");
        if (!positions) return positions.error();
        const size_t vertices = positions->size() / 3;
        std::vector<float> normals, uvs, tangents;
        if (find("NORMAL") >= 0) {
          auto n = read.floats(find("NORMAL"), 3, what + " normals");
          if (!n) return n.error();
          if (n->size() == positions->size()) normals = std::move(*n);
        }
        if (find("TEXCOORD_0") >= 0) {
          auto t = read.floats(find("TEXCOORD_0"), 2, what + " texture coordinates");
          if (!t) return t.error();
          if (t->size() / 2 == vertices) uvs = std::move(*t);
        }
        // Tangents matter only where a normal map turns the normal along them.
        const bool normal_mapped = prim.material >= 0 && static_cast<size_t>(prim.material) < model.materials.size() &&
                                   s.material(static_cast<uint32_t>(prim.material)).normal_map >= 0;
        if (find("TANGENT") >= 0 && normal_mapped && !normals.empty()) {
          auto t = read.floats(find("TANGENT"), 4, what + " tangents");
          if (!t) return t.error();
          if (t->size() / 4 == vertices) tangents = std::move(*t);
        }
        std::vector<uint32_t> order;
        if (prim.indices >= 0) {
          auto i = read.indices(prim.indices, vertices, what + " indices");
          if (!i) return i.error();
          order = std::move(*i);
        } else {
          order.resize(vertices);
          for (uint32_t v = 0; v < vertices; ++v) order[v] = v;
        }
        const uint32_t material = prim.material >= 0 && static_cast<size_t>(prim.material) < model.materials.size()
                                      ? static_cast<uint32_t>(prim.material)
                                      : fallback;
        for (size_t f = 0; f + 2 < order.size(); f += 3) {
          Vec3 p[3], vn[3];
          Vec2 vt[3];
          CornerTangent tn[3];
          for (int c = 0; c < 3; ++c) {
            const size_t v = order[f + static_cast<size_t>(mirrored ? 2 - c : c)];
            p[c] = world.point({(*positions)[3 * v], (*positions)[3 * v + 1], (*positions)[3 * v + 2]});
            if (!normals.empty()) vn[c] = normal_of({normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]});
            // glTF's texture coordinates start at the image's top left; the scene's, as OBJ's, at its bottom left.
            if (!uvs.empty()) {
              const Vec2 t = material < uv_transforms.size() ? uv_transforms[material].apply(uvs[2 * v], uvs[2 * v + 1])
                                                             : Vec2{uvs[2 * v], uvs[2 * v + 1]};
              vt[c] = {t.u, 1.0f - t.v};
            }
            // A tangent turns with the node as surface directions do; a mirroring transform flips the bitangent's
            // side (cross(n, t) of the mirrored pair points the other way).
            if (!tangents.empty())
              tn[c] = {world.vector({tangents[4 * v], tangents[4 * v + 1], tangents[4 * v + 2]}),
                       (tangents[4 * v + 3] < 0) != mirrored ? -1.0f : 1.0f};
          }
          s.add_triangle(p[0], p[1], p[2], material,
                         {normals.empty() ? nullptr : vn, uvs.empty() ? nullptr : vt, tangents.empty() ? nullptr : tn});
        }
      }
    }
    return Ok{};
  });
  if (!status) return status.error();
  if (s.triangle_count() == 0) return make_error(where + ": its default scene holds no triangles");
  return s;
}

}  // namespace lf
