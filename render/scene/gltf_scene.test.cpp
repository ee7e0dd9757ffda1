// glTF 2.0 scenes: a file written here (a node tree with transforms, indexed triangles, normals, texture
// coordinates, a metal-roughness material, a point light) read back exactly; the Blender-exported material-ball grid
// from ../shared; and files that lie about their buffers refused with a message, not read past.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <filesystem>
#include <fstream>

#include "render/scene/scene.hpp"
#include "render/scene/scene_file.hpp"
#include "render/scene/scene_image.hpp"
#include "render/scene/surface.hpp"
#include "render/lights/light_sampling.hpp"

namespace lf {
namespace {

namespace fs = std::filesystem;

// An uncompressed true-colour TGA, top row first: `pixels` as BGR (24 bits) or BGRA (32) bytes, row by row.
void write_tga(const fs::path& path, int width, int height, int bits, const std::string& pixels) {
  std::string tga(18, '\0');
  tga[2] = 2;
  tga[12] = static_cast<char>(width), tga[14] = static_cast<char>(height);
  tga[16] = static_cast<char>(bits), tga[17] = static_cast<char>(0x20 | (bits == 32 ? 8 : 0));
  std::ofstream(path, std::ios::binary) << tga + pixels;
}

// A 4 x 4 image's pixels whose left half is `left` and right half `right` (one pixel's bytes each).
std::string halves(const std::string& left, const std::string& right) {
  std::string px;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) px += x < 2 ? left : right;
  return px;
}

struct GltfFiles {
  fs::path dir = fs::temp_directory_path() / ("lightfarm-gltf-" + std::to_string(::getpid()));
  // Set: every corner has this TANGENT (x, y, z, w), in a fifth buffer view.
  std::optional<std::array<float, 4>> tangent;
  GltfFiles() { fs::create_directories(dir); }
  ~GltfFiles() { fs::remove_all(dir); }
  // A quad of two triangles (u16 indices) with normals and texture coordinates in x.bin; `accessor_count` lets a
  // test make the positions claim more than the buffer holds.
  // `material`: the material's JSON; `images`: what follows it at the top level (textures, images, samplers).
  std::string write(const std::string& nodes, int accessor_count = 4,
                    const std::string& material = R"({"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.2, 1], "metallicFactor": 1, "roughnessFactor": 0.25}, "emissiveFactor": [0, 0, 0]})",
                    const std::string& images = "") const {
    const float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
    const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
    std::string bin;
    auto add = [&](const void* p, size_t n) { bin.append(static_cast<const char*>(p), n); };
    add(positions, sizeof positions);
    add(normals, sizeof normals);
    add(uvs, sizeof uvs);
    add(indices, sizeof indices);
    if (tangent)
      for (int v = 0; v < 4; ++v) add(tangent->data(), sizeof(float) * 4);
    std::ofstream(dir / "x.bin", std::ios::binary) << bin;
    const std::string tangent_attribute = tangent ? R"(, "TANGENT": 4)" : "";
    const std::string tangent_view = tangent ? R"(, {"buffer": 0, "byteOffset": 140, "byteLength": 64})" : "";
    const std::string tangent_accessor = tangent ? R"(, {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC4"})" : "";
    const std::string json = R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683, "color": [1, 0.5, 0.25]}]}},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": )" + nodes + R"(,
  "meshes": [{"name": "quad", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2)" + tangent_attribute + R"(}, "indices": 3, "material": 0}]}],
  "materials": [)" + material + R"(],)" + images + R"(
  "buffers": [{"uri": "x.bin", "byteLength": )" + std::to_string(bin.size()) + R"(}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 32}, {"buffer": 0, "byteOffset": 128, "byteLength": 12})" + tangent_view + R"(],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": )" + std::to_string(accessor_count) + R"(, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"})" + tangent_accessor + R"(]
})";
    const fs::path path = dir / "x.gltf";
    std::ofstream(path) << json;
    return path.string();
  }
  // The quad under one node with `material`, whose textures are all the one image `image` (in dir).
  std::string write_textured(const std::string& material, const std::string& image) const {
    return write(R"([{"mesh": 0}])", 4, material,
                 R"("textures": [{"source": 0}], "images": [{"uri": ")" + image + R"("}],)");
  }
};

