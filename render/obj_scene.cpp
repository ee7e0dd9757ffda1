// OBJ + MTL scenes through tinyobjloader, and how an MTL material becomes one of ours.
#include <tiny_obj_loader.h>

#include <algorithm>
#include <filesystem>
#include <cctype>
#include <map>
#include <set>
#include <sstream>
#include <fstream>

#include "render/scene.hpp"

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
    const bool ambient = m.ambient[0] > 0 || m.ambient[1] > 0 || m.ambient[2] > 0;
    const bool emits = m.emission[0] > 0 || m.emission[1] > 0 || m.emission[2] > 0;
    if (ambient && !emits) s.ambient_only_.push_back(m.name);
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

Result<ObjCatalogue> Scene::catalogue_obj(const std::string& path) {
  std::ifstream obj(path);
  if (!obj) return make_error("scene file '" + path + "' not found");
  const auto dir = std::filesystem::path(path).parent_path();
  ObjCatalogue out;
  std::set<std::string> known, reported;
  std::vector<std::pair<int, std::string>> uses;  // usemtl lines, checked once every mtllib is read
  std::string line;
  for (int number = 1; std::getline(obj, line); ++number) {
    const bool mtllib = line.rfind("mtllib", 0) == 0, usemtl = line.rfind("usemtl", 0) == 0;
    if ((!mtllib && !usemtl) || line.size() < 7 || !std::isspace(static_cast<unsigned char>(line[6]))) continue;
    std::istringstream words(line.substr(7));
    std::string word;
    if (usemtl) {
      if (words >> word) uses.emplace_back(number, word);
      continue;
    }
    while (words >> word) {
      std::ifstream mtl(dir / word);
      if (!mtl) {
        out.warnings.push_back(path + ":" + std::to_string(number) + ": material library '" + word +
                               "' not found beside the OBJ; its faces get a grey default");
        continue;
      }
      std::map<std::string, int> index;
      std::vector<tinyobj::material_t> materials;
      std::string warning, error;
      tinyobj::LoadMtl(&index, &materials, &mtl, &warning, &error);
      for (const auto& m : materials) {
        out.material_names.push_back(m.name);
        known.insert(m.name);
        for (const auto& [slot, name] : {std::pair{"map_Kd", &m.diffuse_texname}, {"map_Ks", &m.specular_texname},
                                         {"map_d", &m.alpha_texname}, {"map_Ke", &m.emissive_texname}})
          if (!name->empty()) {
            std::error_code ec;
            out.textures.push_back({m.name, slot, *name, std::filesystem::is_regular_file(dir / *name, ec)});
          }
      }
    }
  }
  for (const auto& [number, name] : uses)
    if (!known.count(name) && reported.insert(name).second)
      out.warnings.push_back(path + ":" + std::to_string(number) + ": usemtl '" + name +
                             "' names no material of its libraries; those faces get a grey default");
  return out;
}

}  // namespace lf
