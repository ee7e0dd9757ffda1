#include "render/scene/scene.hpp"
#include "render/scene/scene_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace lf {

static const std::string kShared = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/cornell_box_mcguire/";

#define REQUIRE_SHARED_SCENES()                                                          \
  if (!std::filesystem::is_directory(kShared)) GTEST_SKIP() << "no " << kShared << " here"

TEST(Scene, BuiltinCornellBoxHasItsGeometryAndOneDownwardLight) {
  auto s = Scene::builtin("cornell");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(s->triangle_count(), 38u);  // 5 walls, a ceiling in 4 pieces, the light, 10 block faces
  ASSERT_EQ(s->emitters().size(), 2u);
  for (uint32_t t : s->emitters()) {
    EXPECT_FLOAT_EQ(s->normal(t).y, -1.0f);
    EXPECT_EQ(s->material(s->material_of(t)).name, "light");
  }
  float area = s->area(s->emitters()[0]) + s->area(s->emitters()[1]);
  EXPECT_NEAR(area, 130.0f * 105.0f, 1e-2f);
}

TEST(Scene, CornellGlassHasAClosedGlassSphereAndAMirrorBlock) {
  auto s = Scene::builtin("cornell_glass");
  ASSERT_TRUE(s.ok()) << s.error().message;
  size_t glass = 0, mirror = 0;
  double glass_area = 0;
  for (uint32_t t = 0; t < s->triangle_count(); ++t) {
    const Material& m = s->material(s->material_of(t));
    if (m.type == Material::Type::glass) {
      ++glass;
      glass_area += s->area(t);
      // Outward winding: the normal points away from the centre.
      Vec3 c = (s->vertex(t, 0) + s->vertex(t, 1) + s->vertex(t, 2)) / 3.0f;
      EXPECT_GT(dot(s->normal(t), c - Vec3{185, 90, 169}), 0.0f);
    }
    mirror += m.type == Material::Type::mirror;
  }
  EXPECT_EQ(glass, 20u * 256u);
  EXPECT_NEAR(glass_area / (4 * M_PI * 90 * 90), 1.0, 0.01);  // a level-4 icosphere is within 1 % of the sphere
  EXPECT_EQ(mirror, 10u);
}

TEST(Scene, UnknownBuiltinNamesTheKnownOnes) {
  auto s = Scene::builtin("kitchen");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "unknown built-in scene 'kitchen' (built-in scenes: cornell, cornell_glass, room)");
}

TEST(Scene, MissingFileIsAClearError) {
  auto s = Scene::load_obj("/nonexistent/room.obj");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message, "scene file '/nonexistent/room.obj' not found");
}

TEST(Scene, McGuireOriginalLoadsDespiteTabsAndDuplicateFaces) {
  REQUIRE_SHARED_SCENES();
  auto s = Scene::load_obj(kShared + "CornellBox-Original.obj");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_GE(s->triangle_count(), 30u);
  ASSERT_FALSE(s->emitters().empty());
  for (uint32_t t : s->emitters()) {
    EXPECT_LT(s->normal(t).y, -0.99f);  // the light faces down into the box
    EXPECT_EQ(s->material(s->material_of(t)).ke, (RGB{17, 12, 4}));
  }
}

TEST(Scene, AnObjFromMemoryIsTheSameSceneAsFromItsFile) {
  REQUIRE_SHARED_SCENES();
  std::ifstream obj(kShared + "CornellBox-Original.obj"), mtl(kShared + "CornellBox-Original.mtl");
  std::stringstream obj_text, mtl_text;
  obj_text << obj.rdbuf();
  mtl_text << mtl.rdbuf();
  auto from_file = Scene::load_obj_unlit(kShared + "CornellBox-Original.obj");
  auto from_text = Scene::parse_obj_unlit(obj_text.str(), mtl_text.str(), "box.obj");
  ASSERT_TRUE(from_file.ok() && from_text.ok());
  ASSERT_EQ(from_text->triangle_count(), from_file->triangle_count());
  ASSERT_EQ(from_text->materials().size(), from_file->materials().size());
  for (uint32_t t = 0; t < from_file->triangle_count(); ++t) {
    EXPECT_EQ(from_text->material_of(t), from_file->material_of(t));
    for (int c = 0; c < 3; ++c) EXPECT_EQ(from_text->vertex(t, c), from_file->vertex(t, c));
  }
  auto bad = Scene::parse_obj_unlit("f 1 2 3\n", "", "broken.obj");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message, "scene file 'broken.obj': a face refers to a vertex that does not exist");
}

