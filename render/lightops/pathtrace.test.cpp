// pathtrace against closed forms, and direct against pathtrace.
#include <gtest/gtest.h>

#include <cmath>

#include "render/shading/bsdf.hpp"
#include "render/tracing/camera.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {
namespace {

std::vector<RGB> shade(const char* kind, Value::Map params, const Scene& scene, const RayTracer& tracer,
                       const ShadingPoints& pts) {
  auto op = create_lightop(*find_lightop_kind(kind), ParamTable(std::move(params), kind));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&scene, &tracer}, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  return out;
}

// A closed cube seen from inside: every face emits E and reflects rho (diffuse). Radiance everywhere is
// E / (1 - rho); the renderer adds the E it sees, so the reflected part a LightOp returns is rho E / (1 - rho).
// Paths of 4096 samples from 16 points, with `roulette` and `rr_threshold` (and the rule they follow: survival q
// for a throughput beta). Every path's throughput is the same function of its length here, so the mean path length
// follows from the rule: vertices 1-3 always (roulette starts after the third, when beta is rho^3), then each with
// probability q, the path carrying beta / q on.
void expect_furnace(const char* roulette, double rr_threshold, double (*survival)(double beta), double rho,
                    double& mean_vertices) {
  Scene s;
  const float e = 1.0f, r = static_cast<float>(rho);
  auto m = s.add_material({"furnace", {r, r, r}, {e, e, e}});
  test::add_closed_box(s, m);  // faces wound inwards
  ASSERT_TRUE(s.finalize("furnace").ok());
  RayTracer tracer(s);
  ShadingPoints pts;
  for (int i = 0; i < 8; ++i) {
    const float u = 0.1f + 0.1f * i;
    pts.push_back({u, 0.0f, 1 - u}, {0, 1, 0}, normalize(Vec3{0.3f, 1, 0.2f}), m, sample_key(i, 0));
    pts.push_back({0.0f, u, 0.5f}, {1, 0, 0}, {1, 0, 0}, m, sample_key(i, 1));
  }
  auto op = create_lightop(*find_lightop_kind("pathtrace"),
                           ParamTable(Value::Map{{"samples", 4096}, {"max_depth", 1000}, {"roulette", roulette},
                                                      {"rr_threshold", rr_threshold}},
                                           "pathtrace"));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&s, &tracer}, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  double mean = 0;
  for (const RGB& l : out) mean += l.y;
  mean /= static_cast<double>(out.size());
  EXPECT_NEAR(mean / (rho * e / (1 - rho)), 1.0, 0.02) << roulette << ", rho " << rho;
  EXPECT_NEAR((e + mean) / (e / (1 - rho)), 1.0, 0.02) << "total radiance vs E / (1 - rho)";
  const Value st = op->stats();
  EXPECT_EQ(st.find("paths")->as_int(), 4096 * 16);
  double expected = 3, reach = 1, beta = rho * rho * rho;
  for (int k = 0; k < 2000; ++k) {
    const double q = survival(beta);
    reach *= q;
    expected += reach;
    beta = beta / q * rho;
  }
  mean_vertices = st.find("mean_path_vertices")->as_double();
  EXPECT_NEAR(mean_vertices / expected, 1.0, 0.02) << roulette << ", rho " << rho;
}

TEST(PathTrace, FurnaceConvergesToEOverOneMinusRho) {
  for (double rho : {0.5, 0.8}) {
    double vertices = 0;
    expect_furnace("throughput", 1.0, [](double beta) { return std::min(0.95, beta); }, rho, vertices);
    // The rule in closed form: the fourth vertex with probability rho^3, each later one with probability rho.
    EXPECT_NEAR(vertices / (3 + rho * rho * rho / (1 - rho)), 1.0, 0.02) << "rho " << rho;
  }
}

