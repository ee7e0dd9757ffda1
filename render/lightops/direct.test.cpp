// direct against closed forms: the radiance a white diffuse point reflects from a uniformly emitting polygon is
// L = Le * F, with F the point-to-polygon form factor (Lambert's contour formula).
#include <gtest/gtest.h>

#include <cmath>

#include "render/lightop_registry.hpp"
#include "render/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {

using test::form_factor;

struct Rig {
  Scene scene;
  std::unique_ptr<RayTracer> tracer;
  std::unique_ptr<LightOp> op;
  LocalInputs none;
  std::vector<Vec3> light;
  uint32_t floor = 0;

  Rig(const std::vector<Vec3>& light_polygon, int light_samples, bool blocker = false) : light(light_polygon) {
    floor = scene.add_material({"white", {1, 1, 1}, {}});
    auto grey = scene.add_material({"grey", {0.5f, 0.5f, 0.5f}, {}});
    auto emitter = scene.add_material({"light", {0, 0, 0}, {2, 3, 4}});
    scene.add_quad({-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, floor);
    // Light polygon as a fan; the caller gives corners so that the winding faces down.
    for (size_t i = 1; i + 1 < light.size(); ++i) scene.add_triangle(light[0], light[i], light[i + 1], emitter);
    if (blocker) scene.add_quad({-1.2f, 0.5f, -1.2f}, {1.2f, 0.5f, -1.2f}, {1.2f, 0.5f, 1.2f}, {-1.2f, 0.5f, 1.2f}, grey);
    EXPECT_TRUE(scene.finalize("test").ok());
    tracer = std::make_unique<RayTracer>(scene);
    op = create_lightop(*find_lightop_kind("direct"),
                        ParamTable(Value::Map{{"light_samples", light_samples}}, "lightop 'direct'"));
    run_to_completion(op->setup(SceneContext{&scene, tracer.get()}, none));
  }

  std::vector<RGB> shade(const ShadingPoints& pts) {
    std::vector<RGB> out(pts.size());
    run_to_completion(op->shade(pts, out, none));
    return out;
  }
};

static ShadingPoints points_at(const std::vector<Vec3>& ps) {
  ShadingPoints pts;
  for (size_t i = 0; i < ps.size(); ++i) pts.push_back(ps[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0));
  return pts;
}

TEST(Direct, CentredSquareMatchesFormFactorWithinOnePercent) {
  // A 2x2 square at height 1, facing down.
  Rig rig({{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}}, 200000);
  auto out = rig.shade(points_at({{0, 0, 0}}));
  const double f = form_factor({0, 0, 0}, {0, 1, 0}, rig.light);
  EXPECT_NEAR(f, 0.5541, 1e-3);  // tabulated value for a square of side 2h centred above the point
  EXPECT_NEAR(out[0].x / (2 * f), 1.0, 0.01);
  EXPECT_NEAR(out[0].y / (3 * f), 1.0, 0.01);
  EXPECT_NEAR(out[0].z / (4 * f), 1.0, 0.01);
}

TEST(Direct, OffsetRectangleAndDiscMatchLambertsFormula) {
  // A 3x1 rectangle well off to the side, and a 64-gon disc of radius 1.5 at height 2.
  Rig rect({{1, 2, -0.5f}, {4, 2, -0.5f}, {4, 2, 0.5f}, {1, 2, 0.5f}}, 200000);
  std::vector<Vec3> disc;
  for (int i = 0; i < 64; ++i) {
    float a = 2 * kPi * i / 64;  // this turn, fanned from corner 0, faces down
    disc.push_back({1.5f * std::cos(a), 2, 1.5f * std::sin(a)});
  }
  Rig round(disc, 200000);
  std::vector<Vec3> where{{0, 0, 0}, {-1.5f, 0, 1}, {2.5f, 0, 0}};
  auto a = rect.shade(points_at(where));
  auto b = round.shade(points_at(where));
  for (size_t i = 0; i < where.size(); ++i) {
    EXPECT_NEAR(a[i].y / (3 * form_factor(where[i], {0, 1, 0}, rect.light)), 1.0, 0.01) << i;
    EXPECT_NEAR(b[i].y / (3 * form_factor(where[i], {0, 1, 0}, round.light)), 1.0, 0.01) << i;
  }
  // Coaxial disc: F = r^2 / (h^2 + r^2); the 64-gon is within 0.2 % of the circle.
  EXPECT_NEAR(b[0].y / (3 * (1.5 * 1.5) / (4 + 1.5 * 1.5)), 1.0, 0.012);
}

TEST(Direct, ShadowsAndBackFacesGiveNothing) {
  Rig rig({{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}}, 64, /*blocker=*/true);
  auto out = rig.shade(points_at({{0, 0, 0}, {3, 0, 3}}));
  EXPECT_EQ(out[0], RGB{});  // the blocker hides the whole light
  EXPECT_GT(out[1].x, 0.0f);  // outside the blocker's shadow
  ShadingPoints below;
  below.push_back({0, 2, 0}, {0, 1, 0}, {0, 1, 0}, 0, 1);  // above the light, looking away from it
  EXPECT_EQ(rig.shade(below)[0], RGB{});
}

TEST(Direct, ResultOfAPointDoesNotDependOnItsBatch) {
  Rig rig({{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}}, 4);
  std::vector<Vec3> ps{{0.1f, 0, 0.2f}, {-0.3f, 0, 0.5f}, {0.7f, 0, -0.4f}};
  auto all = rig.shade(points_at(ps));
  ShadingPoints last;
  auto three = points_at(ps);
  last.push_back(three.position[2], three.normal[2], three.wo[2], 0, three.key[2]);
  EXPECT_EQ(rig.shade(last)[0], all[2]);  // bit for bit
}

TEST(Direct, PointLightGivesICosOverPiDSquared) {
  // A white diffuse floor under a point light: reflected radiance is I cos(theta) / (pi d^2), exactly.
  Scene s;
  auto white = s.add_material({"white", {1, 1, 1}, {}});
  s.add_quad({-10, 0, -10}, {-10, 0, 10}, {10, 0, 10}, {10, 0, -10}, white);
  s.add_point_light({1, 2, 0}, {8, 4, 2});
  ASSERT_TRUE(s.finalize("point").ok());
  RayTracer tracer(s);
  auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{}, "d"));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&s, &tracer}, none));
  ShadingPoints pts;
  pts.push_back({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, white, 1, 0);
  pts.push_back({3, 0, 1}, {0, 1, 0}, {0, 1, 0}, white, 2, 0);
  std::vector<RGB> out(2);
  run_to_completion(op->shade(pts, out, none));
  for (size_t i = 0; i < 2; ++i) {
    const Vec3 d = Vec3{1, 2, 0} - pts.position[i];
    const float d2 = dot(d, d), cos = d.y / std::sqrt(d2);
    EXPECT_NEAR(out[i].x, 8 * cos / (kPi * d2), 1e-5f) << i;
    EXPECT_NEAR(out[i].z, 2 * cos / (kPi * d2), 1e-5f) << i;
  }
}

TEST(Direct, BadParametersAreReported) {
  const auto& kind = *find_lightop_kind("direct");
  EXPECT_THROW(create_lightop(kind, ParamTable(Value::Map{{"light_samples", 0}}, "d")), ParamError);
  EXPECT_THROW(create_lightop(kind, ParamTable(Value::Map{{"samples", 4}}, "d")), ParamError);
}

}  // namespace lf