TEST(GltfScene, NodesTransformsMaterialsAndLightsAsTheFileSays) {
  GltfFiles files;
  // The root moves everything by (10, 0, 0); its child scales the quad by 2 and holds the light at its origin.
  const std::string path = files.write(R"([{"translation": [10, 0, 0], "children": [1]},
      {"scale": [2, 2, 2], "mesh": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}}])");
  auto s = Scene::load_gltf_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->triangle_count(), 2u);
  EXPECT_EQ(s->vertex(0, 0), (Vec3{10, 0, 0}));
  EXPECT_EQ(s->vertex(0, 1), (Vec3{12, 0, 0}));
  EXPECT_EQ(s->vertex(1, 2), (Vec3{10, 2, 0}));
  EXPECT_NEAR(s->normal(0).z, 1, 1e-6) << "counter-clockwise is the front, as in glTF";
  const Material& gold = s->material(s->material_of(0));
  EXPECT_EQ(gold.name, "gold");
  EXPECT_EQ(gold.type, Material::Type::metal_rough);
  EXPECT_FLOAT_EQ(gold.metallic, 1);
  EXPECT_FLOAT_EQ(gold.roughness, 0.25f);
  EXPECT_FLOAT_EQ(gold.kd.y, 0.6f);
  // glTF's v runs down the image, the scene's (as OBJ's) up: the file's (0, 1) corner is the scene's (0, 0).
  EXPECT_FLOAT_EQ(s->uv(0, {1, 0, 0}).v, 0);
  EXPECT_FLOAT_EQ(s->uv(0, {0, 0, 1}).v, 1);
  // 683 candela of colour (1, 0.5, 0.25) is 1 W/sr of it, at the light's node.
  ASSERT_EQ(s->point_lights().size(), 1u);
  EXPECT_EQ(s->point_lights()[0].position, (Vec3{10, 0, 0}));
  EXPECT_NEAR(s->point_lights()[0].intensity.y, 0.5f, 1e-6f);
  auto catalogue = Scene::catalogue_file(path);
  ASSERT_TRUE(catalogue.ok());
  EXPECT_EQ(catalogue->material_names, (std::vector<std::string>{"gold"}));
}

// KHR_materials_transmission and KHR_materials_ior: a rough transmitting material is rough glass of the file's
// index; a smooth, whole, untextured one the `glass` material, tinted by its base colour twice (in and out, as glTF
// tints each crossing); a transmission texture is
// a warning, the factor holding everywhere.
TEST(GltfScene, TransmissionMakesGlassRoughOrSmooth) {
  GltfFiles files;
  auto load = [&](const std::string& material, std::string* warnings = nullptr) {
    testing::internal::CaptureStderr();
    auto s = Scene::load_gltf_unlit(files.write(R"([{"mesh": 0}])", 4, material));
    const std::string err = testing::internal::GetCapturedStderr();
    if (warnings) *warnings = err;
    EXPECT_TRUE(s.ok()) << s.error().message;
    return s.ok() ? s->material(s->material_of(0)) : Material{};
  };
  const Material frosted = load(R"({"name": "frosted", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.9, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.4},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.33}}})");
  EXPECT_EQ(frosted.type, Material::Type::metal_rough);
  EXPECT_FLOAT_EQ(frosted.transmission, 1);
  EXPECT_FLOAT_EQ(frosted.ior, 1.33f);
  EXPECT_TRUE(frosted.transmits());
  const Material clear = load(R"({"name": "clear", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.9, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}})");
  EXPECT_EQ(clear.type, Material::Type::glass);
  EXPECT_FLOAT_EQ(clear.ior, 1.5f);
  EXPECT_EQ(clear.tf, (RGB{0.8f * 0.8f, 0.9f * 0.9f, 1}));
  std::string warnings;
  const Material textured = load(R"({"name": "half", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.5},
      "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5, "transmissionTexture": {"index": 0}}, "KHR_materials_ior": {"ior": 7}}})",
                                 &warnings);
  EXPECT_FLOAT_EQ(textured.transmission, 0.5f);
  EXPECT_FLOAT_EQ(textured.ior, 1.5f);
  EXPECT_NE(warnings.find("material 'half': its transmissionTexture is left out; transmissionFactor holds everywhere"),
            std::string::npos) << warnings;
  EXPECT_NE(warnings.find("material 'half': KHR_materials_ior 7.000000 is outside [1, 3]; 1.5 is used"), std::string::npos)
      << warnings;
}