// MTL as exporters mean it: illum 3 with Kd keeps it beside the mirror, Tf tints glass; both survive the compact
// form that ships a scene to hosts.
TEST(Scene, Illum3AndTfReachTheMaterialAndTheShippedScene) {
  const std::string obj = "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl coat\nf 1 2 3\nusemtl tint\nf 1 2 3\nusemtl lamp\nf 1 2 3\n";
  const std::string mtl = "newmtl lamp\nKe 1 1 1\nnewmtl coat\nillum 3\nKd 0.5 0.4 0.3\nKs 0.4 0.4 0.4\nNs 80\n"
                          "newmtl tint\nillum 7\nNi 1.4\nTf 0.3 0.6 0.9\n";
  auto s = Scene::parse_obj_unlit(obj, mtl, "x.obj");
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& coat = s->material(s->material_of(0));
  EXPECT_EQ(coat.type, Material::Type::glossy);
  EXPECT_FLOAT_EQ(coat.kd.y, 0.4f);
  EXPECT_FLOAT_EQ(coat.ks.x, 0.2f);
  EXPECT_FLOAT_EQ(coat.kr.x, 0.2f);
  EXPECT_FLOAT_EQ(coat.ns, 80);
  const Material& tint = s->material(s->material_of(1));
  EXPECT_EQ(tint.type, Material::Type::glass);
  EXPECT_FLOAT_EQ(tint.tf.y, 0.6f);
  auto shipped = scene_from_bytes(scene_to_bytes(*s), "x.lfscene");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  EXPECT_FLOAT_EQ(shipped->material(shipped->material_of(0)).kr.z, 0.2f);
  EXPECT_FLOAT_EQ(shipped->material(shipped->material_of(1)).tf.z, 0.9f);
}

// MTL's PBR extension: Pr and Pm make glTF's metal-roughness model on the Kd base (its Ks lobe gone); without them a
// material keeps its illum model, and glass stays glass.
TEST(Scene, MtlPbrFieldsMakeAMetalRoughMaterial) {
  const std::string obj = "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl gold\nf 1 2 3\nusemtl plastic\nf 1 2 3\n"
                          "usemtl plain\nf 1 2 3\nusemtl lamp\nf 1 2 3\n";
  const std::string mtl = "newmtl lamp\nKe 1 1 1\nnewmtl gold\nKd 0.9 0.7 0.3\nKs 0.5 0.5 0.5\nNs 200\nillum 2\nPr 0.25\nPm 1\n"
                          "newmtl plastic\nKd 0.2 0.3 0.8\nPr 0.6\nnewmtl plain\nKd 0.5 0.5 0.5\n";
  auto s = Scene::parse_obj_unlit(obj, mtl, "x.obj");
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& gold = s->material(s->material_of(0));
  EXPECT_EQ(gold.type, Material::Type::metal_rough);
  EXPECT_FLOAT_EQ(gold.metallic, 1);
  EXPECT_FLOAT_EQ(gold.roughness, 0.25f);
  EXPECT_FLOAT_EQ(gold.kd.x, 0.9f) << "the base colour, not scaled against the Ks the model replaces";
  EXPECT_TRUE(is_black(gold.ks));
  const Material& plastic = s->material(s->material_of(1));
  EXPECT_EQ(plastic.type, Material::Type::metal_rough);
  EXPECT_FLOAT_EQ(plastic.metallic, 0);
  EXPECT_EQ(s->material(s->material_of(2)).type, Material::Type::diffuse);
  auto shipped = scene_from_bytes(scene_to_bytes(*s), "x.lfscene");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  EXPECT_FLOAT_EQ(shipped->material(shipped->material_of(0)).roughness, 0.25f);
}

