// direct against closed forms: the radiance a white diffuse point reflects from a uniformly emitting polygon is
// L = Le * F, with F the point-to-polygon form factor (Lambert's contour formula).
#include <gtest/gtest.h>

#include <cmath>

#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
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

  Rig(const std::vector<Vec3>& light_polygon, int light_samples, bool blocker = false,
      SamplerKind sampler = SamplerKind::independent, Value::Map params = {}, float floor_half = 50)
      : light(light_polygon) {
    floor = scene.add_material({"white", {1, 1, 1}, {}});
    auto grey = scene.add_material({"grey", {0.5f, 0.5f, 0.5f}, {}});
    auto emitter = scene.add_material({"light", {0, 0, 0}, {2, 3, 4}});
    scene.add_quad({-floor_half, 0, -floor_half}, {-floor_half, 0, floor_half}, {floor_half, 0, floor_half},
                   {floor_half, 0, -floor_half}, floor);
    // Light polygon as a fan; the caller gives corners so that the winding faces down.
    for (size_t i = 1; i + 1 < light.size(); ++i) scene.add_triangle(light[0], light[i], light[i + 1], emitter);
    if (blocker) scene.add_quad({-1.2f, 0.5f, -1.2f}, {1.2f, 0.5f, -1.2f}, {1.2f, 0.5f, 1.2f}, {-1.2f, 0.5f, 1.2f}, grey);
    EXPECT_TRUE(scene.finalize("test").ok());
    tracer = std::make_unique<RayTracer>(scene);
    params["light_samples"] = light_samples;
    op = create_lightop(*find_lightop_kind("direct"), ParamTable(std::move(params), "lightop 'direct'"));
    SceneContext ctx{&scene, tracer.get()};
    ctx.sampler = sampler;
    run_to_completion(op->setup(ctx, none));
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

// The same points, each naming the floor triangle it lies on, as a renderer's camera hits do (a ray up from below).
static ShadingPoints points_on_floor(const Rig& rig, const std::vector<Vec3>& ps) {
  std::vector<Ray> up;
  for (const Vec3& p : ps) up.push_back(Ray{p - Vec3{0, 1, 0}, {0, 1, 0}});
  std::vector<Hit> hits(up.size());
  rig.tracer->intersect(up, hits);
  ShadingPoints pts;
  for (size_t i = 0; i < ps.size(); ++i) {
    EXPECT_EQ(rig.scene.material_of(hits[i].triangle), rig.floor);
    pts.push_back(ps[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0), hits[i].triangle);
  }
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

// The Sobol sampler (image { sampler = "sobol" }): a point's light samples are a scrambled Sobol net over the
// light's area, so the error falls much faster with samples than with independent numbers (N^-1 or better for this
// smooth, unoccluded integrand, against N^-1/2). Relative RMSE over 256 pixels, each its own scramble.
TEST(Direct, SobolLightSamplesConvergeFasterThanIndependentOnes) {
  const std::vector<Vec3> square{{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}};
  const double f = form_factor({0, 0, 0}, {0, 1, 0}, square);
  auto rmse = [&](SamplerKind kind, int samples) {
    Rig rig(square, samples, false, kind);
    ShadingPoints pts;
    for (uint64_t i = 0; i < 256; ++i)
      pts.push_back({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 0,
                    kind == SamplerKind::sobol ? sobol_sample_key(i, 0) : sample_key(i, 0));
    double sum = 0;
    for (const RGB& l : rig.shade(pts)) sum += (l.x / (2 * f) - 1) * (l.x / (2 * f) - 1);
    return std::sqrt(sum / 256);
  };
  const double independent16 = rmse(SamplerKind::independent, 16), independent256 = rmse(SamplerKind::independent, 256);
  const double sobol16 = rmse(SamplerKind::sobol, 16), sobol256 = rmse(SamplerKind::sobol, 256);
  // Independent: 16x the samples, 4x less error (within noise). Sobol: far more, and far less error at each count.
  EXPECT_NEAR(independent16 / independent256, 4.0, 1.0);
  EXPECT_GT(sobol16 / sobol256, 10.0) << sobol16 << " -> " << sobol256;
  EXPECT_LT(sobol16, 0.5 * independent16);
  EXPECT_LT(sobol256, 0.2 * independent256);
  std::printf("direct, relative RMSE at 16 / 256 light samples: independent %.5f / %.5f, sobol %.5f / %.5f\n",
              independent16, independent256, sobol16, sobol256);
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

// light_point = "solid_angle": the point on the light is drawn uniformly over the solid angle the light's triangle
// subtends, so it still gives Lambert's formula, and right under a wide light (where a uniform point on the area
// carries cos cos / d^2 weights that vary a lot) with far less noise.
TEST(Direct, SolidAngleLightPointsMatchLambertsFormulaWithLessNoiseUnderAWideLight) {
  const std::vector<Vec3> low{{-1, 0.2f, -1}, {1, 0.2f, -1}, {1, 0.2f, 1}, {-1, 0.2f, 1}};
  const Value::Map solid{{"light_point", "solid_angle"}};
  Rig exact(low, 20000, false, SamplerKind::independent, solid);
  const std::vector<Vec3> where{{0, 0, 0}, {0.9f, 0, 0.3f}, {1.5f, 0, -0.5f}};
  const auto got = exact.shade(points_at(where));
  for (size_t i = 0; i < where.size(); ++i)
    EXPECT_NEAR(got[i].y / (3 * form_factor(where[i], {0, 1, 0}, low)), 1.0, 0.01) << i;
  // With a BSDF sample too, MIS weighs each by the other's density, so the light's must be the solid-angle one. This
  // also checks where rays start: a BSDF ray that left the floor higher than the light sample's shadow ray sees the
  // light larger than the light sample did. Offsets of 1e-4 of the scene's diagonal (0.014 on this 100-wide floor,
  // 7 % of the light's height) gave 1.015 / 1.028 / 0.989 here; offsets from the floor's own float precision do not.
  Rig weighed(low, 100000, false, SamplerKind::independent, Value::Map{{"light_point", "solid_angle"}, {"mis", true}});
  const auto mixed = weighed.shade(points_on_floor(weighed, where));
  for (size_t i = 0; i < where.size(); ++i)
    EXPECT_NEAR(mixed[i].y / (3 * form_factor(where[i], {0, 1, 0}, low)), 1.0, 0.01) << "with mis, " << i;
  Rig by_area_weighed(low, 100000, false, SamplerKind::independent, Value::Map{{"mis", true}});
  const auto area_mixed = by_area_weighed.shade(points_on_floor(by_area_weighed, where));
  for (size_t i = 0; i < where.size(); ++i)
    EXPECT_NEAR(area_mixed[i].y / (3 * form_factor(where[i], {0, 1, 0}, low)), 1.0, 0.01) << "area points, mis, " << i;
  auto rmse = [&](Value::Map params) {
    Rig rig(low, 16, false, SamplerKind::independent, std::move(params));
    ShadingPoints pts;
    for (uint64_t i = 0; i < 256; ++i) pts.push_back({0.3f, 0, 0.2f}, {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0));
    const double f = form_factor({0.3f, 0, 0.2f}, {0, 1, 0}, low);
    double sum = 0;
    for (const RGB& l : rig.shade(pts)) sum += (l.y / (3 * f) - 1) * (l.y / (3 * f) - 1);
    return std::sqrt(sum / 256);
  };
  const double by_area = rmse({{"mis", false}}), by_solid_angle = rmse(solid);
  EXPECT_LT(by_solid_angle, 0.5 * by_area) << by_area << " -> " << by_solid_angle;
  std::printf("direct under a wide light, relative RMSE at 16 light samples: area %.4f, solid angle %.4f\n", by_area,
              by_solid_angle);
}

// Far from the origin a float's precision is coarse (6e-5 at 1000, 5e-4 at 5000) and a surface's own shadow rays
// can hit it again unless they start far enough above it: a ray origin that scales with the coordinates keeps a
// 4-wide floor under a 2x2 light as bright at 5000 units out as at the origin. (An offset of 1e-4 of the scene's
// diagonal, 6e-4 here, let the floor itself block 2-4 % of the light samples at 5000 units out.)
TEST(Direct, AFloorFarFromTheOriginIsLitAsAtTheOrigin) {
  for (const float away : {0.0f, 1000.0f, 5000.0f}) {
    SCOPED_TRACE(away);
    const Vec3 c{away, away, away};
    Scene scene;
    const uint32_t white = scene.add_material({"white", {1, 1, 1}, {}});
    const uint32_t emitter = scene.add_material({"light", {0, 0, 0}, {1, 1, 1}});
    scene.add_quad(c + Vec3{-2, 0, -2}, c + Vec3{-2, 0, 2}, c + Vec3{2, 0, 2}, c + Vec3{2, 0, -2}, white);
    const std::vector<Vec3> light{c + Vec3{-1, 1, -1}, c + Vec3{1, 1, -1}, c + Vec3{1, 1, 1}, c + Vec3{-1, 1, 1}};
    scene.add_quad(light[0], light[1], light[2], light[3], emitter);
    ASSERT_TRUE(scene.finalize("far").ok());
    RayTracer tracer(scene);
    auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 65536}}, "direct"));
    LocalInputs none;
    run_to_completion(op->setup(SceneContext{&scene, &tracer}, none));
    // Points on the floor where a camera 8 units away finds them (carrying that ray's rounding), naming the triangle.
    const std::vector<Vec3> where{{0.1f, 0, 0.2f}, {-0.7f, 0, 0.4f}, {1.3f, 0, -0.9f}};
    const Vec3 eye = c + Vec3{7, 3, 4};  // low enough to see under the light
    std::vector<Ray> down;
    for (const Vec3& w : where) down.push_back(Ray{eye, normalize(w - Vec3{7, 3, 4})});
    std::vector<Hit> hits(down.size());
    tracer.intersect(down, hits);
    ShadingPoints pts;
    for (size_t i = 0; i < where.size(); ++i) {
      ASSERT_TRUE(hits[i].valid());
      ASSERT_EQ(scene.material_of(hits[i].triangle), white);
      pts.push_back(down[i].origin + down[i].direction * hits[i].t, {0, 1, 0}, {0, 1, 0}, white, sample_key(i, 0),
                    hits[i].triangle);
    }
    std::vector<RGB> out(pts.size());
    run_to_completion(op->shade(pts, out, none));
    for (size_t i = 0; i < where.size(); ++i) {
      const std::vector<Vec3> light_here{light[0] - c, light[1] - c, light[2] - c, light[3] - c};
      EXPECT_NEAR(out[i].y / form_factor(pts.position[i] - c, {0, 1, 0}, light_here), 1.0, 0.01) << i;
    }
  }
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

// With `mis` unset (and no environment) a diffuse point takes a BSDF sample beside its light samples only where a
// light is near: within mis_reach (4) of its triangles' radii. There it is exactly mis = true's estimate, elsewhere
// exactly mis = false's; and right beside a small lamp it matches Lambert's formula with less noise than light
// samples alone.
TEST(Direct, UnsetMisTakesBsdfSamplesOnlyNearTheLights) {
  // A 0.2-wide lamp 0.03 above the floor: each of its triangles has a sphere of radius 0.14 around it, so points
  // within 0.57 of its centre are near.
  const std::vector<Vec3> lamp{{-0.1f, 0.03f, -0.1f}, {0.1f, 0.03f, -0.1f}, {0.1f, 0.03f, 0.1f}, {-0.1f, 0.03f, 0.1f}};
  const std::vector<Vec3> where{{0.05f, 0, 0}, {0.2f, 0, 0.1f}, {0.7f, 0, 0.3f}, {1.2f, 0, 0}};
  const bool near[] = {true, true, false, false};
  Rig unset(lamp, 4), with(lamp, 4, false, SamplerKind::independent, Value::Map{{"mis", true}}),
      without(lamp, 4, false, SamplerKind::independent, Value::Map{{"mis", false}});
  const auto u = unset.shade(points_on_floor(unset, where)), w = with.shade(points_on_floor(with, where)),
             o = without.shade(points_on_floor(without, where));
  for (size_t i = 0; i < where.size(); ++i) {
    EXPECT_GT(u[i].y, 0) << i;
    EXPECT_EQ(u[i].y, near[i] ? w[i].y : o[i].y) << i;
  }
  EXPECT_NE(u[0].y, o[0].y);  // MIS changes these estimates, so the equalities above say which rule was applied
  EXPECT_NE(u[1].y, o[1].y);
  // mis_reach = 0: no point is near; light samples alone everywhere.
  Rig none(lamp, 4, false, SamplerKind::independent, Value::Map{{"mis_reach", 0}});
  const auto z = none.shade(points_on_floor(none, where));
  for (size_t i = 0; i < where.size(); ++i) EXPECT_EQ(z[i].y, o[i].y) << i;

  // Beside the lamp: unbiased, and less noisy than light samples alone.
  auto relative_rmse = [&](Value::Map params) {
    Rig rig(lamp, 4, false, SamplerKind::independent, std::move(params));
    std::vector<Vec3> at(4096, Vec3{0.12f, 0, 0.02f});
    const ShadingPoints pts = points_on_floor(rig, at);
    const double f = form_factor(at[0], {0, 1, 0}, lamp);
    double sum = 0, mean = 0;
    for (const RGB& l : rig.shade(pts)) {
      sum += (l.y / (3 * f) - 1) * (l.y / (3 * f) - 1);
      mean += l.y / (3 * f) / static_cast<double>(at.size());
    }
    const double rmse = std::sqrt(sum / static_cast<double>(at.size()));
    EXPECT_NEAR(mean, 1.0, 4 * rmse / std::sqrt(static_cast<double>(at.size())));  // four standard errors
    return rmse;
  };
  const double light_only = relative_rmse({{"mis", false}}), near_lights = relative_rmse({});
  EXPECT_LT(near_lights, 0.6 * light_only) << light_only << " -> " << near_lights;
  std::printf("beside a small lamp, relative RMSE at 4 light samples: light samples alone %.4f, with MIS near lights %.4f\n",
              light_only, near_lights);
}

TEST(Direct, BadParametersAreReported) {
  const auto& kind = *find_lightop_kind("direct");
  EXPECT_THROW(create_lightop(kind, ParamTable(Value::Map{{"light_samples", 0}}, "d")), ParamError);
  EXPECT_THROW(create_lightop(kind, ParamTable(Value::Map{{"samples", 4}}, "d")), ParamError);
  EXPECT_THROW(create_lightop(kind, ParamTable(Value::Map{{"mis_reach", -1}}, "d")), ParamError);
}

}  // namespace lf

