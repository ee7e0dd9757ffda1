// NearLights answers exactly what testing every emitter's zone would, for small lamps in its grid and for a large
// panel it tests everywhere.
#include <gtest/gtest.h>

#include <cmath>

#include "render/lights/near_lights.hpp"
#include "render/scene/scene.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

TEST(NearLights, AnswersAsTestingEveryZoneWould) {
  Scene scene;
  const auto floor = scene.add_material({"floor", {1, 1, 1}, {}});
  const auto lamp = scene.add_material({"lamp", {0, 0, 0}, {5, 5, 5}});
  scene.add_quad({-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20}, floor);
  // 40 lamps of three sizes along a winding line, and one large panel high overhead.
  std::vector<Vec3> lamps;
  for (int i = 0; i < 40; ++i) {
    const float s = 0.05f * static_cast<float>(1 + i % 3);
    const float x = -18 + 0.9f * static_cast<float>(i), z = 4 * std::sin(0.3f * static_cast<float>(i));
    scene.add_quad({x - s, 1, z - s}, {x + s, 1, z - s}, {x + s, 1, z + s}, {x - s, 1, z + s}, lamp);
    lamps.push_back({x, 1, z});
  }
  scene.add_quad({-3, 30, -3}, {3, 30, -3}, {3, 30, 3}, {-3, 30, 3}, lamp);
  ASSERT_TRUE(scene.finalize("lamps").ok());

  const float reach = 4;
  const NearLights near(scene, reach);
  EXPECT_EQ(near.zone_count(), scene.emitters().size());
  EXPECT_EQ(near.everywhere_count(), 2u);  // the panel's two triangles
  auto brute = [&](Vec3 x) {
    for (const uint32_t t : scene.emitters()) {
      const Vec3 a = scene.vertex(t, 0), b = scene.vertex(t, 1), c = scene.vertex(t, 2);
      const Vec3 lo{std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
      const Vec3 hi{std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
      if (length(x - (lo + hi) * 0.5f) < reach * 0.5f * length(hi - lo)) return true;
    }
    return false;
  };
  Rng rng(3, 5);
  int agreed = 0, near_count = 0;
  const int points = 40000;
  for (int i = 0; i < points; ++i) {
    // Half around a lamp, a quarter anywhere in the room, a quarter far outside it.
    Vec3 x;
    auto within = [&](float half) { return (2 * rng.uniform() - 1) * half; };
    if (i % 4 < 2)
      x = lamps[static_cast<size_t>(rng.uniform() * 40) % 40] + Vec3{within(1.5f), within(1.5f), within(1.5f)};
    else if (i % 4 == 2)
      x = {within(20), within(20) + 20, within(20)};
    else
      x = {within(400), within(400), within(400)};
    const bool expected = brute(x);
    agreed += near.near(x) == expected;
    near_count += expected;
  }
  EXPECT_EQ(agreed, points);
  EXPECT_GT(near_count, points / 20);        // both answers are exercised
  EXPECT_LT(near_count, points - points / 20);
  EXPECT_TRUE(near.near({-18, 0.8f, 0.05f}));  // just under the first lamp (its zone: 0.28 around it)
  EXPECT_FALSE(near.near({-18, 0.5f, 0}));     // further under it
  EXPECT_TRUE(near.near({0, 20, 0}));        // under the panel
  EXPECT_FALSE(near.near({0, 0, 18}));       // off to the side
  EXPECT_FALSE(NearLights(scene, 0).near({-18, 1, 0}));  // no reach: nothing is near
}

}  // namespace
}  // namespace lf
