#include "render/scene.hpp"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace lf {

Material material_from_mtl(std::string name, RGB kd, RGB ks, RGB ke, float ns, float ni, int illum) {
  Material m{std::move(name), kd, ke};
  m.ks = ks;
  m.ns = ns;
  m.ior = ni > 1.0f ? ni : 1.5f;
  if (illum == 3 || illum == 5) {
    m.type = Material::Type::mirror;
    if (is_black(m.ks)) m.ks = {1, 1, 1};
    m.kd = {};
  } else if (illum == 4 || illum == 6 || illum == 7 || illum == 9) {
    m.type = Material::Type::glass;
    m.kd = {};
  } else if (illum == 2 && !is_black(ks) && ns > 0) {
    m.type = Material::Type::glossy;
    // Per channel kd + ks <= 1.
    const RGB sum = m.kd + m.ks;
    const float peak = std::max({sum.x, sum.y, sum.z});
    if (peak > 1.0f) {
      m.kd *= 1.0f / peak;
      m.ks *= 1.0f / peak;
    }
  } else {
    m.ks = {};
  }
  return m;
}

uint32_t Scene::add_material(Material m) {
  materials_.push_back(std::move(m));
  return static_cast<uint32_t>(materials_.size() - 1);
}

void Scene::add_triangle(Vec3 a, Vec3 b, Vec3 c, uint32_t material) {
  Vec3 n = cross(b - a, c - a);
  float len = length(n);
  if (!(len > 0)) return;  // degenerate: nothing to hit, nothing to emit
  auto base = static_cast<uint32_t>(vertices_.size());
  vertices_.push_back(a);
  vertices_.push_back(b);
  vertices_.push_back(c);
  triangles_.push_back({base, base + 1, base + 2});
  material_of_.push_back(material);
  normals_.push_back(n / len);
  areas_.push_back(0.5f * len);
}

void Scene::add_sphere(Vec3 center, float radius, int subdivisions, uint32_t material) {
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
  for (const auto& tri : f)
    add_triangle(center + v[static_cast<size_t>(tri[0])] * radius, center + v[static_cast<size_t>(tri[1])] * radius,
                 center + v[static_cast<size_t>(tri[2])] * radius, material);
}

void Scene::add_quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, uint32_t material) {
  add_triangle(a, b, c, material);
  add_triangle(a, c, d, material);
}

Status Scene::finalize(const std::string& what) {
  if (triangles_.empty()) return make_error(what + ": the scene has no triangles");
  Vec3 lo = vertices_[0], hi = vertices_[0];
  for (const auto& v : vertices_) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
  epsilon_ = std::max(1e-4f * length(hi - lo), 1e-6f);

  emitters_.clear();
  emitter_cdf_.clear();
  emitter_pdf_.clear();
  double total = 0;
  std::vector<double> power;  // emitted flux: pi * area * Le for triangles, 4 pi I for points
  for (uint32_t t = 0; t < triangles_.size(); ++t) {
    const Material& m = materials_[material_of_[t]];
    if (!m.emissive()) continue;
    emitters_.push_back(t);
    power.push_back(static_cast<double>(areas_[t]) * average(m.ke) * kPi);
    total += power.back();
  }
  for (const auto& p : point_lights_) {
    power.push_back(4.0 * kPi * average(p.intensity));
    total += power.back();
  }
  if (power.empty() || !(total > 0))
    return make_error(what + ": the scene has no light (no material with Ke > 0, and the script adds none)");
  double running = 0;
  for (double p : power) {
    running += p;
    emitter_cdf_.push_back(static_cast<float>(running / total));
    emitter_pdf_.push_back(static_cast<float>(p / total));
  }
  emitter_cdf_.back() = 1.0f;
  triangle_light_pdf_.assign(triangles_.size(), 0.0f);
  for (size_t i = 0; i < emitters_.size(); ++i) triangle_light_pdf_[emitters_[i]] = emitter_pdf_[i];
  return Ok{};
}

size_t Scene::pick_emitter(float u, float& probability) const {
  auto it = std::upper_bound(emitter_cdf_.begin(), emitter_cdf_.end(), u);
  size_t i = std::min(static_cast<size_t>(it - emitter_cdf_.begin()), emitter_cdf_.size() - 1);
  probability = emitter_pdf_[i];
  return i;
}