// map_Pr and map_Pm hold the roughness and metallic values themselves (their first channel, linear), as Blender's
// importer reads them; one that cannot be read leaves the file's Pm, with a warning.
TEST(Scene, MtlPbrMapsVaryRoughnessOverTheSurface) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-pbrmaps-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::string tga(18, '\0');
  tga[2] = 3;                    // uncompressed grey
  tga[12] = 2, tga[14] = 1;      // 2 x 1
  tga[16] = 8, tga[17] = 0x20;   // 8 bits, top row first
  tga += std::string{'\x33', '\xff'};  // 0.2 on the left, 1 on the right
  std::ofstream(dir / "rough.tga", std::ios::binary) << tga;
  std::ofstream(dir / "x.obj") << "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0.5\nvt 1 0.5\nvt 0 0.5\n"
                                  "usemtl patchy\nf 1/1 2/2 3/3\n";
  std::ofstream(dir / "x.mtl") << "newmtl patchy\nKd 0.5 0.5 0.5\nPr 0.5\nPm 0.3\nmap_Pr rough.tga\nmap_Pm gone.tga\n";
  auto s = Scene::load_obj_unlit((dir / "x.obj").string());
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& m = s->material(s->material_of(0));
  ASSERT_EQ(m.type, Material::Type::metal_rough);
  ASSERT_GE(m.roughness_map, 0);
  EXPECT_EQ(m.metallic_map, -1);
  float metallic = -1, roughness = -1;
  // Corner 2 is at u = 1 (the right texel's centre is u = 0.75, the left's 0.25, repeating between them).
  s->metal_rough_at(0, {0.5f, 0.5f, 0.0f}, 0, metallic, roughness);  // u = 0.5: halfway between the two texels
  EXPECT_NEAR(roughness, 0.6f, 0.01f);
  EXPECT_NEAR(metallic, 0.3f, 1e-6f);
  s->metal_rough_at(0, {0.5f, 0.25f, 0.25f}, 0, metallic, roughness);  // u = 0.25: the left texel's centre
  EXPECT_NEAR(roughness, 0.2f, 0.01f);
}

// map_Bump (and bump) is a tangent-space normal map, as Blender's importer and exporter mean it, scaled by -bm; a
// grey one is an old file's height map, left out with a warning that says so.
TEST(Scene, MtlBumpIsANormalMapAndAGreyOneIsRefused) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-bump-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto tga = [&](const char* name, int type, int bits, const std::string& pixels) {
    std::string t(18, '\0');
    t[2] = static_cast<char>(type);  // 2: true colour, 3: grey
    t[12] = 1, t[14] = 1;            // 1 x 1
    t[16] = static_cast<char>(bits), t[17] = 0x20;
    std::ofstream(dir / name, std::ios::binary) << t + pixels;
  };
  tga("tilted.tga", 2, 24, std::string{'\xd9', '\x80', '\xd9'});  // BGR: x 0.7, y 0, z 0.7 (45 degrees along +u)
  tga("height.tga", 3, 8, std::string{'\x80'});
  std::ofstream(dir / "x.obj") << "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                  "usemtl bumpy\nf 1/1 2/2 3/3\nusemtl old\nf 1/1 2/2 3/3\n";
  std::ofstream(dir / "x.mtl") << "newmtl bumpy\nKd 0.5 0.5 0.5\nmap_Bump -bm 0.5 tilted.tga\n"
                                  "newmtl old\nKd 0.5 0.5 0.5\nbump height.tga\n";
  testing::internal::CaptureStderr();
  auto s = Scene::load_obj_unlit((dir / "x.obj").string());
  const std::string warnings = testing::internal::GetCapturedStderr();
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const Material& bumpy = s->material(s->material_of(0));
  ASSERT_GE(bumpy.normal_map, 0);
  EXPECT_FLOAT_EQ(bumpy.normal_scale, 0.5f);
  // x scaled by one half: the normal leans towards +u (the triangle's +x) by atan(0.35 / 0.7), not 45 degrees.
  const Vec3 n = s->normal_mapped(0, {1.0f / 3, 1.0f / 3, 1.0f / 3}, {0, 0, 1});
  EXPECT_NEAR(std::atan2(n.x, n.z) * 180 / kPi, std::atan(0.5) * 180 / kPi, 1.0);
  EXPECT_NEAR(n.y, 0, 0.01);
  EXPECT_EQ(s->material(s->material_of(1)).normal_map, -1);
  EXPECT_NE(warnings.find("material 'old': map_Bump 'height.tga' is grey, a height map; lightfarm reads map_Bump as a "
                          "tangent-space normal map (as Blender does), so the material stays smooth"),
            std::string::npos)
      << warnings;
}