TEST(GltfScene, AMirroringTransformKeepsTheFrontFacingOut) {
  GltfFiles files;
  auto s = Scene::load_gltf_unlit(files.write(R"([{"scale": [1, 1, -1], "mesh": 0}])"));
  ASSERT_TRUE(s.ok()) << s.error().message;
  // The quad faced +z; mirrored in z it faces -z, with its normals.
  EXPECT_NEAR(s->normal(0).z, -1, 1e-6);
  EXPECT_NEAR(s->corner_normal(0, 0).z, -1, 1e-6);
}

// alphaMode MASK cuts the surface where the base colour texture's alpha (times the factor's) is below alphaCutoff:
// a 4 x 4 TGA whose left half has alpha 0.4 and right half 0.2, cut at 0.3 (a cut at one half would take both).
TEST(GltfScene, AlphaMaskCutsWhereCoverageIsBelowTheCutoff) {
  GltfFiles files;
  write_tga(files.dir / "leaf.tga", 4, 4, 32, halves({'\x80', '\x80', '\x80', 102}, {'\x80', '\x80', '\x80', 50}));
  const std::string path = files.write_textured(R"({"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.3, "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})", "leaf.tga");
  auto s = Scene::load_gltf_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& leaf = s->material(s->material_of(0));
  ASSERT_GE(leaf.alpha_map, 0);
  ASSERT_GE(leaf.kd_map, 0);
  // Triangle 0 runs (0,0) (1,0) (1,1); x < 0.5 is the image's left half.
  EXPECT_TRUE(s->opaque(0, {0.8f, 0.1f, 0.1f}));
  EXPECT_FALSE(s->opaque(0, {0.1f, 0.8f, 0.1f}));
}

// metallicRoughnessTexture: blue is metallic, green roughness, each times its factor, and the maps travel with the
// shipped scene. A 4 x 4 TGA: the left half rough (green 1) dielectric (blue 0), the right half smooth (green 0.2)
// metal (blue 1); factors metallic 1, roughness 0.5.
TEST(GltfScene, MetallicRoughnessTexturesVaryTheModelOverTheSurface) {
  GltfFiles files;
  write_tga(files.dir / "mr.tga", 4, 4, 24, halves({'\x00', '\xff', '\x00'}, {'\xff', '\x33', '\x00'}));
  const std::string path = files.write_textured(R"({"name": "patchy", "pbrMetallicRoughness": {"metallicFactor": 1, "roughnessFactor": 0.5, "metallicRoughnessTexture": {"index": 0}}})", "mr.tga");
  auto s = Scene::load_gltf_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& m = s->material(s->material_of(0));
  ASSERT_GE(m.metallic_map, 0);
  ASSERT_GE(m.roughness_map, 0);
  s->add_point_light({0, 0, 1}, {1, 1, 1});
  ASSERT_TRUE(s->finalize("patchy").ok());
  auto shipped = scene_from_bytes(scene_to_bytes(*s), "shipped");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  // Triangle 0's texture coordinates: u = b1 + b2, so b = (0.8, 0.1, 0.1) is at u 0.2 (left), (0.3, 0.4, 0.3) at 0.7.
  for (const Scene* scene : {&*s, &*shipped}) {
    float metallic = -1, roughness = -1;
    scene->metal_rough_at(0, {0.8f, 0.1f, 0.1f}, 0, metallic, roughness);
    EXPECT_NEAR(metallic, 0.0f, 1e-6f);
    EXPECT_NEAR(roughness, 0.5f, 1e-6f);
    scene->metal_rough_at(0, {0.3f, 0.4f, 0.3f}, 0, metallic, roughness);
    EXPECT_NEAR(metallic, 1.0f, 1e-6f);
    EXPECT_NEAR(roughness, 0.1f, 1e-3f);
  }
}