// Roulette by the square root of the throughput ends fewer paths; it must stay unbiased, and end them as its rule
// says: Cycles' rule (rr_threshold 1), and the default, which ends no path whose throughput is a quarter or more.
TEST(PathTrace, SqrtRouletteIsUnbiasedInTheFurnace) {
  for (double rho : {0.5, 0.8}) {
    double cycles = 0, quarter = 0;
    expect_furnace("sqrt", 1.0, [](double beta) { return std::min(1.0, std::sqrt(beta)); }, rho, cycles);
    EXPECT_GT(cycles, 3 + rho * rho * rho / (1 - rho)) << "longer paths than roulette by the throughput";
    expect_furnace("sqrt", 0.25, [](double beta) { return std::min(1.0, std::sqrt(beta / 0.25)); }, rho, quarter);
    EXPECT_GT(quarter, cycles) << "longer paths than Cycles' rule, rho " << rho;
  }
}

// Roulette by the square root, below a quarter, is the default (docs/decisions.md, "Roulette by the square root",
// "Roulette below a quarter"): a pathtrace op without `roulette` or `rr_threshold` shades exactly as one with "sqrt"
// and 0.25, and not as one with "throughput" or with Cycles' threshold of 1.
TEST(PathTrace, SqrtRouletteIsTheDefault) {
  auto scene = Scene::builtin("cornell");
  ASSERT_TRUE(scene.ok());
  RayTracer tracer(*scene);
  ShadingPoints pts;
  for (int i = 0; i < 16; ++i)
    pts.push_back({0.1f + 0.05f * i, 0.0f, 0.3f}, {0, 1, 0}, {0, 1, 0}, scene->material_of(0), sample_key(i, 0));
  const auto by_default = shade("pathtrace", Value::Map{{"samples", 64}}, *scene, tracer, pts);
  EXPECT_EQ(by_default, shade("pathtrace", Value::Map{{"samples", 64}, {"roulette", "sqrt"}, {"rr_threshold", 0.25}},
                              *scene, tracer, pts));
  EXPECT_NE(by_default, shade("pathtrace", Value::Map{{"samples", 64}, {"roulette", "throughput"}}, *scene, tracer, pts));
  EXPECT_NE(by_default, shade("pathtrace", Value::Map{{"samples", 64}, {"rr_threshold", 1.0}}, *scene, tracer, pts));
}

struct Estimate {
  std::vector<double> mean, se2;  // per point, green channel: mean and squared standard error over seeds
};

Estimate estimate(const char* kind, const char* samples_key, int samples, const Scene& scene, const RayTracer& tracer,
                  const ShadingPoints& pts, Value::Map extra = {}) {
  const int seeds = 8;
  std::vector<std::vector<double>> runs;
  for (int seed = 0; seed < seeds; ++seed) {
    Value::Map params = extra;
    params[samples_key] = samples;
    params["seed"] = seed;
    auto out = shade(kind, params, scene, tracer, pts);
    std::vector<double> g;
    for (const RGB& l : out) g.push_back(l.y);
    runs.push_back(std::move(g));
  }
  Estimate e;
  for (size_t i = 0; i < pts.size(); ++i) {
    double m = 0, v = 0;
    for (const auto& r : runs) m += r[i];
    m /= seeds;
    for (const auto& r : runs) v += (r[i] - m) * (r[i] - m);
    e.mean.push_back(m);
    e.se2.push_back(v / (seeds - 1) / seeds);
  }
  return e;
}

// Two unbiased estimators of the same direct light: their squared differences average to the sum of their
// squared standard errors. The bound, 1.3 times that sum, leaves room for the error in estimating the errors
// (8 seeds) and fails a bias of a few percent of the signal.
void expect_same_direct_light(const Scene& scene, const ShadingPoints& pts, const char* what) {
  RayTracer tracer(scene);
  auto direct = estimate("direct", "light_samples", 16, scene, tracer, pts);
  auto path = estimate("pathtrace", "samples", 16, scene, tracer, pts, Value::Map{{"max_depth", 1}});
  double diff2 = 0, se2 = 0, signal = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    diff2 += (direct.mean[i] - path.mean[i]) * (direct.mean[i] - path.mean[i]);
    se2 += direct.se2[i] + path.se2[i];
    signal += direct.mean[i];
  }
  ASSERT_GT(signal, 0) << what;
  EXPECT_LT(diff2, 1.3 * se2) << what << ": RMSE " << std::sqrt(diff2 / pts.size()) << " vs expected "
                              << std::sqrt(se2 / pts.size());
}