namespace lf {

// A closed room built as a voxel world is (Lost Empire: every block face its own pair of triangles), here with a
// single layer of unit faces on the integer grid and a point light inside. Shadow rays from points outside must
// never get through — not between faces sharing an edge, not at shared corners (the light on an integer position
// sees the lattice points outside through exactly those), not through the ray offset. Points inside are lit.
TEST(Direct, AClosedRoomOfSmallBlocksLeaksNoLight) {
  constexpr int kOuter = 8;  // the room is the cube [0,8]^3
  for (const Vec3 light : {Vec3{4, 4, 4}, Vec3{3.37f, 4.41f, 2.23f}}) {
    Scene scene;
    const uint32_t rock = scene.add_material({"rock", {0.8f, 0.8f, 0.8f}, {}});
    // Unit quads on a plane, wound to face `facing` (+1 or -1 along `axis`).
    auto face_grid = [&](int axis, float at, int lo, int hi, int facing) {
      for (int a = lo; a < hi; ++a)
        for (int b = lo; b < hi; ++b) {
          auto corner = [&](float u, float v) {
            Vec3 p;
            float* c = &p.x;
            c[axis] = at;
            c[(axis + 1) % 3] = u;
            c[(axis + 2) % 3] = v;
            return p;
          };
          const Vec3 p0 = corner(a, b), p1 = corner(a + 1, b), p2 = corner(a + 1, b + 1), p3 = corner(a, b + 1);
          if (facing > 0) scene.add_quad(p0, p1, p2, p3, rock);
          else scene.add_quad(p0, p3, p2, p1, rock);
        }
    };
    for (int axis = 0; axis < 3; ++axis) {
      face_grid(axis, 0, 0, kOuter, +1);  // the room's walls, facing in
      face_grid(axis, kOuter, 0, kOuter, -1);
    }
    scene.add_point_light(light, {100, 100, 100});
    ASSERT_TRUE(scene.finalize("blocks").ok());
    RayTracer tracer(scene);
    auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{}, "lightop 'direct'"));
    LocalInputs none;
    run_to_completion(op->setup(SceneContext{&scene, &tracer}, none));