// normalTexture turns the shading normal (surface_at's, which every op shades with) in the tangent frame of the
// texture coordinates: red along +u, green along +v (image up, glTF's convention), blue along the normal. A
// constant map tilted 30 degrees towards +u, then towards +v; read, and after shipping.
TEST(GltfScene, NormalTexturesTurnTheShadingNormal) {
  for (int axis : {0, 1}) {
    GltfFiles files;
    const unsigned char red = axis == 0 ? 191 : 128, green = axis == 1 ? 191 : 128, blue = 238;
    std::string px;
    for (int i = 0; i < 4; ++i) px += std::string{static_cast<char>(blue), static_cast<char>(green), static_cast<char>(red)};
    write_tga(files.dir / "n.tga", 2, 2, 24, px);
    const std::string path = files.write_textured(R"({"name": "bumpy", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0, "roughnessFactor": 1}, "normalTexture": {"index": 0}})", "n.tga");
    auto s = Scene::load_gltf_unlit(path);
    ASSERT_TRUE(s.ok()) << s.error().message;
    ASSERT_GE(s->material(s->material_of(0)).normal_map, 0);
    s->add_point_light({0, 0, 1}, {1, 1, 1});
    ASSERT_TRUE(s->finalize("bumpy").ok());
    ASSERT_TRUE(s->has_normal_maps());
    auto shipped = scene_from_bytes(scene_to_bytes(*s), "shipped");
    ASSERT_TRUE(shipped.ok()) << shipped.error().message;
    const fs::path image = files.dir / "x.image";  // as a host's actors map the shipped scene
    std::ofstream(image, std::ios::binary) << SceneImage::encode(*shipped, "0123456789abcdef");
    auto mapped = SceneImage::map(image.string(), "0123456789abcdef", "mapped");
    ASSERT_TRUE(mapped.ok()) << mapped.error().message;
    const float x = 2 * red / 255.0f - 1, y = 2 * green / 255.0f - 1, z = 2 * blue / 255.0f - 1;
    const Vec3 expected = normalize(Vec3{x, y, z});  // the quad's u runs along +x, its v along +y
    for (const Scene* scene : {&*s, &*shipped, &*mapped}) {
      const SurfacePoint sp = surface_at(*scene, 0, {0.7f, 0.3f, 0}, {0, 0, 1});
      EXPECT_NEAR(sp.ns.x, expected.x, 1e-4f) << "axis " << axis;
      EXPECT_NEAR(sp.ns.y, expected.y, 1e-4f) << "axis " << axis;
      EXPECT_NEAR(sp.ns.z, expected.z, 1e-4f) << "axis " << axis;
      EXPECT_NEAR(sp.ng.z, 1.0f, 1e-6f);
    }
  }
}

// emissiveTexture: emissiveFactor (times the strength) times the texture's colour, at every place light meets it: a
// quad whose left half glows (white) and right half does not (black), strength 2. Light samples on it carry that
// radiance, so their estimate of its emitted radiance over its area is 1 (half of the unit quad at 2).
TEST(GltfScene, EmissiveTexturesLightWhereTheyGlow) {
  GltfFiles files;
  write_tga(files.dir / "glow.tga", 4, 4, 24, halves(std::string(3, '\xff'), std::string(3, '\0')));
  const std::string path = files.write_textured(R"({"name": "sign", "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}, "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}})", "glow.tga");
  auto s = Scene::load_gltf_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_GE(s->material(s->material_of(0)).emission_map, 0);
  ASSERT_TRUE(s->finalize("sign").ok());
  auto shipped = scene_from_bytes(scene_to_bytes(*s), "shipped");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  for (const Scene* scene : {&*s, &*shipped}) {
    // Triangle 0: u = b1 + b2 (see the metallic-roughness test): left at 0.2, right at 0.7.
    EXPECT_NEAR(scene->emission(0, {0.8f, 0.1f, 0.1f}).x, 2.0f, 1e-4f);
    EXPECT_NEAR(scene->emission(0, {0.3f, 0.4f, 0.3f}).x, 0.0f, 1e-4f);
    EXPECT_NEAR(scene->mean_emission(scene->material(scene->material_of(0))).y, 1.0f, 0.02f);
    Rng rng(1, 2);
    double integral = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
      const LightSample ls = sample_light(*scene, rng);
      integral += ls.radiance.x / ls.pdf_area;
    }
    EXPECT_NEAR(integral / n, 1.0, 0.02);
  }
}