// The Cornell box as published by the Cornell Program of Computer Graphics (measured geometry, millimetres),
// with the usual RGB approximations of its measured reflectances and light.
// `glass`: the Cornell box with a glass sphere where the short block stood and a mirror for the tall block, for
// caustics on the floor.
static Scene cornell_box(bool glass) {
  Scene s;
  auto white = s.add_material({"white", {0.725f, 0.71f, 0.68f}, {}});
  auto red = s.add_material({"red", {0.63f, 0.065f, 0.05f}, {}});
  auto green = s.add_material({"green", {0.14f, 0.45f, 0.091f}, {}});
  auto light = s.add_material({"light", {0.78f, 0.78f, 0.78f}, {17.0f, 12.0f, 4.0f}});

  s.add_quad({552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}, white);                     // floor
  // The ceiling has a hole where the light sits (as the real box does): a light just below an unbroken ceiling
  // z-fights with it at camera distance in float precision.
  auto ceiling = [&](float x0, float x1, float z0, float z1) {
    s.add_quad({x1, 548.8f, z0}, {x1, 548.8f, z1}, {x0, 548.8f, z1}, {x0, 548.8f, z0}, white);
  };
  ceiling(0, 556.0f, 0, 227.0f);
  ceiling(0, 556.0f, 332.0f, 559.2f);
  ceiling(0, 213.0f, 227.0f, 332.0f);
  ceiling(343.0f, 556.0f, 227.0f, 332.0f);
  s.add_quad({549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}, white);  // back
  s.add_quad({0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}, green);                      // right
  s.add_quad({552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}, red);    // left
  // The light hangs 0.1 mm below the ceiling so the two never share a plane; it faces down.
  s.add_quad({343.0f, 548.7f, 227.0f}, {343.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 332.0f},
             {213.0f, 548.7f, 227.0f}, light);

  const float short_block[5][4][3] = {
      {{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}},
      {{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}},
      {{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}},
      {{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}},
      {{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}};
  const float tall_block[5][4][3] = {
      {{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}},
      {{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}},
      {{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}},
      {{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}},
      {{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}};
  const uint32_t tall_material =
      glass ? s.add_material(material_from_mtl("mirror", {}, {0.95f, 0.95f, 0.95f}, {}, 0, 1, 3)) : white;
  for (const auto* block : {short_block, tall_block}) {
    if (glass && block == short_block) continue;
    for (int f = 0; f < 5; ++f) {
      auto v = [&](int i) { return Vec3{block[f][i][0], block[f][i][1], block[f][i][2]}; };
      s.add_quad(v(0), v(1), v(2), v(3), block == tall_block ? tall_material : white);
    }
  }
  if (glass) {
    const uint32_t sphere = s.add_material(material_from_mtl("glass", {}, {}, {}, 0, 1.5f, 7));
    s.add_sphere({185.0f, 90.0f, 169.0f}, 90.0f, 4, sphere);
  }
  return s;
}

// A furnished room (metres, 6 x 3 x 5) for radiosity: walls, floor and ceiling facing in, a ceiling panel light,
// a table and two chairs, a sofa and a cabinet as boxes. Only quads, so that radiosity meshes it as authored.
static Scene furnished_room() {
  Scene s;
  const auto wall = s.add_material({"wall", {0.75f, 0.73f, 0.70f}, {}});
  const auto blue_wall = s.add_material({"blue wall", {0.30f, 0.42f, 0.65f}, {}});
  const auto floor = s.add_material({"floor", {0.55f, 0.42f, 0.30f}, {}});
  const auto wood = s.add_material({"wood", {0.45f, 0.30f, 0.18f}, {}});
  const auto fabric = s.add_material({"fabric", {0.65f, 0.12f, 0.10f}, {}});
  const auto light = s.add_material({"panel", {0.8f, 0.8f, 0.8f}, {12.0f, 11.0f, 9.0f}});
  auto face = [&](Vec3 o, Vec3 u, Vec3 v, uint32_t m) { s.add_quad(o, o + u, o + u + v, o + v, m); };
  // Outward faces of an axis-aligned box; boxes standing on the floor leave out their bottom.
  auto box = [&](Vec3 lo, Vec3 hi, uint32_t m) {
    const Vec3 d = hi - lo;
    face({hi.x, lo.y, lo.z}, {0, d.y, 0}, {0, 0, d.z}, m);
    face(lo, {0, 0, d.z}, {0, d.y, 0}, m);
    face({lo.x, hi.y, lo.z}, {0, 0, d.z}, {d.x, 0, 0}, m);
    if (lo.y > 0) face(lo, {d.x, 0, 0}, {0, 0, d.z}, m);
    face({lo.x, lo.y, hi.z}, {d.x, 0, 0}, {0, d.y, 0}, m);
    face(lo, {0, d.y, 0}, {d.x, 0, 0}, m);
  };
  face({0, 0, 0}, {0, 0, 5}, {6, 0, 0}, floor);
  face({0, 3, 0}, {6, 0, 0}, {0, 0, 5}, wall);
  face({0, 0, 0}, {0, 3, 0}, {0, 0, 5}, wall);
  face({6, 0, 0}, {0, 0, 5}, {0, 3, 0}, blue_wall);
  face({0, 0, 0}, {6, 0, 0}, {0, 3, 0}, wall);
  face({0, 0, 5}, {0, 3, 0}, {6, 0, 0}, wall);
  face({2.4f, 2.99f, 2.0f}, {1.2f, 0, 0}, {0, 0, 1.0f}, light);
  auto table = [&](float x, float z, float w, float d, float h) {
    box({x, h - 0.05f, z}, {x + w, h, z + d}, wood);
    for (float lx : {x + 0.03f, x + w - 0.09f})
      for (float lz : {z + 0.03f, z + d - 0.09f}) box({lx, 0, lz}, {lx + 0.06f, h - 0.05f, lz + 0.06f}, wood);
  };
  table(1.8f, 1.6f, 1.8f, 1.0f, 0.75f);
  for (float x : {2.0f, 3.0f}) {
    table(x, 2.9f, 0.45f, 0.45f, 0.47f);                         // seat on legs
    box({x, 0.47f, 3.3f}, {x + 0.45f, 1.0f, 3.35f}, wood);       // backrest
  }
  box({0.05f, 0, 1.2f}, {0.95f, 0.45f, 3.6f}, fabric);           // sofa
  box({0.05f, 0.45f, 1.2f}, {0.30f, 0.90f, 3.6f}, fabric);
  box({0.30f, 0.45f, 1.2f}, {0.95f, 0.65f, 1.4f}, fabric);
  box({0.30f, 0.45f, 3.4f}, {0.95f, 0.65f, 3.6f}, fabric);
  box({5.45f, 0, 0.8f}, {5.95f, 1.9f, 2.4f}, wood);              // cabinet
  box({4.2f, 0, 4.3f}, {5.6f, 0.5f, 4.9f}, wood);                // chest
  return s;
}

const std::vector<std::string>& Scene::builtin_names() {
  static const std::vector<std::string> names{"cornell", "cornell_glass", "room"};
  return names;
}

Result<Scene> Scene::builtin(const std::string& name) {
  auto s = builtin_unlit(name);
  if (!s) return s;
  if (auto st = s->finalize("built-in scene '" + name + "'"); !st) return st.error();
  return s;
}

Result<Scene> Scene::builtin_unlit(const std::string& name) {
  Scene s;
  if (name == "cornell" || name == "cornell_glass") {
    s = cornell_box(name == "cornell_glass");
  } else if (name == "room") {
    s = furnished_room();
  } else {
    std::string known;
    for (const auto& n : builtin_names()) known += (known.empty() ? "" : ", ") + n;
    return make_error("unknown built-in scene '" + name + "' (built-in scenes: " + known + ")");
  }
  return s;
}

Result<Scene> Scene::load_obj(const std::string& path) {
  auto s = load_obj_unlit(path);
  if (!s) return s;
  if (auto st = s->finalize("scene file '" + path + "'"); !st) return st.error();
  return s;
}

Result<Scene> Scene::load_obj_unlit(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return make_error("scene file '" + path + "' not found");
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  config.mtl_search_path = std::filesystem::path(path).parent_path().string();
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path, config)) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    return make_error("cannot read scene file '" + path + "': " + (why.empty() ? "parse error" : why));
  }
  const auto& attrib = reader.GetAttrib();
  const auto& materials = reader.GetMaterials();
  Scene s;
  for (const auto& m : materials) {
    s.add_material(material_from_mtl(m.name, {m.diffuse[0], m.diffuse[1], m.diffuse[2]},
                                     {m.specular[0], m.specular[1], m.specular[2]},
                                     {m.emission[0], m.emission[1], m.emission[2]}, m.shininess, m.ior, m.illum));
  }
  // Faces without a material get a neutral grey, as most renderers do.
  const auto fallback = s.add_material({"(default)", {0.5f, 0.5f, 0.5f}, {}});
  const size_t vertex_count = attrib.vertices.size() / 3;
  for (const auto& shape : reader.GetShapes()) {
    const auto& mesh = shape.mesh;
    size_t index = 0;
    for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      const size_t corners = mesh.num_face_vertices[f];
      if (corners != 3) {
        index += corners;
        continue;
      }
      Vec3 p[3];
      bool valid = true;
      for (size_t c = 0; c < 3; ++c) {
        int vi = mesh.indices[index + c].vertex_index;
        if (vi < 0 || static_cast<size_t>(vi) >= vertex_count) {
          valid = false;
          break;
        }
        p[c] = {attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]};
      }
      index += 3;
      if (!valid) return make_error("scene file '" + path + "': a face refers to a vertex that does not exist");
      int mid = f < mesh.material_ids.size() ? mesh.material_ids[f] : -1;
      uint32_t material = (mid >= 0 && static_cast<size_t>(mid) < materials.size()) ? static_cast<uint32_t>(mid)
                                                                                      : fallback;
      s.add_triangle(p[0], p[1], p[2], material);
    }
  }
  return s;
}