TEST(Scene, McGuireEmptyCOReadsTheIndentedMaterial) {
  REQUIRE_SHARED_SCENES();
  auto s = Scene::load_obj(kShared + "CornellBox-Empty-CO.obj");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_FALSE(s->emitters().empty());
}

TEST(Scene, SceneWithoutEmittersIsAnErrorThatSaysSo) {
  REQUIRE_SHARED_SCENES();
  auto s = Scene::load_obj(kShared + "CornellBox-Glossy.obj");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("has no light (no material with Ke > 0, and the script adds no light, environment or sun)"),
            std::string::npos)
      << s.error().message;
}

TEST(Scene, ScriptLightsLightASceneWithoutEmitters) {
  REQUIRE_SHARED_SCENES();
  SceneSpec spec;
  spec.file = kShared + "CornellBox-Glossy.obj";
  spec.lights = Value::Array{Value::Map{
      {"quad", Value::Array{Value::Array{-0.2, 1.58, 0.2}, Value::Array{-0.2, 1.58, -0.2}, Value::Array{0.2, 1.58, -0.2},
                            Value::Array{0.2, 1.58, 0.2}}},
      {"radiance", Value::Array{17, 12, 4}}}};
  auto s = Scene::load(spec);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->emitters().size(), 2u);
  EXPECT_LT(s->normal(s->emitters()[0]).y, -0.99f);  // faces down into the box
  size_t glossy = 0;
  for (const auto& m : s->materials()) glossy += m.type == Material::Type::glossy;
  EXPECT_GT(glossy, 0u) << "the Glossy box's MTL has glossy materials";
}

// A job frame's point-light change (frames { lights }) moves the named one of the script's point lights, and a change
// that does not name one as a packet must (a whole index within the script's count) is an error, never a crash.
TEST(Scene, AFramesPointLightChangeMovesThatLightOnly) {
  SceneSpec spec;
  spec.builtin = "cornell";
  spec.lights = Value::Array{Value::Map{{"point", Value::Array{100, 500, 100}}, {"intensity", Value::Array{1, 1, 1}}},
                             Value::Map{{"name", "bulb"}, {"point", Value::Array{200, 500, 200}},
                                        {"intensity", Value::Array{2, 2, 2}}}};
  auto s = Scene::load(spec);
  ASSERT_TRUE(s.ok()) << s.error().message;
  const size_t n = s->point_lights().size();
  ASSERT_GE(n, 2u);
  auto change = [](Value index, Value of, Value point) {
    return Value::Array{Value::Map{{"name", "bulb"},
                                   {"light", Value::Map{{"index", std::move(index)}, {"of", std::move(of)},
                                                        {"point", std::move(point)}}}}};
  };
  auto moved = s->with_material_changes(change(int64_t{1}, int64_t{2}, Value::Array{1, 2, 3}), "frame 2");
  ASSERT_TRUE(moved.ok()) << moved.error().message;
  const auto& lights = (*moved)->point_lights();
  EXPECT_EQ(lights[n - 1].position.x, 1);
  EXPECT_EQ(lights[n - 1].position.z, 3);
  EXPECT_EQ(lights[n - 1].intensity.x, 2);  // left out: the declared one
  EXPECT_EQ(lights[n - 2].position.x, s->point_lights()[n - 2].position.x);
  for (const auto& [index, of] : std::vector<std::pair<Value, Value>>{{std::nan(""), int64_t{2}},
                                                                      {0.5, int64_t{2}},
                                                                      {int64_t{2}, int64_t{2}},
                                                                      {int64_t{-1}, int64_t{2}},
                                                                      {int64_t{0}, static_cast<int64_t>(n + 1)},
                                                                      {Value("one"), int64_t{2}}}) {
    auto bad = s->with_material_changes(change(index, of, Value::Array{1, 2, 3}), "frame 2");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.error().message.find("point light 'bulb' is not among the scene's point lights"), std::string::npos)
        << bad.error().message;
  }
  auto bad_point = s->with_material_changes(change(int64_t{1}, int64_t{2}, Value("up")), "frame 2");
  ASSERT_FALSE(bad_point.ok());
  EXPECT_NE(bad_point.error().message.find("point light 'bulb': point must be {x, y, z}"), std::string::npos);
}