// KHR_texture_transform moves a material's texture over its surface: a texture white on its left half and black
// on its right, shifted by half its width, is black where it was white; scaled by 2, it repeats twice across.
// A file's TANGENT gives the frame (not the texture coordinates): tangents along +y with the bitangent on the -x
// side turn a map that leans along its x towards +y, and with w = -1 the bitangent flips (a mirrored UV layout).
TEST(GltfScene, TheFilesTangentsGiveTheNormalMapsFrame) {
  for (float w : {1.0f, -1.0f}) {
    GltfFiles files;
    files.tangent = std::array<float, 4>{0, 1, 0, w};
    std::string px;  // x 0.5, y 0.25, z 0.83
    for (int i = 0; i < 4; ++i) px += std::string{static_cast<char>(233), static_cast<char>(160), static_cast<char>(191)};
    write_tga(files.dir / "n.tga", 2, 2, 24, px);
    auto s = Scene::load_gltf_unlit(files.write_textured(R"({"name": "bumpy", "normalTexture": {"index": 0}})", "n.tga"));
    ASSERT_TRUE(s.ok()) << s.error().message;
    ASSERT_TRUE(s->has_tangents());
    s->add_point_light({0, 0, 1}, {1, 1, 1});
    ASSERT_TRUE(s->finalize("bumpy").ok());
    auto shipped = scene_from_bytes(scene_to_bytes(*s), "shipped");
    ASSERT_TRUE(shipped.ok()) << shipped.error().message;
    const fs::path image = files.dir / "x.image";
    std::ofstream(image, std::ios::binary) << SceneImage::encode(*shipped, "0123456789abcdef");
    auto mapped = SceneImage::map(image.string(), "0123456789abcdef", "mapped");
    ASSERT_TRUE(mapped.ok()) << mapped.error().message;
    const float x = 2 * 191 / 255.0f - 1, y = 2 * 160 / 255.0f - 1, z = 2 * 233 / 255.0f - 1;
    // Tangent +y; bitangent w * cross(+z, +y) = w * -x.
    const Vec3 expected = normalize(Vec3{-w * y, x, z});
    for (const Scene* scene : {&*s, &*shipped, &*mapped}) {
      const SurfacePoint sp = surface_at(*scene, 0, {0.7f, 0.3f, 0}, {0, 0, 1});
      EXPECT_NEAR(sp.ns.x, expected.x, 1e-4f) << "w " << w;
      EXPECT_NEAR(sp.ns.y, expected.y, 1e-4f) << "w " << w;
      EXPECT_NEAR(sp.ns.z, expected.z, 1e-4f) << "w " << w;
    }
  }
}

TEST(GltfScene, TextureTransformsMoveTheTexture) {
  for (const char* transform : {R"({"offset": [0.5, 0]})", R"({"scale": [2, 1]})"}) {
    GltfFiles files;
    write_tga(files.dir / "half.tga", 4, 4, 24, halves(std::string(3, '\xff'), std::string(3, '\0')));
    const std::string path = files.write_textured(std::string(R"({"name": "moved", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": )") +
            transform + "}}}}", "half.tga");
    auto s = Scene::load_gltf_unlit(path);
    ASSERT_TRUE(s.ok()) << s.error().message;
    // Triangle 0: u = b1 + b2. Shifted by a half, u 0.2 reads the texture at 0.7 (black) and 0.7 at 1.2, i.e. 0.2
    // (white); scaled by 2, u 0.375 reads it at 0.75 (a black texel's centre) and 0.625 at 1.25, i.e. 0.25 (white).
    const bool shifted = std::string(transform).find("offset") != std::string::npos;
    const float black_at = shifted ? 0.2f : 0.375f, white_at = shifted ? 0.7f : 0.625f;
    EXPECT_NEAR(s->albedo(0, {1 - black_at, black_at / 2, black_at / 2}).x, 0.0f, 1e-3f) << transform;
    EXPECT_NEAR(s->albedo(0, {1 - white_at, white_at / 2, white_at / 2}).x, 1.0f, 1e-3f) << transform;
  }
}

