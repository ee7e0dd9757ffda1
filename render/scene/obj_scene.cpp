// OBJ + MTL scenes through tinyobjloader, and how an MTL material becomes one of ours.
#include <tiny_obj_loader.h>

#include <algorithm>
#include <filesystem>
#include <cctype>
#include <map>
#include <set>
#include <sstream>
#include <fstream>

#include "core/log.hpp"
#include "render/images/image.hpp"
#include "render/scene/scene.hpp"

namespace lf {

Material material_from_mtl(std::string name, RGB kd, RGB ks, RGB ke, float ns, float ni, int illum, RGB tf) {
  Material m{std::move(name), kd, ke};
  m.ks = ks;
  m.ns = ns;
  m.ior = ni > 1.0f ? ni : 1.5f;
  // Per channel kd + ks <= 1.
  auto cap = [&] {
    const RGB sum = m.kd + m.ks;
    const float peak = std::max({sum.x, sum.y, sum.z});
    if (peak > 1.0f) {
      m.kd *= 1.0f / peak;
      m.ks *= 1.0f / peak;
    }
  };
  if (illum == 3 && !is_black(kd) && !is_black(ks)) {
    // "Reflection on, ray trace on": Kd, the highlight Ks^Ns and a mirror reflection Ks. Ks is one specular
    // reflectance, so a lobe and the mirror share it (half each) rather than each taking all of it.
    cap();
    if (ns > 0) {
      m.type = Material::Type::glossy;
      m.kr = m.ks * 0.5f;
      m.ks = m.ks * 0.5f;
    } else {
      m.kr = m.ks;
      m.ks = {};
    }
  } else if (illum == 3 || illum == 5) {
    m.type = Material::Type::mirror;
    if (is_black(m.ks)) m.ks = {1, 1, 1};
    m.kd = {};
  } else if (illum == 4 || illum == 6 || illum == 7 || illum == 9) {
    m.type = Material::Type::glass;
    m.kd = {};
    // tinyobjloader reads a missing Tf as 0 0 0; a glass that keeps nothing of what enters is not what it means.
    if (!is_black(tf)) m.tf = {std::min(tf.x, 1.0f), std::min(tf.y, 1.0f), std::min(tf.z, 1.0f)};
  } else if (illum == 2 && !is_black(ks) && ns > 0) {
    m.type = Material::Type::glossy;
    cap();
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
  return from_obj_reader(reader, path, config.mtl_search_path);
}

Result<Scene> Scene::parse_obj_unlit(const std::string& obj_text, const std::string& mtl_text,
                                     const std::string& label) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(obj_text, mtl_text, config)) {
    std::string why = reader.Error();
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    return make_error("cannot read scene file '" + label + "': " + (why.empty() ? "parse error" : why));
  }
  return from_obj_reader(reader, label, "");
}

namespace {

// Whether every pixel's colour channels are equal (one or two channels, grey and alpha, always are).
bool is_grey(const Texels& t, size_t pixels) {
  const size_t c = static_cast<size_t>(t.channels);
  if (c < 3) return true;
  for (size_t i = 0; i < pixels; ++i) {
    const uint8_t* px = &t.bytes[i * c];
    if (px[0] != px[1] || px[1] != px[2]) return false;
  }
  return true;
}

// MTL's PBR extension (Pr, Pm; Blender's exporter writes them): glTF's metal-roughness model with Kd (and map_Kd) as
// the base colour, in place of the illum model's lobes. tinyobjloader reads an absent Pr or Pm as 0, so a material
// with both 0 and no maps stays the illum model's; glass stays glass (the extension has no transmission).
void with_mtl_pbr(Material& mat, const tinyobj::material_t& m) {
  const bool pbr = m.roughness > 0 || m.metallic > 0 || !m.roughness_texname.empty() || !m.metallic_texname.empty();
  if (!pbr || mat.type == Material::Type::glass) return;
  mat.type = Material::Type::metal_rough;
  mat.kd = {std::clamp(m.diffuse[0], 0.0f, 1.0f), std::clamp(m.diffuse[1], 0.0f, 1.0f), std::clamp(m.diffuse[2], 0.0f, 1.0f)};
  mat.metallic = std::clamp(static_cast<float>(m.metallic), 0.0f, 1.0f);
  mat.roughness = std::clamp(static_cast<float>(m.roughness), 0.0f, 1.0f);
  mat.ks = mat.kr = {};
  mat.ns = 0;
  // A map holds the value itself (as Blender's importer reads map_Pr and map_Pm): the factor it multiplies is 1.
  if (!m.roughness_texname.empty()) mat.roughness = 1;
  if (!m.metallic_texname.empty()) mat.metallic = 1;
}

}  // namespace