    // Outside: planes one unit away from each wall, on a lattice of step 1/4 (from x = -1, a ray to the light at
    // x = 4 crosses the wall at 4/5 of the way: lattice points map onto the wall's edges and corners) and at
    // random points.
    ShadingPoints outside, inside;
    Rng rng(11, 0);
    auto add = [&](ShadingPoints& pts, int axis, float at, float sign, float u, float v) {
      Vec3 p, n;
      (&p.x)[axis] = at;
      (&p.x)[(axis + 1) % 3] = u;
      (&p.x)[(axis + 2) % 3] = v;
      (&n.x)[axis] = sign;
      pts.push_back(p, n, n, rock, sample_key(static_cast<uint32_t>(pts.size()), 0));
    };
    for (int axis = 0; axis < 3; ++axis)
      for (int side : {0, 1}) {
        const float wall = static_cast<float>(side * kOuter), toward = side ? -1.0f : 1.0f;
        for (int i = -4; i <= 4 * kOuter + 4; ++i)
          for (int j = -4; j <= 4 * kOuter + 4; ++j) add(outside, axis, wall - toward, toward, i / 4.0f, j / 4.0f);
        for (int k = 0; k < 500; ++k)
          add(outside, axis, wall - toward, toward, -1 + (kOuter + 2) * rng.uniform(), -1 + (kOuter + 2) * rng.uniform());
        for (int k = 0; k < 100; ++k)
          add(inside, axis, wall, toward, kOuter * rng.uniform(), kOuter * rng.uniform());
      }
    std::vector<RGB> out(outside.size()), in(inside.size());
    run_to_completion(op->shade(outside, out, none));
    run_to_completion(op->shade(inside, in, none));
    size_t leaks = 0, lit = 0;
    for (const RGB& c : out) leaks += !is_black(c);
    for (const RGB& c : in) lit += !is_black(c);
    EXPECT_EQ(leaks, 0u) << "light (" << light.x << ", " << light.y << ", " << light.z << "): " << leaks << " of "
                         << outside.size() << " points outside the room receive its light";
    EXPECT_EQ(lit, inside.size());
  }
}

}  // namespace lf