// A KHR_lights_punctual spot shines along its node's -z with its cone angles; shipped with them.
TEST(GltfScene, SpotLightsShineAlongTheirNodesMinusZ) {
  GltfFiles files;
  // A quarter turn about +x takes the node's -z to the scene's +y.
  const std::string path = files.write(R"([{"mesh": 0}, {"rotation": [0.7071068, 0, 0, 0.7071068],
      "extensions": {"KHR_lights_punctual": {"light": 0}}}])");
  {
    std::ifstream in(path);
    std::string json((std::istreambuf_iterator<char>(in)), {});
    const std::string point = R"({"type": "point", "intensity": 683, "color": [1, 0.5, 0.25]})";
    json.replace(json.find(point), point.size(),
                 R"({"type": "spot", "intensity": 683, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.3}})");
    json.replace(json.find(R"("nodes": [0])"), 12, R"("nodes": [0, 1])");
    std::ofstream(path) << json;
  }
  auto s = Scene::load_gltf_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->point_lights().size(), 1u);
  ASSERT_TRUE(s->finalize("spot").ok());
  auto shipped = scene_from_bytes(scene_to_bytes(*s), "shipped");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  for (const Scene* scene : {&*s, &*shipped}) {
    const PointLight& spot = scene->point_lights()[0];
    ASSERT_TRUE(spot.spot());
    EXPECT_NEAR(spot.axis.y, 1.0f, 1e-5f);
    EXPECT_NEAR(spot.cos_inner, std::cos(0.1f), 1e-6f);
    EXPECT_NEAR(spot.cos_outer, std::cos(0.3f), 1e-6f);
    EXPECT_NEAR(spot.intensity_towards({0, 1, 0}).x, 1.0f, 1e-6f);
    EXPECT_EQ(spot.intensity_towards({1, 0, 0}).x, 0.0f);
  }
}

TEST(GltfScene, BadFilesAreRefusedWithAMessage) {
  GltfFiles files;
  auto past = Scene::load_gltf_unlit(files.write(R"([{"mesh": 0}])", 40));
  ASSERT_FALSE(past.ok());
  EXPECT_NE(past.error().message.find("reach past their buffer"), std::string::npos) << past.error().message;
  auto cycle = Scene::load_gltf_unlit(files.write(R"([{"children": [1]}, {"children": [0], "mesh": 0}])"));
  ASSERT_FALSE(cycle.ok());
  auto missing = Scene::load_file_unlit((files.dir / "none.glb").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().message, "scene file '" + (files.dir / "none.glb").string() + "' not found");
  std::ofstream(files.dir / "junk.glb") << "not glTF";
  auto junk = Scene::load_file_unlit((files.dir / "junk.glb").string());
  ASSERT_FALSE(junk.ok());
  EXPECT_NE(junk.error().message.find("not a glTF file"), std::string::npos) << junk.error().message;
}

// The material-ball grid Blender's own exporter wrote: 8 balls, the floor and an emissive panel, each material as
// Blender's Principled BSDF had it.
TEST(GltfScene, ReadsBlendersMaterialBalls) {
  const std::string path = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/gltf/balls.glb";
  if (!fs::exists(path)) GTEST_SKIP() << "no " << path;
  auto s = Scene::load_file_unlit(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->triangle_count(), 17668u);
  int balls = 0;
  for (const Material& m : s->materials()) {
    if (m.name.rfind("Ball_m", 0) != 0) continue;
    ++balls;
    EXPECT_EQ(m.type, Material::Type::metal_rough);
    EXPECT_FLOAT_EQ(m.metallic, m.name[6] == '1' ? 1.0f : 0.0f) << m.name;
    EXPECT_NEAR(m.roughness, std::stof(m.name.substr(9)), 1e-6) << m.name;
  }
  EXPECT_EQ(balls, 8);
  bool panel = false;
  for (const Material& m : s->materials()) panel = panel || (m.name == "Panel" && m.ke == RGB{12, 11, 10});
  EXPECT_TRUE(panel);
  EXPECT_TRUE(s->has_shading_normals()) << "the balls are shaded smooth";
}

