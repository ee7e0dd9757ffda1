// The light tree: its probabilities are what pick() does, no light that can reach a point is ever left out, and
// direct light through it matches the closed form (Lambert's contour formula) with less noise than choosing by
// power when lights are many and spread out.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

#include "render/lights/light_sampling.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

using test::form_factor;

constexpr int kLights = 48;

// A long floor (x from 0 to 24) under a row of small square lamps at height 1, facing down, every 0.5 units; every
// fourth lamp faces up (it can light nothing on the floor); and a point light off to one side.
struct Corridor {
  Scene scene;
  std::vector<std::vector<Vec3>> down_lamps;
  Corridor() {
    const auto floor = scene.add_material({"floor", {1, 1, 1}, {}});
    const auto lamp = scene.add_material({"lamp", {0, 0, 0}, {5, 5, 5}});
    scene.add_quad({0, 0, -2}, {0, 0, 2}, {24, 0, 2}, {24, 0, -2}, floor);
    for (int i = 0; i < kLights; ++i) {
      const float x0 = 0.2f + 0.5f * static_cast<float>(i), x1 = x0 + 0.1f;
      const Vec3 a{x0, 1, -0.05f}, b{x1, 1, -0.05f}, c{x1, 1, 0.05f}, d{x0, 1, 0.05f};
      if (i % 4 == 3) {
        scene.add_quad(a, d, c, b, lamp);  // faces up
      } else {
        scene.add_quad(a, b, c, d, lamp);  // faces down
        down_lamps.push_back({a, b, c, d});
      }
    }
    scene.add_point_light({30, 3, 0}, {2, 2, 2});
    EXPECT_TRUE(scene.finalize("corridor").ok());
  }
};

TEST(LightTree, PickingFollowsTheProbabilitiesItReports) {
  Corridor c;
  const LightTree& tree = c.scene.light_tree();
  ASSERT_EQ(tree.light_count(), c.scene.emitters().size() + 1);
  EXPECT_LE(tree.depth(), 8);  // 97 lights, balanced
  const Vec3 x{3.1f, 0, 0.3f}, n{0, 1, 0};
  double total = 0;
  for (size_t l = 0; l < tree.light_count(); ++l) total += tree.probability(x, n, l);
  EXPECT_NEAR(total, 1.0, 1e-4);
  // Counts of 400k picks against the probabilities, and each pick reports its light's probability.
  std::map<size_t, int> counts;
  Rng rng(7, 11);
  const int picks = 400000;
  for (int i = 0; i < picks; ++i) {
    size_t light = 0;
    float p = 0;
    ASSERT_TRUE(tree.pick(x, n, rng.uniform(), light, p));
    ASSERT_NEAR(p, tree.probability(x, n, light), 1e-6f * std::max(1.0f, p));
    ++counts[light];
  }
  for (size_t l = 0; l < tree.light_count(); ++l) {
    const double expected = tree.probability(x, n, l) * picks;
    EXPECT_NEAR(counts[l], expected, 5 * std::sqrt(expected) + 2) << "light " << l;
  }
}

TEST(LightTree, NoLightThatCanReachAPointIsLeftOut) {
  Corridor c;
  const LightTree& tree = c.scene.light_tree();
  const auto& emitters = c.scene.emitters();
  Rng rng(3, 5);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 x{24 * rng.uniform(), 0.8f * rng.uniform(), 4 * rng.uniform() - 2};
    const Vec3 n = normalize(Vec3{rng.uniform() - 0.5f, rng.uniform(), rng.uniform() - 0.5f});
    for (size_t l = 0; l < emitters.size(); ++l) {
      const uint32_t t = emitters[l];
      // A corner of the lamp in front of the lamp and above x's horizon: the lamp can give x light.
      bool reaches = false;
      for (int k = 0; k < 3; ++k) {
        const Vec3 to = c.scene.vertex(t, k) - x;
        if (dot(to, n) > 1e-3f && dot(c.scene.normal(t), to) < -1e-3f) reaches = true;
      }
      if (reaches) {
        EXPECT_GT(tree.probability(x, n, l), 0.0f) << "trial " << trial << " light " << l;
      }
    }
  }
  // Lamps facing away from the floor are never chosen for a floor point straight below them.
  for (size_t l = 0; l < emitters.size(); ++l)
    if (c.scene.normal(emitters[l]).y > 0) {
      const Vec3 below = c.scene.vertex(emitters[l], 0) * Vec3{1, 0, 1};
      EXPECT_EQ(tree.probability(below, {0, 1, 0}, l), 0.0f);
    }
}

std::vector<RGB> shade_direct(const Corridor& c, const ShadingPoints& pts, const std::string& sampling, int samples) {
  RayTracer tracer(c.scene);
  return test::shade_direct(SceneContext{&c.scene, &tracer}, pts, sampling, samples);
}

// Floor points along the corridor: what the down-facing lamps give (white floor: L = sum Le F) plus the point
// light's I cos / d^2 / pi.
TEST(LightTree, DirectLightMatchesTheClosedFormWithLessNoiseThanPower) {
  Corridor c;
  std::vector<Vec3> xs;
  for (int i = 0; i < 24; ++i) xs.push_back({0.5f + static_cast<float>(i), 0, 0.4f});
  auto expected = [&](Vec3 x) {
    double f = 0;
    for (const auto& lamp : c.down_lamps) f += form_factor(x, {0, 1, 0}, lamp);
    const Vec3 d = Vec3{30, 3, 0} - x;
    const double d2 = dot(d, d), cosine = d.y / std::sqrt(d2);
    return 5 * f + 2 * cosine / d2 / kPi;
  };
  // Many samples: both strategies converge to the closed form (power, with ten times as many, to 5 %: the point
  // light has 77 % of the power and takes that share of its samples wherever the point is).
  ShadingPoints pts;
  for (size_t i = 0; i < xs.size(); ++i) pts.push_back(xs[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0));
  for (const auto& [sampling, samples, tolerance] : {std::tuple{"tree", 20000, 0.02}, {"power", 200000, 0.05}}) {
    const auto out = shade_direct(c, pts, sampling, samples);
    for (size_t i = 0; i < xs.size(); ++i)
      EXPECT_NEAR(out[i].x / expected(xs[i]), 1.0, tolerance) << sampling << " x " << xs[i].x;
  }
  // One sample each over 200 keys per point: the tree's relative RMSE is well below power's.
  ShadingPoints many;
  for (size_t i = 0; i < xs.size(); ++i)
    for (uint32_t s = 0; s < 200; ++s) many.push_back(xs[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, s));
  auto rmse = [&](const std::string& sampling) {
    const auto out = shade_direct(c, many, sampling, 1);
    double sum = 0;
    for (size_t k = 0; k < out.size(); ++k) {
      const double e = expected(xs[k / 200]), r = out[k].x / e - 1;
      sum += r * r;
    }
    return std::sqrt(sum / static_cast<double>(out.size()));
  };
  const double tree = rmse("tree"), power = rmse("power");
  EXPECT_LT(tree, 0.5 * power) << "tree " << tree << ", power " << power;
}

}  // namespace
}  // namespace lf