ShadingPoints camera_points(const Scene& scene, const CameraSpec& cam, int size) {
  RayTracer tracer(scene);
  ImageSpec image;
  image.width = image.height = size;
  image.spp = 1;
  Camera camera(cam, size, size);
  TileWork work;
  trace_tile(scene, tracer, camera, image, TileRect{0, 0, size, size}, work);
  return work.points;
}

// The Sobol sampler on the furnace: every path's first vertices are stratified over a pixel's samples, so the error
// over 256 points (pixels) falls faster with samples than with independent numbers, and the mean stays E/(1 - rho).
TEST(PathTrace, SobolPathsConvergeFasterInTheFurnace) {
  const float rho = 0.5f, e = 1.0f;
  Scene s;
  auto m = s.add_material({"furnace", {rho, rho, rho}, {e, e, e}});
  test::add_closed_box(s, m);
  ASSERT_TRUE(s.finalize("furnace").ok());
  RayTracer tracer(s);
  const double expected = rho * e / (1 - rho);
  auto rmse = [&](SamplerKind kind, int samples, double& mean) {
    ShadingPoints pts;
    for (uint64_t i = 0; i < 256; ++i)
      pts.push_back({0.3f, 0.0f, 0.6f}, {0, 1, 0}, normalize(Vec3{0.3f, 1, 0.2f}), m,
                    kind == SamplerKind::sobol ? sobol_sample_key(i, 0) : sample_key(i, 0));
    auto op = create_lightop(*find_lightop_kind("pathtrace"),
                             ParamTable(Value::Map{{"samples", samples}, {"max_depth", 1000}}, "pathtrace"));
    LocalInputs none;
    SceneContext ctx{&s, &tracer};
    ctx.sampler = kind;
    run_to_completion(op->setup(ctx, none));
    std::vector<RGB> out(pts.size());
    run_to_completion(op->shade(pts, out, none));
    double sum = 0;
    mean = 0;
    for (const RGB& l : out) {
      sum += (l.y / expected - 1) * (l.y / expected - 1);
      mean += l.y / 256;
    }
    return std::sqrt(sum / 256);
  };
  double mean = 0;
  const double independent16 = rmse(SamplerKind::independent, 16, mean), independent256 = rmse(SamplerKind::independent, 256, mean);
  const double sobol16 = rmse(SamplerKind::sobol, 16, mean), sobol256 = rmse(SamplerKind::sobol, 256, mean);
  std::printf("furnace, relative RMSE at 16 / 256 paths: independent %.5f / %.5f, sobol %.5f / %.5f\n", independent16,
              independent256, sobol16, sobol256);
  EXPECT_NEAR(mean / expected, 1.0, 0.01) << "the Sobol sampler is unbiased";
  // The furnace's error is mostly Russian roulette's (every direction sees the same walls), a 1D decision per
  // vertex: Sobol gains less here than on a light's area, but it gains at every count and falls faster.
  EXPECT_NEAR(independent16 / independent256, 4.0, 1.0);
  EXPECT_GT(sobol16 / sobol256, independent16 / independent256);
  EXPECT_LT(sobol16, independent16);
  EXPECT_LT(sobol256, 0.8 * independent256);
}

TEST(PathTrace, DirectMatchesPathTraceLimitedToDirectLightOnTheCornellBox) {
  auto scene = Scene::builtin("cornell");
  expect_same_direct_light(*scene, camera_points(*scene, CameraSpec{}, 24), "cornell");
}

// The direct light a glossy point reflects from a quad light, by midpoint quadrature over the light's area (no
// occluders in the scene): an independent reference for what MIS estimates.
double quadrature(const Scene& s, const Bsdf& bsdf, Vec3 x, Vec3 n, Vec3 wo, const Vec3 q[4], RGB le) {
  const int grid = 400;
  const Vec3 e1 = q[1] - q[0], e2 = q[3] - q[0];
  const Vec3 ln = normalize(cross(e1, e2));
  const float da = length(cross(e1, e2)) / (grid * grid);
  double sum = 0;
  for (int a = 0; a < grid; ++a)
    for (int b = 0; b < grid; ++b) {
      const Vec3 y = q[0] + e1 * ((a + 0.5f) / grid) + e2 * ((b + 0.5f) / grid);
      const Vec3 d = y - x;
      const float d2 = dot(d, d);
      const Vec3 wi = d / std::sqrt(d2);
      const float cx = dot(n, wi), cy = -dot(ln, wi);
      if (cx <= 0 || cy <= 0) continue;
      sum += bsdf.eval(n, wo, wi).y * le.y * cx * cy / d2 * da;
    }
  (void)s;
  return sum;
}