// A rig ("Rig", node 0) carrying a camera ("Cam", node 1), and an animation whose channels are `channels`, with
// samplers over accessors: 0 times {0, 2}; 1 times {0, 1}; 2 rig translation {0,0,0} -> {4,0,0}; 3 camera rotation
// identity -> 90 degrees about +y; 4 camera translation {0,0,10} -> {0,5,10}; 5 cubic translation (in, value, out)
// x 2 keys: value {0,0,10} -> {4,0,10}, every tangent {2,0,0} (the line's slope, 4 over 2 s); 6 times {2, 1}.
std::string write_animated(const fs::path& dir, const std::string& samplers, const std::string& channels,
                           const std::string& camera_node = R"({"name": "Cam", "camera": 0})") {
  const float s = std::sqrt(0.5f);
  const std::vector<float> data = {0, 2,  0, 1,  0, 0, 0, 4, 0, 0,  0, 0, 0, 1, 0, s, 0, s,  0, 0, 10, 0, 5, 10,
                                   2, 0, 0, 0, 0, 10, 2, 0, 0, 2, 0, 0, 4, 0, 10, 2, 0, 0,  2, 1};
  std::ofstream(dir / "anim.bin", std::ios::binary).write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size() * 4));
  auto view = [](int first, int count) {
    return R"({"buffer": 0, "byteOffset": )" + std::to_string(first * 4) + R"(, "byteLength": )" + std::to_string(count * 4) + "}";
  };
  auto accessor = [](int v, int count, const char* type) {
    return R"({"bufferView": )" + std::to_string(v) + R"(, "componentType": 5126, "count": )" + std::to_string(count) +
           R"(, "type": ")" + type + R"("})";
  };
  const std::string json = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"name": "Rig", "children": [1]}, )" + camera_node + R"(],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
  "buffers": [{"uri": "anim.bin", "byteLength": )" + std::to_string(data.size() * 4) + R"(}],
  "bufferViews": [)" + view(0, 2) + "," + view(2, 2) + "," + view(4, 6) + "," + view(10, 8) + "," + view(18, 6) + "," +
                           view(24, 18) + "," + view(42, 2) + R"(],
  "accessors": [)" + accessor(0, 2, "SCALAR") + "," + accessor(1, 2, "SCALAR") + "," + accessor(2, 2, "VEC3") + "," +
                           accessor(3, 2, "VEC4") + "," + accessor(4, 2, "VEC3") + "," + accessor(5, 6, "VEC3") + "," +
                           accessor(6, 2, "SCALAR") + R"(],
  "animations": [{"samplers": )" + samplers + R"(, "channels": )" + channels + R"(}]})";
  const fs::path path = dir / "anim.gltf";
  std::ofstream(path) << json;
  return path.string();
}

void expect_view(const CameraSpec& v, std::array<double, 3> eye, std::array<double, 3> ahead, std::array<double, 3> up,
                 double tolerance, const std::string& what) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(v.eye[i], eye[i], tolerance) << what << " eye[" << i << "]";
    EXPECT_NEAR(v.at[i] - v.eye[i], ahead[i], tolerance) << what << " ahead[" << i << "]";
    EXPECT_NEAR(v.up[i], up[i], tolerance) << what << " up[" << i << "]";
  }
}