TEST(Scene, EveryMcGuireSceneWithALightLoads) {
  REQUIRE_SHARED_SCENES();
  for (const char* name : {"CornellBox-Mirror", "CornellBox-Sphere", "CornellBox-Water", "CornellBox-Empty-RG",
                           "CornellBox-Empty-Squashed", "CornellBox-Empty-White"}) {
    auto s = Scene::load_obj(kShared + name + ".obj");
    ASSERT_TRUE(s.ok()) << name << ": " << s.error().message;
    EXPECT_FALSE(s->emitters().empty()) << name;
  }
}

}  // namespace lf

namespace lf {
TEST(Scene, BoundsHoldEveryVertexAndGiveTheDiagonal) {
  auto s = Scene::builtin("cornell");
  ASSERT_TRUE(s.ok());
  const Bounds& b = s->bounds();
  for (const Vec3& v : s->vertices())
    for (int c = 0; c < 3; ++c) {
      EXPECT_LE(b.lo[c], v[c]);
      EXPECT_GE(b.hi[c], v[c]);
    }
  // The published box: 556 x 548.8 x 559.2 mm.
  EXPECT_NEAR(b.diagonal(), std::sqrt(556.0f * 556.0f + 548.8f * 548.8f + 559.2f * 559.2f), 1.0f);
}
}  // namespace lf

namespace lf {

// Diagnostics of an OBJ's text, each naming file and line; a hint when an unlit scene has Ka where Ke was meant;
// a bent light quad is an error.
TEST(Scene, ObjDiagnosticsNameFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-diag-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string a = (dir / "a.obj").string(), b = (dir / "b.obj").string();
  std::ofstream(a) << "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl nothing\nf 1 2 3\n";
  std::ofstream(b) << "mtllib b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl nothere\nf 1 2 3\nusemtl glow\nf 1 2 3\n"
                      "usemtl nothere\nf 1 2 3\n";
  std::ofstream(dir / "b.mtl") << "newmtl glow\nKd 0.5 0.5 0.5\nKa 5 5 5\n";
  auto ca = Scene::catalogue_obj(a);
  ASSERT_TRUE(ca.ok());
  EXPECT_EQ(ca->warnings, (std::vector<std::string>{
                              a + ":1: material library 'missing.mtl' not found beside the OBJ; its faces get a grey default",
                              a + ":5: usemtl 'nothing' names no material of its libraries; those faces get a grey default"}));
  auto cb = Scene::catalogue_obj(b);
  ASSERT_TRUE(cb.ok());
  EXPECT_EQ(cb->material_names, std::vector<std::string>{"glow"});
  EXPECT_EQ(cb->warnings, std::vector<std::string>{
                              b + ":5: usemtl 'nothere' names no material of its libraries; those faces get a grey default"});
  auto unlit = Scene::load_obj(b);
  ASSERT_FALSE(unlit.ok());
  EXPECT_EQ(unlit.error().message, "scene file '" + b + "': the scene has no light (no material with Ke > 0, and the "
                                   "script adds no light, environment or sun); glow has Ka but no Ke: did you mean Ke?");
  std::filesystem::remove_all(dir);

  Scene s;
  auto bent = s.add_script_lights(Value::Array{Value::Map{
      {"quad", Value::Array{Value::Array{0.0, 0.0, 0.0}, Value::Array{1.0, 0.0, 0.0}, Value::Array{1.0, 1.0, 0.5},
                            Value::Array{0.0, 1.0, 0.0}}},
      {"radiance", Value::Array{1.0, 1.0, 1.0}}}});
  ASSERT_FALSE(bent.ok());
  EXPECT_EQ(bent.error().message.rfind("light 1: the quad is not planar (its 4th corner is ", 0), 0u) << bent.error().message;
}

}  // namespace lf

