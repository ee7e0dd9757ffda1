// The scene structure: triangles, materials, lights and the light distribution. Built-in scenes are in
// builtin_scenes.cpp, OBJ/MTL loading in obj_scene.cpp, the lights a script adds in script_lights.cpp.
#include "render/scene/scene.hpp"
#include "render/scene/scene_image.hpp"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>

namespace lf {

Bounds bounds_of(std::span<const Vec3> points) {
  Vec3 lo = points[0], hi = points[0];
  for (const auto& v : points) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  return Bounds{lo, hi};
}

uint32_t Scene::add_material(Material m) {
  materials_.push_back(std::move(m));
  return static_cast<uint32_t>(materials_.size() - 1);
}

void Scene::add_triangle(Vec3 a, Vec3 b, Vec3 c, uint32_t material, CornerAttributes extra) {
  Vec3 n = cross(b - a, c - a);
  float len = length(n);
  if (!(len > 0)) return;  // degenerate: nothing to hit, nothing to emit
  n = n / len;
  // Corner attributes are all-or-none per scene: the first triangle that has them gives the earlier ones theirs
  // (the face normal; no uv, a NaN, which leaves the face untextured), and later triangles without them the same.
  const size_t before = triangles_.size();
  if (extra.normals || !corner_normals_.empty()) {
    if (corner_normals_.empty()) {
      corner_normals_.reserve(3 * (before + 1));
      for (size_t t = 0; t < before; ++t) corner_normals_.insert(corner_normals_.end(), 3, normals_[t]);
    }
    for (int k = 0; k < 3; ++k) {
      Vec3 vn = extra.normals ? extra.normals[k] : n;
      const float l = length(vn);
      // A zero or non-finite normal says nothing: use the face's.
      vn = (l > 0 && std::isfinite(l)) ? vn / l : n;
      corner_normals_.push_back(vn);
    }
  }
  if (extra.uvs || !corner_uvs_.empty()) {
    constexpr Vec2 kNoUv{std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::quiet_NaN()};
    if (corner_uvs_.empty()) corner_uvs_.assign(3 * before, kNoUv);
    for (int k = 0; k < 3; ++k) corner_uvs_.push_back(extra.uvs ? extra.uvs[k] : kNoUv);
  }
  if (extra.tangents || !corner_tangents_.empty()) {
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    const CornerTangent none{{kNaN, kNaN, kNaN}, 1};
    if (corner_tangents_.empty()) corner_tangents_.assign(3 * before, none);
    for (int k = 0; k < 3; ++k) corner_tangents_.push_back(extra.tangents ? extra.tangents[k] : none);
  }
  auto base = static_cast<uint32_t>(vertices_.size());
  vertices_.push_back(a);
  vertices_.push_back(b);
  vertices_.push_back(c);
  triangles_.push_back({base, base + 1, base + 2});
  material_of_.push_back(material);
  normals_.push_back(n);
  areas_.push_back(0.5f * len);
  view_owned_arrays();
}

void Scene::view_owned_arrays() {
  vertex_view_ = vertices_;
  triangle_view_ = triangles_;
  material_view_ = material_of_;
  normal_view_ = normals_;
  area_view_ = areas_;
  light_pdf_view_ = triangle_light_pdf_;
  corner_normal_view_ = corner_normals_;
  corner_uv_view_ = corner_uvs_;
  corner_tangent_view_ = corner_tangents_;
}

void Scene::restore_corners(std::vector<Vec3> normals, std::vector<Vec2> uvs, std::vector<CornerTangent> tangents) {
  corner_normals_ = std::move(normals);
  corner_uvs_ = std::move(uvs);
  corner_tangents_ = std::move(tangents);
  view_owned_arrays();
}

uint32_t Scene::add_texture(Texture t) {
  t.texels = t.owned;
  textures_.push_back(std::move(t));
  return static_cast<uint32_t>(textures_.size() - 1);
}

void Scene::add_sphere(Vec3 center, float radius, int subdivisions, uint32_t material, bool smooth) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<Vec3> v{{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                      {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p = normalize(p);
  for (int level = 0; level < subdivisions; ++level) {
    std::vector<std::array<int, 3>> next;
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back(normalize((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]) * 0.5f));
      return midpoint[key] = static_cast<int>(v.size() - 1);
    };
    for (const auto& tri : f) {
      int a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), c = mid(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = std::move(next);
  }
  for (const auto& tri : f) {
    const Vec3 normals[3] = {v[static_cast<size_t>(tri[0])], v[static_cast<size_t>(tri[1])], v[static_cast<size_t>(tri[2])]};
    add_triangle(center + normals[0] * radius, center + normals[1] * radius, center + normals[2] * radius, material,
                 smooth ? CornerAttributes{normals, nullptr} : CornerAttributes{});
  }
}

void Scene::add_quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint32_t material) {
  add_triangle(a, b, c, material);
  add_triangle(a, c, d, material);
}

Status Scene::finalize(const std::string& what) {
  if (triangles_.empty()) return make_error(what + ": the scene has no triangles");
  bounds_ = bounds_of(vertices_);
  epsilon_ = std::max(1e-4f * bounds_.diagonal(), 1e-6f);

  view_owned_arrays();
  if (auto st = settle_lights(what); !st) return st;
  settle_normal_maps();
  return Ok{};
}

Status Scene::settle_lights(const std::string& what) {
  emitters_.clear();
  emitter_cdf_.clear();
  emitter_pdf_.clear();
  double total = 0;
  std::vector<double> power;  // emitted flux: pi * area * Le for triangles, 4 pi I for points
  for (uint32_t t = 0; t < triangle_count(); ++t) {
    const Material& m = materials_[material_view_[t]];
    if (!m.emissive()) continue;
    emitters_.push_back(t);
    power.push_back(emitted_power(t));
    total += power.back();
  }
  for (const auto& p : point_lights_) {
    power.push_back(p.power());
    total += power.back();
  }
  const bool environment_emits = environment_ && environment_->emits();
  if ((power.empty() || !(total > 0)) && !environment_emits) {
    std::string hint;
    for (const auto& name : ambient_only_) hint += (hint.empty() ? "" : ", ") + name;
    if (!hint.empty()) hint = "; " + hint + " ha" + (ambient_only_.size() > 1 ? "ve" : "s") + " Ka but no Ke: did you mean Ke?";
    return make_error(what + ": the scene has no light (no material with Ke > 0, and the script adds no light, environment or sun)" + hint);
  }
  if (!(total > 0)) {  // only the environment lights the scene
    power.clear();
    emitters_.clear();
  }
  double running = 0;
  for (double p : power) {
    running += p;
    emitter_cdf_.push_back(static_cast<float>(running / total));
    emitter_pdf_.push_back(static_cast<float>(p / total));
  }
  if (!power.empty()) emitter_cdf_.back() = 1.0f;
  triangle_light_pdf_.assign(triangle_count(), 0.0f);
  for (size_t i = 0; i < emitters_.size(); ++i) triangle_light_pdf_[emitters_[i]] = emitter_pdf_[i];
  light_pdf_view_ = triangle_light_pdf_;
  light_tree_ = std::make_shared<const LightTree>(*this);
  emitter_cutouts_ = std::make_shared<const EmitterCutouts>(*this);
  settle_environment_share();
  return Ok{};
}

Result<std::shared_ptr<const Scene>> Scene::with_material_changes(const Value::Array& changes,
                                                                  const std::string& what) const {
  std::shared_ptr<Scene> changed(new Scene(*this));
  // A scene of its own arrays: the copy's views and texels point at its own copies, not at this scene's.
  if (!storage_) {
    changed->view_owned_arrays();
    for (Texture& t : changed->textures_)
      if (!t.owned.empty()) t.texels = t.owned;
  }
  if (auto st = changed->apply_material_overrides(changes); !st) return make_error(what + ": " + st.error().message);
  if (auto st = changed->apply_light_changes(changes); !st) return make_error(what + ": " + st.error().message);
  if (auto st = changed->settle_lights(what); !st) return st.error();
  return std::shared_ptr<const Scene>(std::move(changed));
}

void Scene::settle_normal_maps() {
  has_normal_maps_ = false;
  for (const Material& m : materials_) has_normal_maps_ = has_normal_maps_ || m.normal_map >= 0;
  has_normal_maps_ = has_normal_maps_ && has_uvs();
}

void Scene::settle_environment_share() {
  const bool others = !emitter_cdf_.empty();
  environment_share_ = environment_ && environment_->emits() ? (others ? 0.5f : 1.0f) : 0.0f;
}

size_t Scene::emitter_index_of(uint32_t t) const {
  // emitters_ lists triangles in increasing order (finalize() and the scene image both keep it so).
  return static_cast<size_t>(std::lower_bound(emitters_.begin(), emitters_.end(), t) - emitters_.begin());
}

size_t Scene::pick_emitter(float u, float& probability, float* remainder) const {
  auto it = std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u);
  size_t i = std::min(static_cast<size_t>(it - emitter_cdf_.begin()), emitter_cdf_.size() - 1);
  probability = emitter_pdf_[i];
  if (remainder) {
    const float low = i > 0 ? emitter_cdf_[i - 1] : 0.0f, width = emitter_cdf_[i] - low;
    *remainder = width > 0 ? std::clamp((u - low) / width, 0.0f, 0x1.fffffep-1f) : 0.0f;
  }
  return i;
}

Result<Scene> Scene::load(const SceneSpec& spec) {
  const bool file = !spec.file.empty();
  if (!spec.cache.empty())
    return load_shared_scene(spec.cache, spec.hash, file ? "scene file '" + spec.file + "'" : "the shipped scene");
  auto s = file ? load_file_unlit(spec.file) : builtin_unlit(spec.builtin.empty() ? "cornell" : spec.builtin);
  if (!s) return s;
  if (auto st = s->add_script_shapes(spec.shapes); !st) return st.error();
  if (auto st = s->apply_material_overrides(spec.materials); !st) return st.error();
  if (auto st = s->add_script_lights(spec.lights); !st) return st.error();
  const std::string what = file ? "scene file '" + spec.file + "'" : "built-in scene '" + spec.builtin + "'";
  if (auto st = s->finalize(what); !st) return st.error();
  return s;
}

}  // namespace lf