TEST(PathTrace, DirectAndPathTraceMatchQuadratureOnGlossySurfaces) {
  // A glossy floor under a tilted rectangular light: light sampling alone would be noisy here, so direct uses MIS.
  Scene s;
  const Material glossy = material_from_mtl("glossy", {0.2f, 0.2f, 0.2f}, {0.7f, 0.7f, 0.7f}, {}, 60, 1, 2);
  auto floor = s.add_material(glossy);
  auto light = s.add_material({"light", {}, {5, 5, 5}});
  const Vec3 q[4] = {{-0.5f, 1.2f, -0.3f}, {0.5f, 1.2f, -0.3f}, {0.5f, 1.0f, 0.3f}, {-0.5f, 1.0f, 0.3f}};
  s.add_quad({-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, floor);
  s.add_quad(q[0], q[1], q[2], q[3], light);
  ASSERT_TRUE(s.finalize("glossy").ok());
  RayTracer tracer(s);
  ShadingPoints pts;
  std::vector<double> reference;
  for (int i = 0; i < 40; ++i) {
    const float x = -1.2f + 2.4f * (i % 8) / 7.0f, z = -1.0f + 2.0f * (i / 8) / 4.0f;
    const Vec3 wo = normalize(Vec3{-x * 0.3f, 1.0f, 1.5f - z});
    pts.push_back({x, 0, z}, {0, 1, 0}, wo, floor, sample_key(i, 0), 0);
    reference.push_back(quadrature(s, Bsdf(s.material(floor)), {x, 0, z}, {0, 1, 0}, wo, q, {5, 5, 5}));
  }
  for (const char* kind : {"direct", "pathtrace"}) {
    auto e = estimate(kind, kind == std::string("direct") ? "light_samples" : "samples", 256, s, tracer, pts,
                      kind == std::string("direct") ? Value::Map{} : Value::Map{{"max_depth", 1}});
    double sum = 0, ref = 0, worst = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      sum += e.mean[i];
      ref += reference[i];
      worst = std::max(worst, std::abs(e.mean[i] - reference[i]) / std::sqrt(e.se2[i] + 1e-12));
    }
    // The total over the points within 2 %, and no point further than 6 of its standard errors from quadrature.
    EXPECT_NEAR(sum / ref, 1.0, 0.02) << kind;
    EXPECT_LT(worst, 6.0) << kind;
  }
}

TEST(Combine, SumsItsInputsWithWeights) {
  auto scene = Scene::builtin("cornell");
  RayTracer tracer(*scene);
  auto pts = camera_points(*scene, CameraSpec{}, 16);
  auto direct = shade("direct", Value::Map{{"light_samples", 2}}, *scene, tracer, pts);
  auto emitted = shade("emission", Value::Map{}, *scene, tracer, pts);

  auto d = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 2}}, "d"));
  auto e = create_lightop(*find_lightop_kind("emission"), ParamTable(Value::Map{}, "e"));
  auto c = create_lightop(*find_lightop_kind("combine"),
                          ParamTable(Value::Map{{"weights", Value::Array{2.0, 0.5}}}, "c"));
  LocalInputs none;
  SceneContext ctx{&*scene, &tracer};
  run_to_completion(d->setup(ctx, none));
  run_to_completion(e->setup(ctx, none));
  LocalInputs inputs({{d.get(), &none}, {e.get(), &none}});
  run_to_completion(c->setup(ctx, inputs));
  std::vector<RGB> out(pts.size());
  run_to_completion(c->shade(pts, out, inputs));
  int lit = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    EXPECT_EQ(out[i], direct[i] * 2.0f + emitted[i] * 0.5f) << i;
    lit += !is_black(emitted[i]);
  }
  EXPECT_GT(lit, 0) << "some points lie on the light";

  LocalInputs one({{d.get(), &none}});
  EXPECT_THROW(run_to_completion(c->setup(ctx, one)), LightOpError);  // two weights, one input
}

}  // namespace
}  // namespace lf