Result<Scene> Scene::from_obj_reader(const tinyobj::ObjReader& reader, const std::string& path,
                                     const std::string& texture_dir) {
  const auto& attrib = reader.GetAttrib();
  const auto& materials = reader.GetMaterials();
  Scene s;
  for (const auto& m : materials) {
    const bool ambient = m.ambient[0] > 0 || m.ambient[1] > 0 || m.ambient[2] > 0;
    const bool emits = m.emission[0] > 0 || m.emission[1] > 0 || m.emission[2] > 0;
    if (ambient && !emits) s.ambient_only_.push_back(m.name);
    Material mat = material_from_mtl(m.name, {m.diffuse[0], m.diffuse[1], m.diffuse[2]},
                                     {m.specular[0], m.specular[1], m.specular[2]},
                                     {m.emission[0], m.emission[1], m.emission[2]}, m.shininess, m.ior, m.illum,
                                     {m.transmittance[0], m.transmittance[1], m.transmittance[2]});
    with_mtl_pbr(mat, m);
    s.add_material(std::move(mat));
  }
  // Textures, each file read once per use (a colour map keeps RGB, an alpha map one channel). One that cannot be
  // read leaves its material flat, with a warning.
  const std::string where = "scene file '" + path + "'";
  // A colour map keeps RGB (sRGB-encoded); a coverage map (map_d) and a scalar map (map_Pr, map_Pm: linear values,
  // the first channel) one channel.
  enum class Use { colour, coverage, scalar, normals };
  std::map<std::pair<std::string, Use>, int32_t> loaded;
  auto texture = [&](const std::string& name, Use use, const std::string& material, const char* statement) -> int32_t {
    if (name.empty()) return -1;
    const bool alpha = use == Use::coverage || use == Use::scalar;
    auto [it, fresh] = loaded.emplace(std::pair{name, use}, -1);
    if (!fresh) return it->second;
    const std::string file = (std::filesystem::path(texture_dir) / name).string();
    std::error_code ec;
    // Only a regular file goes to the image reader (not a folder, a device or a pipe, which could block it).
    auto texels = !texture_dir.empty() && std::filesystem::is_regular_file(file, ec) ? read_texels(file)
                                                             : Result<Texels>(make_error("no such file"));
    if (!texels) {
      log_warn(where + ": material '" + material + "': " + statement + " '" + name + "' cannot be read (" +
               texels.error().message + "); the material stays " +
               (use == Use::coverage ? "uncut" : use == Use::colour ? "flat (its Kd)" : use == Use::normals ? "smooth" : "at its factor everywhere"));
      return -1;
    }
    const size_t pixels = static_cast<size_t>(texels->width) * static_cast<size_t>(texels->height);
    if (use == Use::normals && is_grey(*texels, pixels)) {
      // A grey image is a height map (old files' map_Bump), not directions: leaving it out beats a tilted surface.
      log_warn(where + ": material '" + material + "': " + statement + " '" + name +
               "' is grey, a height map; lightfarm reads " + statement +
               " as a tangent-space normal map (as Blender does), so the material stays smooth");
      return -1;
    }
    Texture t;
    t.path = name;
    t.width = static_cast<uint32_t>(texels->width);
    t.height = static_cast<uint32_t>(texels->height);
    t.channels = alpha ? 1 : 3;
    t.linear = use == Use::normals;  // a normal map's channels are x, y, z, not colour
    const size_t n = static_cast<size_t>(t.width) * t.height, from = static_cast<size_t>(texels->channels);
    t.owned.resize(n * t.channels);
    // Coverage is the alpha channel where it says something (varies), else the first channel: a grey image, as the
    // MTL format means map_d (Lost Empire's alpha map is grey with a constant alpha).
    size_t coverage = 0;
    if (use == Use::coverage && (from == 2 || from == 4))
      for (size_t i = 0; i < n && coverage == 0; ++i)
        if (texels->bytes[i * from + from - 1] != texels->bytes[from - 1]) coverage = from - 1;
    for (size_t i = 0; i < n; ++i) {
      const uint8_t* px = &texels->bytes[i * from];
      if (alpha) {
        t.owned[i] = px[coverage];
        continue;
      }
      for (size_t c = 0; c < 3; ++c) {
        uint8_t v = px[std::min(c, from == 2 ? 0 : from - 1)];
        if (texels->linear && use == Use::colour) {  // stored sRGB-encoded, as 8-bit colour files are
          const float l = static_cast<float>(v) / 255.0f;
          v = static_cast<uint8_t>(std::lround(std::clamp(srgb_encode(l), 0.0f, 1.0f) * 255.0f));
        }
        t.owned[i * 3 + c] = v;
      }
    }
    t.build_pyramid();
    return it->second = static_cast<int32_t>(s.add_texture(std::move(t)));
  };
  for (size_t i = 0; i < materials.size(); ++i) {
    Material& m = s.materials_[i];
    if (m.type == Material::Type::diffuse || m.type == Material::Type::glossy || m.type == Material::Type::metal_rough)
      m.kd_map = texture(materials[i].diffuse_texname, Use::colour, m.name, "map_Kd");
    m.alpha_map = texture(materials[i].alpha_texname, Use::coverage, m.name, "map_d");
    if (!m.specular()) {
      // norm, else map_Bump / bump, which Blender's importer and exporter mean as a normal map too; -bm scales it.
      const bool norm = !materials[i].normal_texname.empty();
      const tinyobj::texture_option_t& option = norm ? materials[i].normal_texopt : materials[i].bump_texopt;
      m.normal_map = texture(norm ? materials[i].normal_texname : materials[i].bump_texname, Use::normals, m.name,
                             norm ? "norm" : "map_Bump");
      if (m.normal_map >= 0 && std::isfinite(option.bump_multiplier)) m.normal_scale = option.bump_multiplier;
    }
    if (m.type == Material::Type::metal_rough) {
      m.roughness_map = texture(materials[i].roughness_texname, Use::scalar, m.name, "map_Pr");
      m.metallic_map = texture(materials[i].metallic_texname, Use::scalar, m.name, "map_Pm");
      // A map that cannot be read leaves the factor, which the map's presence set to 1: back to the file's value.
      if (m.roughness_map < 0 && !materials[i].roughness_texname.empty()) m.roughness = std::clamp(materials[i].roughness, 0.0f, 1.0f);
      if (m.metallic_map < 0 && !materials[i].metallic_texname.empty()) m.metallic = std::clamp(materials[i].metallic, 0.0f, 1.0f);
    }
  }
  // Faces without a material get a neutral grey, as most renderers do.
  const auto fallback = s.add_material({"(default)", {0.5f, 0.5f, 0.5f}, {}});
  const size_t vertex_count = attrib.vertices.size() / 3;
  const size_t normal_count = attrib.normals.size() / 3, uv_count = attrib.texcoords.size() / 2;
  for (const auto& shape : reader.GetShapes()) {
    const auto& mesh = shape.mesh;
    size_t index = 0;
    for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      const size_t corners = mesh.num_face_vertices[f];
      if (corners != 3) {
        index += corners;
        continue;
      }
      Vec3 p[3], vn[3];
      Vec2 vt[3];
      bool valid = true, normals = true, uvs = true;
      for (size_t c = 0; c < 3; ++c) {
        const auto& corner = mesh.indices[index + c];
        const int vi = corner.vertex_index, ni = corner.normal_index, ti = corner.texcoord_index;
        if (vi < 0 || static_cast<size_t>(vi) >= vertex_count) {
          valid = false;
          break;
        }
        p[c] = {attrib.vertices[3 * vi], attrib.vertices[3 * vi + 1], attrib.vertices[3 * vi + 2]};
        // A face uses vertex normals (or texture coordinates) only when all three corners have valid ones.
        normals = normals && ni >= 0 && static_cast<size_t>(ni) < normal_count;
        if (normals) vn[c] = {attrib.normals[3 * ni], attrib.normals[3 * ni + 1], attrib.normals[3 * ni + 2]};
        uvs = uvs && ti >= 0 && static_cast<size_t>(ti) < uv_count;
        if (uvs) vt[c] = {attrib.texcoords[2 * ti], attrib.texcoords[2 * ti + 1]};
      }
      index += 3;
      if (!valid) return make_error("scene file '" + path + "': a face refers to a vertex that does not exist");
      int mid = f < mesh.material_ids.size() ? mesh.material_ids[f] : -1;
      uint32_t material = (mid >= 0 && static_cast<size_t>(mid) < materials.size()) ? static_cast<uint32_t>(mid)
                                                                                      : fallback;
      s.add_triangle(p[0], p[1], p[2], material, {normals ? vn : nullptr, uvs ? vt : nullptr});
    }
  }
  // Vertex normals that only repeat the faces' (Lost Empire's 18 axis normals) would cost 36 bytes a triangle in
  // every shipped scene and a lookup at every point for nothing: a scene whose faces are all flat has none.
  if (s.has_shading_normals()) {
    bool flat = true;
    for (uint32_t t = 0; t < s.triangle_count() && flat; ++t)
      for (int c = 0; c < 3 && flat; ++c) flat = dot(s.corner_normal(t, c), s.normal(t)) > 1 - 1e-6f;
    if (flat) s.restore_corners({}, std::move(s.corner_uvs_), std::move(s.corner_tangents_));
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
                                         {"map_d", &m.alpha_texname}, {"map_Ke", &m.emissive_texname},
                                         {"map_Pr", &m.roughness_texname}, {"map_Pm", &m.metallic_texname},
                                         {"norm", &m.normal_texname}, {"map_Bump", &m.bump_texname}})
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
