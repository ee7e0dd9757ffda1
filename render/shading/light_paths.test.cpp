// Light path sets: composition as the ops state it, counts, and the summaries `lightfarm graph` draws.
#include "render/shading/light_paths.hpp"

#include "render/scene/scene.hpp"

#include <gtest/gtest.h>

namespace lf {
namespace {

const Lobes kDG = Lobes::of({Lobe::diffuse, Lobe::glossy});

TEST(LightPaths, EveryAndThenCountEachPathOnce) {
  const LightPaths direct = LightPaths::every(1, 1, kDG);
  EXPECT_EQ(direct.counted(), (std::vector<std::string>{"LD", "LG"}));
  const LightPaths bounce = direct.then(Lobe::diffuse);
  EXPECT_EQ(bounce.counted(), (std::vector<std::string>{"LDD", "LGD"}));
  EXPECT_EQ(LightPaths::every(0, 2).counted().size(), 1u + 3u + 9u);
  EXPECT_EQ(LightPaths::every(1, 99).count("LSSSSSS"), 1.0f);  // 6 events: the longest tracked
  EXPECT_EQ(LightPaths::every(1, 99).count("LSSSSSSS"), 0.0f);
  EXPECT_EQ(LightPaths::every(1, 6, Lobes::of({Lobe::diffuse})).count("LDGD"), 0.0f);
}

TEST(LightPaths, SumsCountTwiceWhatBothPartsHold) {
  LightPaths sum = LightPaths::every(1, 1, kDG);
  sum += LightPaths::every(1, 3);
  EXPECT_EQ(sum.count("LD"), 2.0f);
  EXPECT_EQ(sum.count("LS"), 1.0f);
  EXPECT_EQ(sum.count("LDSD"), 1.0f);
  EXPECT_EQ((sum * 0.5f).count("LD"), 1.0f);
}

TEST(LightPaths, ChainsKeepWhatEndsOnTheirLandingLobes) {
  // A specular chain over `direct` and an emitter it meets: L S+ and L (D|G) S+.
  LightPaths landing = LightPaths::emission();
  landing += LightPaths::every(1, 1, kDG).ending_in(kDG, true);
  const LightPaths chains = landing.then_repeated(Lobe::specular, 1, 8);
  EXPECT_EQ(chains.count("LS"), 1.0f);
  EXPECT_EQ(chains.count("LSSS"), 1.0f);
  EXPECT_EQ(chains.count("LDS"), 1.0f);
  EXPECT_EQ(chains.count("LGSS"), 1.0f);
  EXPECT_EQ(chains.count("L"), 0.0f);
  EXPECT_EQ(chains.count("LSDS"), 0.0f);
  // ending_in drops paths that end on other lobes, and the lone L unless asked.
  EXPECT_EQ(LightPaths::every(0, 2).ending_in(Lobes::of({Lobe::specular}), false).counted(),
            (std::vector<std::string>{"LS", "LDS", "LGS", "LSS"}));
}

// A scene's lobes by material: a metal_rough material is a glossy lobe (its specular lobe, its rough glass) and a
// diffuse one (its base under the coating, a conductor's multiply scattered light), which the caches serve by
// elevation bands; rough glass alone, or a perfectly smooth metal, is glossy only.
TEST(LightPaths, AMetalRoughMaterialIsAGlossyAndADiffuseLobe) {
  Scene s;
  Material ball{"ball", {0.8f, 0.8f, 0.8f}, {}};
  ball.type = Material::Type::metal_rough;
  Material glass = ball;
  glass.name = "glass";
  glass.transmission = 1;
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, s.add_material(ball));
  s.add_quad({0, 0, 2}, {1, 0, 2}, {1, 0, 3}, {0, 0, 3}, s.add_material(glass));
  s.add_quad({0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}, s.add_material({"lamp", {}, {1, 1, 1}}));
  ASSERT_TRUE(s.finalize("lobes").ok());
  const SceneLobes found = scene_lobes(s);
  EXPECT_EQ(found.materials[static_cast<int>(Lobe::glossy)], (std::vector<std::string>{"ball", "glass"}));
  EXPECT_EQ(found.materials[static_cast<int>(Lobe::diffuse)], (std::vector<std::string>{"ball"}));
  EXPECT_TRUE(found.materials[static_cast<int>(Lobe::specular)].empty());
  EXPECT_FALSE(ball.has_lambert_lobe());
  EXPECT_TRUE(ball.has_diffuse_lobe());
  EXPECT_FALSE(glass.has_diffuse_lobe());
}

TEST(LightPaths, SummariesNameTheShapes) {
  EXPECT_EQ(LightPaths::every(1, 1, kDG).summary(), "L(D|G)");
  EXPECT_EQ(LightPaths::every(1, 8).summary(), "L(D|G|S)+");
  EXPECT_EQ(LightPaths::every(1, 8).then(Lobe::diffuse).summary(), "L(D|G|S)+D");
  EXPECT_EQ(LightPaths::every(1, 1, kDG).then(Lobe::diffuse).summary(), "L(D|G)D");
  // Everything but what mirrors alone bring (a cache's input beside a photon map), and a cache over that.
  LightPaths lit = LightPaths::every(1, 8);
  lit += LightPaths::emission().then_repeated(Lobe::specular, 1, 8) * -1.0f;
  EXPECT_EQ(lit.summary(), "L(D|G|S)*(D|G)(D|G|S)*");  // a D or a G somewhere
  EXPECT_EQ(lit.then(Lobe::diffuse).summary(), "L(D|G|S)*(D|G)(D|G|S)*D");
  EXPECT_EQ((LightPaths::every(1, 1, kDG) + LightPaths::every(3, 3, Lobes::of({Lobe::specular}))).summary(), "L(D|G) | LSSS");
  EXPECT_EQ(LightPaths::emission().summary(), "L");
  EXPECT_EQ(LightPaths().summary(), "nothing");
}

}  // namespace
}  // namespace lf