Result<Scene> Scene::load(const SceneSpec& spec) {
  const bool file = !spec.file.empty();
  auto s = file ? load_obj_unlit(spec.file) : builtin_unlit(spec.builtin.empty() ? "cornell" : spec.builtin);
  if (!s) return s;
  if (auto st = s->add_script_lights(spec.lights); !st) return st.error();
  const std::string what = file ? "scene file '" + spec.file + "'" : "built-in scene '" + spec.builtin + "'";
  if (auto st = s->finalize(what); !st) return st.error();
  return s;
}

static bool vec3_of(const Value* v, Vec3& out) {
  if (!v || !v->is_array() || v->as_array().size() != 3) return false;
  for (const auto& e : v->as_array())
    if (!e.is_number()) return false;
  const auto& a = v->as_array();
  out = {static_cast<float>(a[0].as_double()), static_cast<float>(a[1].as_double()), static_cast<float>(a[2].as_double())};
  return true;
}

Status Scene::add_script_lights(const Value::Array& lights) {
  for (size_t i = 0; i < lights.size(); ++i) {
    const Value& l = lights[i];
    const std::string which = "light " + std::to_string(i + 1);
    Vec3 colour;
    if (const Value* q = l.find("quad")) {
      if (!vec3_of(l.find("radiance"), colour)) return make_error(which + ": radiance must be {r, g, b}");
      Vec3 c[4];
      if (!q->is_array() || q->as_array().size() != 4) return make_error(which + ": quad needs 4 corners");
      for (int k = 0; k < 4; ++k)
        if (!vec3_of(&q->as_array()[static_cast<size_t>(k)], c[k])) return make_error(which + ": a corner is not {x, y, z}");
      add_quad(c[0], c[1], c[2], c[3], add_material({"light (script)", {}, colour}));
    } else if (const Value* sph = l.find("sphere")) {
      Vec3 centre;
      const Value* r = l.find("radius");
      if (!vec3_of(sph, centre) || !r || !r->is_number() || !(r->as_double() > 0))
        return make_error(which + ": sphere needs a centre {x, y, z} and a radius > 0");
      if (!vec3_of(l.find("radiance"), colour)) return make_error(which + ": radiance must be {r, g, b}");
      add_sphere(centre, static_cast<float>(r->as_double()), 3, add_material({"light (script)", {}, colour}));
    } else if (const Value* p = l.find("point")) {
      Vec3 at;
      if (!vec3_of(p, at)) return make_error(which + ": point must be {x, y, z}");
      if (!vec3_of(l.find("intensity"), colour)) return make_error(which + ": intensity must be {r, g, b}");
      add_point_light(at, colour);
    } else {
      return make_error(which + ": give quad, sphere or point");
    }
  }
  return Ok{};
}

}  // namespace lf