namespace lf {
namespace {

// shape { plane }: a square facing its normal, ten times the scene's extent unless sized; shape { sphere }: a
// round-shaded icosphere; each with a grey material named after it, or the scene's material it names.
TEST(Scene, ScriptShapesAddAPlaneAndASphere) {
  Scene s;
  const uint32_t red = s.add_material({"red", {0.6f, 0.1f, 0.1f}, {}});
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, red);  // extent sqrt(2)
  const size_t before = s.triangle_count();
  ASSERT_TRUE(s.add_script_shapes(Value::Array{
                    Value::Map{{"name", "ground"}, {"plane", Value::Array{0.5, -1.0, 0.5}}, {"normal", Value::Array{0.0, 2.0, 0.0}}},
                    Value::Map{{"name", "ball"}, {"sphere", Value::Array{0.0, 3.0, 0.0}}, {"radius", 0.5}, {"material", "red"}}})
                  .ok());
  const uint32_t ground = static_cast<uint32_t>(before);
  ASSERT_EQ(s.material(s.material_of(ground)).name, "ground");
  EXPECT_EQ(s.material(s.material_of(ground)).kd, (RGB{0.5f, 0.5f, 0.5f}));
  const Vec3 n = normalize(cross(s.vertex(ground, 1) - s.vertex(ground, 0), s.vertex(ground, 2) - s.vertex(ground, 0)));
  EXPECT_NEAR(n.y, 1.0f, 1e-6f) << "it faces its normal";
  float lo = INFINITY, hi = -INFINITY;
  for (uint32_t t : {ground, ground + 1})
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(s.vertex(t, k).y, -1.0f);
      lo = std::min(lo, s.vertex(t, k).x), hi = std::max(hi, s.vertex(t, k).x);
    }
  EXPECT_NEAR(hi - lo, 10 * std::sqrt(2.0f), 1e-4f) << "ten times the scene's extent";
  EXPECT_NEAR((hi + lo) / 2, 0.5f, 1e-5f);
  ASSERT_EQ(s.triangle_count(), before + 2 + 20 * 256) << "a level-4 icosphere";
  const uint32_t ball = ground + 2;
  EXPECT_EQ(s.material_of(ball), red);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(length(s.vertex(ball, k) - Vec3{0, 3, 0}), 0.5f, 1e-5f);
  int outward = 0;
  for (uint32_t t = ball; t < s.triangle_count(); ++t) {
    const Vec3 a = s.vertex(t, 0), b = s.vertex(t, 1), c = s.vertex(t, 2);
    outward += dot(cross(b - a, c - a), (a + b + c) * (1.0f / 3) - Vec3{0, 3, 0}) > 0;
  }
  EXPECT_EQ(outward, 20 * 256) << "every face of the ball faces out";
  EXPECT_TRUE(s.has_shading_normals()) << "the sphere is shaded round";
  EXPECT_EQ(s.add_script_shapes(Value::Array{Value::Map{{"name", "x"}, {"sphere", Value::Array{0.0, 0.0, 0.0}}, {"radius", 0.0}}})
                .error()
                .message,
            "shape 'x': sphere needs a centre {x, y, z} and a radius > 0");
  Scene empty;
  EXPECT_EQ(empty.add_script_shapes(Value::Array{Value::Map{{"name", "floor"}, {"plane", Value::Array{0.0, 0.0, 0.0}}}})
                .error()
                .message,
            "shape 'floor': plane needs a size > 0 (the scene is empty, so give one)");
}

}  // namespace
}  // namespace lf