namespace lf {
namespace {

// A spot light one unit above a Lambert floor, shining down, cones of 0.2 and 0.4 radians: straight below it gives
// I / d^2, between the cones glTF's falloff (the square of the linear ramp in the cosine), outside nothing; the
// photon map's spot photons stay inside the cone.
TEST(DirectLight, ASpotLightsFalloffFollowsItsCones) {
  Scene s;
  const uint32_t floor = s.add_material({"floor", {0.5f, 0.5f, 0.5f}, {}});
  s.add_quad({-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}, floor);
  PointLight spot{{0, 0, 1}, {10, 10, 10}};
  spot.axis = {0, 0, -1};
  spot.cos_inner = std::cos(0.2f);
  spot.cos_outer = std::cos(0.4f);
  s.add_point_light(spot);
  ASSERT_TRUE(s.finalize("spot").ok());
  RayTracer tracer(s);
  ShadingPoints pts;
  const float angles[] = {0.0f, 0.15f, 0.3f, 0.5f};
  for (int i = 0; i < 4; ++i)
    pts.push_back({std::tan(angles[i]), 0, 0}, {0, 0, 1}, {0, 0, 1}, floor, sample_key(static_cast<uint64_t>(i), 0), 0);
  const auto out = test::shade_direct(SceneContext{&s, &tracer}, pts, "tree", 1);
  for (int i = 0; i < 4; ++i) {
    const float a = angles[i], c = std::cos(a);
    const float ramp = std::clamp((c - spot.cos_outer) / (spot.cos_inner - spot.cos_outer), 0.0f, 1.0f);
    // I(a) cos(a) / d^2 with d = 1 / cos(a), times rho / pi.
    const float expected = 0.5f / kPi * 10 * ramp * ramp * c * c * c;
    EXPECT_NEAR(out[static_cast<size_t>(i)].x, expected, 1e-4f * 10) << "at " << a << " radians";
  }
  EXPECT_GT(out[2].x, 0.0f);
  EXPECT_LT(out[2].x, out[1].x * 0.5f) << "between the cones, fading";
  EXPECT_EQ(out[3].x, 0.0f) << "outside the outer cone";
}

}  // namespace
}  // namespace lf
