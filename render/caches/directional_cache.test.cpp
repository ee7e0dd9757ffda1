// The directional cache (Jansen & Reinhard, §3.2): its quadtree's rule, and the path tracer with it against closed
// forms and against itself without it.
#include "render/caches/directional_cache.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "render/tracing/camera.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {
namespace {

Scene unit_box_scene() {
  Scene s;
  const uint32_t m = s.add_material({"white", {0.5f, 0.5f, 0.5f}, {1, 1, 1}});
  test::add_closed_box(s, m);
  EXPECT_TRUE(s.finalize("box").ok());
  return s;
}

TEST(DirectionalCache, ALeafAnswersOnlyOnceDeepEnoughAndSampledEnough) {
  Scene s = unit_box_scene();
  DirectionalCacheOptions o;
  o.cells = 2;
  o.min_samples = 4;
  o.uniform_depth = 2;
  o.max_depth = 4;
  o.max_relative_spread = 1.5;
  DirectionalCache cache(s, o);
  const uint32_t cell = cache.cell_of({0.25f, 0.25f, 0.25f});
  const Vec3 d = normalize(Vec3{0.3f, 0.2f, 0.9f});
  RGB got;
  EXPECT_FALSE(cache.lookup(cell, d, got)) << "an empty cell answers nothing";
  // Constant light from one direction: the leaf splits every 4 rays (the root, then depth 1) down to depth 2; its
  // children start with one ray, so 3 more make 4 there, and then it answers.
  int recorded = 0;
  while (!cache.lookup(cell, d, got) && recorded < 100) {
    cache.record(cell, d, {2, 2, 2});
    ++recorded;
  }
  EXPECT_EQ(recorded, 4 + 3 + 3);
  EXPECT_FLOAT_EQ(got.x, 2.0f);
  EXPECT_EQ(cache.nodes(), 1u + 4u + 4u);
  // Smooth light stops splitting at the uniform depth; uneven light goes on down to max_depth.
  const Vec3 e = normalize(Vec3{-0.5f, 0.1f, -0.8f});
  for (int i = 0; i < 200; ++i) cache.record(cell, e, {i % 8 ? 0.0f : 40.0f, i % 8 ? 0.0f : 40.0f, 0});  // spread ~2.6
  EXPECT_TRUE(cache.lookup(cell, e, got)) << "a leaf as deep as allowed answers however uneven";
  EXPECT_GT(cache.nodes(), 1u + 4u + 4u + 4u + 4u) << "uneven light split its leaves below the uniform depth";
  // Frozen: nothing more is recorded.
  const size_t nodes = cache.nodes();
  cache.freeze();
  for (int i = 0; i < 50; ++i) cache.record(cache.cell_of({0.75f, 0.75f, 0.75f}), d, {1, 1, 1});
  EXPECT_EQ(cache.nodes(), nodes);
}

TEST(DirectionalCache, TheNeighbourhoodEndsWhereARayLeavesTheSphere) {
  Scene s = unit_box_scene();
  DirectionalCacheOptions o;
  o.cells = 2;
  o.radius = 1;
  DirectionalCache cache(s, o);
  const uint32_t cell = cache.cell_of({0.25f, 0.25f, 0.25f});
  const Vec3 c = cache.centre_of(cell);
  EXPECT_NEAR(c.x, 0.25f, 1e-6f);
  EXPECT_NEAR(cache.radius(), 0.5f * std::sqrt(3.0f) / 2, 1e-6f);
  EXPECT_NEAR(cache.local_reach(cell, c, {1, 0, 0}), cache.radius(), 1e-6f);
}

// Shades points on the walls of an emitting furnace (every face emits 1 and reflects rho) with pathtrace, with or
// without the cache; returns the mean of the reflected radiance and the op's figures.
struct FurnaceResult {
  double mean = 0;
  Value stats;
  std::vector<RGB> radiance;
};

FurnaceResult furnace(float rho, Value::Map params, bool glossy = false) {
  Scene s;
  Material furnace_material{"furnace", {rho, rho, rho}, {1, 1, 1}};
  if (glossy) {  // rho split between Lambert and a Phong lobe
    furnace_material.type = Material::Type::glossy;
    furnace_material.kd = {0.6f * rho, 0.6f * rho, 0.6f * rho};
    furnace_material.ks = {0.4f * rho, 0.4f * rho, 0.4f * rho};
    furnace_material.ns = 20;
  }
  const uint32_t m = s.add_material(furnace_material);
  test::add_closed_box(s, m);
  EXPECT_TRUE(s.finalize("furnace").ok());
  RayTracer tracer(s);
  Camera camera(CameraSpec{{0.5f, 0.5f, 0.05f}, {0.5f, 0.5f, 1}, {0, 1, 0}, 90}, 32, 32);
  SceneContext ctx{&s, &tracer};
  ctx.camera = &camera;
  ctx.width = ctx.height = 32;
  auto op = create_lightop(*find_lightop_kind("pathtrace"), ParamTable(std::move(params), "pathtrace"));
  LocalInputs none;
  run_to_completion(op->setup(ctx, none));
  ShadingPoints pts;
  for (int i = 0; i < 64; ++i) {
    const float u = 0.05f + 0.9f * static_cast<float>(i % 8) / 7, v = 0.05f + 0.9f * static_cast<float>(i / 8) / 7;
    pts.push_back({u, 0.0f, v}, {0, 1, 0}, normalize(Vec3{0.2f, 1, 0.1f}), m, sample_key(static_cast<uint64_t>(i), 0));
  }
  FurnaceResult r;
  r.radiance.assign(pts.size(), RGB{});
  run_to_completion(op->shade(pts, r.radiance, none));
  for (const RGB& c : r.radiance) r.mean += average(c);
  r.mean /= static_cast<double>(pts.size());
  r.stats = op->stats();
  return r;
}

// The furnace still gives E / (1 - rho) (the renderer adds E, the op returns rho E / (1 - rho)) when most rays
// leaving a cell's neighbourhood are answered by the cache.
TEST(DirectionalCache, AFurnaceStillGivesEOverOneMinusRho) {
  for (float rho : {0.5f, 0.8f}) {
    SCOPED_TRACE(rho);
    const auto r = furnace(rho, Value::Map{{"samples", 2048}, {"max_depth", 1000}, {"directional_cache", true},
                                           {"cache_cells", 4}, {"cache_radius", 1.0}, {"cache_fill_spp", 256},
                                           {"rr_threshold", 1.0}});
    const double expected = rho / (1 - rho);
    // The cache reads 1.6-2.2 % low at rho = 0.8, where plain path tracing gives 4.003: with roulette by the
    // throughput 3.9205 (rays offset by 1e-4 of the scene's diagonal), 3.9169 (offsets from float precision; 3.917-3.921
    // for 16 to 4096 ulps); by its square root, Cycles' rule as pinned here, 3.934, then 3.914 with one hash per Sobol
    // dimension, which moves every sample (so this figure's own noise is about half a percent). It is the cache's own
    // bias: the same without variance-driven splits (cache_spread 1e9: 3.932), gone when a leaf needs 64 rays to answer
    // (4.021), so it comes from leaves that answer from a few rays, and it needs the fill to answer as it goes: with
    // lookups refused until the cache is frozen the furnace reads 4.012 (3.994 with roulette below a quarter), but the
    // fill then traces whole paths and bench/dircache_bench's bytes sent rise from 0.48x to 0.68x. With the default
    // roulette (rr_threshold 0.25: longer paths, through more answers) it reads 3.903; roulette is pinned to Cycles'
    // rule so that this bound watches the cache, not the roulette. Since BSDF rays start on the line from their
    // vertex (Scene::ray_origin_along) it reads 3.897, and 3.880 / 3.901 / 3.895 with seeds 1-3 (3.898 / 3.913 /
    // 3.907 before), while plain path tracing reads 3.997: the cache's bias, 2.5-3 %.
    EXPECT_NEAR(r.mean, expected, 0.03 * expected);
    const double ratio = r.stats.find("cache_hit_ratio")->as_double();
    EXPECT_GT(ratio, 0.5) << "the cache must do the work being checked " << to_json(r.stats);
  }
}

// A glossy furnace (every face Lambert 0.48 plus a Phong lobe 0.32, n = 20): the cache answers the rays the diffuse
// lobe sends (the vertex takes its lobes one at a time), the lobe's own rays are traced, and the light is the plain
// path tracer's.
TEST(DirectionalCache, AGlossyFurnaceKeepsItsLightWithTheCacheOnItsDiffuseLobe) {
  const Value::Map common{{"samples", 1024}, {"max_depth", 1000}, {"rr_threshold", 1.0}};
  Value::Map cached = common;
  for (auto& [k, v] : Value::Map{{"directional_cache", true}, {"cache_cells", 4}, {"cache_radius", 1.0},
                                 {"cache_fill_spp", 256}})
    cached.emplace(k, v);
  const auto plain = furnace(0.8f, common, true);
  const auto with_cache = furnace(0.8f, cached, true);
  EXPECT_NEAR(with_cache.mean / plain.mean, 1.0, 0.025) << plain.mean << " vs " << with_cache.mean;
  const double ratio = with_cache.stats.find("cache_hit_ratio")->as_double();
  EXPECT_GT(ratio, 0.5) << to_json(with_cache.stats);
  std::printf("glossy furnace: plain %.4f, cached %.4f, hit ratio %.3f\n", plain.mean, with_cache.mean, ratio);
}

// With the neighbourhood wider than the scene no ray ever leaves it: the cache is never asked, and every pixel is
// plain path tracing's, bit for bit (an open scene: the Cornell box, whose front is open).
TEST(DirectionalCache, ANeighbourhoodBeyondTheSceneIsPlainPathTracing) {
  auto scene = Scene::builtin("cornell");
  ASSERT_TRUE(scene);
  RayTracer tracer(*scene);
  const int w = 24, h = 24;
  Camera camera(CameraSpec{}, w, h);
  ShadingPoints pts;
  std::vector<Ray> rays;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rays.push_back(camera.ray(x + 0.5f, y + 0.5f));
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].valid()) continue;
    const Vec3 wo = -rays[i].direction;
    Vec3 n = scene->normal(hits[i].triangle);
    if (dot(n, wo) < 0) n = -n;
    pts.push_back(rays[i].origin + rays[i].direction * hits[i].t, n, wo, scene->material_of(hits[i].triangle),
                  pixel_sample_key(SamplerKind::sobol, i, 0), hits[i].triangle);
  }
  auto shade = [&](Value::Map params) {
    SceneContext ctx{&*scene, &tracer};
    ctx.camera = &camera;
    ctx.width = w;
    ctx.height = h;
    auto op = create_lightop(*find_lightop_kind("pathtrace"), ParamTable(std::move(params), "pathtrace"));
    LocalInputs none;
    run_to_completion(op->setup(ctx, none));
    std::vector<RGB> out(pts.size());
    run_to_completion(op->shade(pts, out, none));
    return std::make_pair(out, op->stats());
  };
  const auto plain = shade(Value::Map{{"max_depth", 6}, {"samples", 4}});
  const auto wide = shade(Value::Map{{"max_depth", 6}, {"samples", 4}, {"directional_cache", true},
                                     {"cache_radius", 1e6}});
  EXPECT_TRUE(plain.first == wide.first);
  // Only rays that leave the scene through its open front leave the neighbourhood (the cache has nothing but
  // darkness for them): fewer than half as many as those that stay.
  EXPECT_GT(wide.second.find("local_rays")->as_int(), 2 * wide.second.find("global_rays")->as_int());
  // And with a neighbourhood smaller than the room, the cache answers: a different estimate of the same light.
  const auto near = shade(Value::Map{{"max_depth", 6}, {"samples", 4}, {"directional_cache", true},
                                     {"cache_cells", 2}, {"cache_radius", 1.0}, {"cache_fill_spp", 256}});
  EXPECT_GT(near.second.find("cache_hit_ratio")->as_double(), 0.3) << to_json(near.second);
  double a = 0, b = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    a += average(plain.first[i]);
    b += average(near.first[i]);
  }
  EXPECT_NEAR(b / a, 1.0, 0.05) << "the image's mean, with and without the cache";
}

// The more rays fill the cache, the more of the rays leaving a neighbourhood it answers.
TEST(DirectionalCache, TheHitRatioRisesWithTheFillSamples) {
  double last = -1;
  for (int fill : {1, 4, 16}) {
    const auto r = furnace(0.5f, Value::Map{{"samples", 64}, {"max_depth", 8}, {"directional_cache", true},
                                            {"cache_cells", 4}, {"cache_radius", 1.0}, {"cache_fill_spp", fill}});
    const double ratio = r.stats.find("cache_hit_ratio")->as_double();
    EXPECT_GT(ratio, last) << fill << " fill samples: " << to_json(r.stats);
    last = ratio;
  }
}

}  // namespace
}  // namespace lf