// A camera moved by its own node's channels and its parent's: LINEAR translation, rotation by the shorter slerp,
// STEP, CUBICSPLINE with its tangents scaled by the key spacing, held before the first key and after the last.
TEST(GltfScene, AnAnimatedCameraIsWhereItsNodesChannelsPutItAtEachTime) {
  GltfFiles files;
  const std::string samplers = R"([{"input": 0, "output": 2}, {"input": 0, "output": 3, "interpolation": "LINEAR"},
                                    {"input": 1, "output": 4, "interpolation": "STEP"}])";
  const std::string path = write_animated(files.dir, samplers, R"([{"sampler": 0, "target": {"node": 0, "path": "translation"}},
    {"sampler": 1, "target": {"node": 1, "path": "rotation"}}, {"sampler": 2, "target": {"node": 1, "path": "translation"}}])");
  auto catalogue = Scene::catalogue_gltf(path);
  ASSERT_TRUE(catalogue.ok()) << catalogue.error().message;
  ASSERT_EQ(catalogue->cameras.size(), 1u);
  EXPECT_TRUE(catalogue->cameras[0].animated);
  EXPECT_EQ(catalogue->cameras[0].animation_seconds, 2);
  EXPECT_EQ(catalogue->cameras[0].view.eye, (std::array<double, 3>{0, 0, 0})) << "at rest: the nodes' own transforms";
  auto views = Scene::gltf_camera_views(path, 0, {-1, 0.5, 1, 5});
  ASSERT_TRUE(views.ok()) << views.error().message;
  const double r = std::sqrt(0.5), a = kPi / 8;  // 45 degrees at 1 s, 22.5 at 0.5 s
  expect_view((*views)[0], {0, 0, 10}, {0, 0, -1}, {0, 1, 0}, 1e-6, "before the first key");
  expect_view((*views)[1], {1, 0, 10}, {-std::sin(a), 0, -std::cos(a)}, {0, 1, 0}, 1e-6, "0.5 s");
  expect_view((*views)[2], {2, 5, 10}, {-r, 0, -r}, {0, 1, 0}, 1e-6, "1 s (the STEP's second key)");
  expect_view((*views)[3], {4, 5, 10}, {-1, 0, 0}, {0, 1, 0}, 1e-6, "after the last key");

  const std::string cubic = write_animated(files.dir, R"([{"input": 0, "output": 5, "interpolation": "CUBICSPLINE"}])",
                                           R"([{"sampler": 0, "target": {"node": 1, "path": "translation"}}])");
  views = Scene::gltf_camera_views(cubic, 0, {0.5, 1});
  ASSERT_TRUE(views.ok()) << views.error().message;
  // Tangents of the line's slope keep the Hermite curve on the line: x = 1 at 0.5 s (zero tangents: 0.625).
  expect_view((*views)[0], {1, 0, 10}, {0, 0, -1}, {0, 1, 0}, 1e-6, "cubic at 0.5 s");
  expect_view((*views)[1], {2, 0, 10}, {0, 0, -1}, {0, 1, 0}, 1e-6, "cubic at 1 s");

  // What cannot be played is an error naming the channel; a camera nothing animates is still.
  auto error_of = [&](const std::string& samplers, const std::string& channels, const std::string& node = R"({"name": "Cam", "camera": 0})") {
    auto v = Scene::gltf_camera_views(write_animated(files.dir, samplers, channels, node), 0, {0});
    return v.ok() ? std::string("played") : v.error().message;
  };
  EXPECT_NE(error_of(R"([{"input": 6, "output": 2}])", R"([{"sampler": 0, "target": {"node": 0, "path": "translation"}}])")
                .find("animation 0's channel 0's key times are not ascending"), std::string::npos);
  EXPECT_NE(error_of(R"([{"input": 0, "output": 5}])", R"([{"sampler": 0, "target": {"node": 1, "path": "translation"}}])")
                .find("animation 0's channel 0 has 6 values for 2 keys"), std::string::npos);
  EXPECT_NE(error_of(R"([{"input": 0, "output": 2}])", R"([{"sampler": 3, "target": {"node": 1, "path": "translation"}}])")
                .find("names a sampler that does not exist"), std::string::npos);
  EXPECT_NE(error_of(R"([{"input": 0, "output": 9}])", R"([{"sampler": 0, "target": {"node": 1, "path": "translation"}}])")
                .find("an accessor that does not exist"), std::string::npos);
  EXPECT_NE(error_of(R"([{"input": 0, "output": 2}])", R"([{"sampler": 0, "target": {"node": 1, "path": "translation"}}])",
                     R"({"name": "Cam", "camera": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})")
                .find("animates a node given by a matrix"), std::string::npos);
  EXPECT_EQ(error_of(R"([{"input": 0, "output": 2}])", R"([{"sampler": 0, "target": {"node": 0, "path": "weights"}}])"), "played");
}

// Blender's own export of a camera keyed at frames 1 and 24 (testdata/camera_walk.py made it): the views at frame /
// fps seconds are the views Blender gives at those frames (its matrix_world, z-up turned y-up as the exporter turns
// it). Blender puts frame f at f / fps seconds.
TEST(GltfScene, BlendersCameraAnimationGivesBlendersViewsAtFrameOverFps) {
  const std::string path = std::string(LIGHTFARM_SOURCE_DIR) + "/render/scene/testdata/camera_walk.gltf";
  auto catalogue = Scene::catalogue_gltf(path);
  ASSERT_TRUE(catalogue.ok()) << catalogue.error().message;
  ASSERT_EQ(catalogue->cameras.size(), 1u);
  EXPECT_EQ(catalogue->cameras[0].name, "Camera");
  EXPECT_TRUE(catalogue->cameras[0].animated);
  EXPECT_NEAR(catalogue->cameras[0].animation_seconds, 1.0, 1e-6);
  auto views = Scene::gltf_camera_views(path, 0, {1 / 24.0, 12 / 24.0, 24 / 24.0});
  ASSERT_TRUE(views.ok()) << views.error().message;
  expect_view((*views)[0], {0, 2, 10}, {0, -0.169967, -0.985450}, {0, 0.985450, -0.169967}, 1e-4, "frame 1");
  expect_view((*views)[1], {3.739295, 2.467412, 8.130353}, {-0.398748, -0.215826, -0.891302}, {-0.088137, 0.976432, -0.197009},
              1e-4, "frame 12");
  expect_view((*views)[2], {8, 3, 6}, {-0.754781, -0.267499, -0.598957}, {-0.209539, 0.963558, -0.166280}, 1e-4, "frame 24");
}

}  // namespace
}  // namespace lf
