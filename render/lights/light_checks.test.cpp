// Lights that light nothing: the escaping share of a light's flux against cases with a known answer.
#include "render/lights/light_checks.hpp"

#include <gtest/gtest.h>

#include "render/test_support.hpp"

namespace lf {
namespace {

// A light inside a closed box: nothing escapes. The same quad wound the other way, just outside the box's top:
// everything does, and the warning names it.
TEST(LightChecks, AClosedBoxKeepsItsLightAndAQuadWoundAwayLosesAll) {
  Scene s;
  auto white = s.add_material({"white", {0.5f, 0.5f, 0.5f}, {}});
  test::add_closed_box(s, white);
  auto inside = s.add_material({"inside", {}, {4, 4, 4}});
  s.add_quad({0.4f, 0.9f, 0.4f}, {0.6f, 0.9f, 0.4f}, {0.6f, 0.9f, 0.6f}, {0.4f, 0.9f, 0.6f}, inside);  // faces down
  auto away = s.add_material({"light at farm.lua:7", {}, {4, 4, 4}});
  s.add_quad({0.4f, 1.1f, 0.4f}, {0.4f, 1.1f, 0.6f}, {0.6f, 1.1f, 0.6f}, {0.6f, 1.1f, 0.4f}, away);  // faces up
  ASSERT_TRUE(s.finalize("box").ok());
  const auto escapes = light_escapes(s);
  ASSERT_EQ(escapes.size(), 2u);
  EXPECT_EQ(escapes[0].light, "material 'inside'");
  EXPECT_EQ(escapes[0].escaping, 0.0);
  EXPECT_EQ(escapes[1].light, "farm.lua:7: light");
  EXPECT_EQ(escapes[1].escaping, 1.0);
  const auto warnings = escaping_light_warnings(escapes);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "farm.lua:7: light: 100% of its flux leaves the scene without meeting a surface (wound the "
                         "wrong way, or outside the geometry?)");
}

// A point light above the middle of a large floor: the floor takes the lower half of its directions, the rest
// escapes, minus the sliver beyond the floor's edge (the floor spans +-100 at height 1: about 1 % of the lower
// half). And a point light inside the box loses nothing.
TEST(LightChecks, APointLightAboveAFloorLosesTheUpperHalf) {
  Scene s;
  auto grey = s.add_material({"grey", {0.5f, 0.5f, 0.5f}, {}});
  s.add_quad({-100, 0, -100}, {-100, 0, 100}, {100, 0, 100}, {100, 0, -100}, grey);
  s.add_point_light({0, 1, 0}, {1, 1, 1});
  ASSERT_TRUE(s.finalize("floor").ok());
  const auto escapes = light_escapes(s, {"farm.lua:3: light"});
  ASSERT_EQ(escapes.size(), 1u);
  EXPECT_EQ(escapes[0].light, "farm.lua:3: light");
  EXPECT_NEAR(escapes[0].escaping, 0.5, 0.05);
  EXPECT_TRUE(escaping_light_warnings(escapes, 0.6).empty());

  Scene box;
  test::add_closed_box(box, box.add_material({"white", {0.5f, 0.5f, 0.5f}, {}}));
  box.add_point_light({0.5f, 0.5f, 0.5f}, {1, 1, 1});
  ASSERT_TRUE(box.finalize("box").ok());
  EXPECT_EQ(light_escapes(box)[0].light, "point light 1");
  EXPECT_EQ(light_escapes(box)[0].escaping, 0.0);
}

}  // namespace
}  // namespace lf
