// The shipped scene form: a round trip rebuilds the same scene bit for bit; short, inconsistent or hostile bytes
// are refused with a message, never a crash.
#include "render/scene/scene_file.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace lf {
namespace {

TEST(SceneFile, RoundTripsTheWholeSceneBitForBit) {
  auto s = Scene::builtin_unlit("cornell_glass");
  ASSERT_TRUE(s.ok());
  s->add_point_light({1, 2, 3}, {4, 5, 6});
  Material ball{"ball", {0.8f, 0.5f, 0.2f}, {}};
  ball.type = Material::Type::metal_rough;
  ball.metallic = 0.75f;
  ball.roughness = 0.125f;
  ball.transmission = 0.5f;
  ball.ior = 1.33f;
  s->add_sphere({0.5f, 0.5f, 0.5f}, 0.1f, 1, s->add_material(ball), true);
  ASSERT_TRUE(s->finalize("test").ok());
  const std::string bytes = scene_to_bytes(*s);
  auto back = scene_from_bytes(bytes, "shipped");
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->triangle_count(), s->triangle_count());
  ASSERT_EQ(back->materials().size(), s->materials().size());
  for (uint32_t t = 0; t < s->triangle_count(); ++t) {
    for (int c = 0; c < 3; ++c) {
      const Vec3 a = back->vertex(t, c), b = s->vertex(t, c);
      EXPECT_EQ(std::memcmp(&a, &b, sizeof(Vec3)), 0);
    }
    EXPECT_EQ(back->material_of(t), s->material_of(t));
    EXPECT_EQ(back->area(t), s->area(t));
  }
  for (size_t m = 0; m < s->materials().size(); ++m) {
    EXPECT_EQ(back->materials()[m].name, s->materials()[m].name);
    EXPECT_EQ(back->materials()[m].type, s->materials()[m].type);
    EXPECT_EQ(back->materials()[m].ke, s->materials()[m].ke);
    EXPECT_EQ(back->materials()[m].metallic, s->materials()[m].metallic);
    EXPECT_EQ(back->materials()[m].roughness, s->materials()[m].roughness);
    EXPECT_EQ(back->materials()[m].transmission, s->materials()[m].transmission);
    EXPECT_EQ(back->materials()[m].ior, s->materials()[m].ior);
  }
  ASSERT_EQ(back->point_lights().size(), 1u);
  EXPECT_EQ(back->point_lights()[0].intensity, (RGB{4, 5, 6}));
  EXPECT_EQ(back->emitters(), s->emitters());
  EXPECT_EQ(back->epsilon(), s->epsilon());
  EXPECT_EQ(scene_to_bytes(*back), bytes);
}

TEST(SceneFile, RefusesShortInconsistentAndHostileBytes) {
  auto s = Scene::builtin("cornell");
  const std::string bytes = scene_to_bytes(*s);
  for (size_t cut : {size_t{0}, size_t{5}, size_t{9}, bytes.size() / 2, bytes.size() - 1})
    EXPECT_FALSE(scene_from_bytes(std::string_view(bytes).substr(0, cut), "x").ok()) << cut;
  EXPECT_EQ(scene_from_bytes("LFSCENE0", "x").error().message, "x: not a lightfarm scene (no LFSCENE11)");
  std::string hostile = "LFSCENE11";
  hostile += std::string("\xff\xff\xff\x7f", 4);  // two billion textures in a few bytes
  EXPECT_EQ(scene_from_bytes(hostile, "x").error().message, "x: the scene's bytes are truncated or inconsistent");
  EXPECT_FALSE(scene_from_bytes(bytes + "extra", "x").ok());
}

TEST(SceneFile, ACachedFileMustMatchItsHash) {
  auto s = Scene::builtin("cornell");
  const std::string bytes = scene_to_bytes(*s);
  const auto path = std::filesystem::temp_directory_path() / ("lightfarm-scene-" + std::to_string(::getpid()));
  std::ofstream(path, std::ios::binary) << bytes;
  EXPECT_TRUE(load_cached_scene(path.string(), content_hash(bytes), "x").ok());
  auto wrong = load_cached_scene(path.string(), "0000000000000000", "x");
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("does not match its hash"), std::string::npos);
  std::filesystem::remove(path);
  EXPECT_NE(load_cached_scene(path.string(), content_hash(bytes), "x").error().message.find("is missing"), std::string::npos);
  EXPECT_NE(content_hash(bytes), content_hash(bytes + " "));
}

}  // namespace
}  // namespace lf
