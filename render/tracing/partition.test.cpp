#include "render/tracing/partition.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "render/tracing/camera.hpp"
#include "render/shading/tile_kernel.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

// Rays that start anywhere in the scene's box (and a little outside it), in every direction, some with a finite
// tfar: the mix of camera, shadow and bounce rays a farm traces, without favouring any part.
std::vector<Ray> random_rays(const Scene& scene, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  const Bounds b = scene.bounds();
  const Vec3 size = b.hi - b.lo;
  std::vector<Ray> rays;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 o = b.lo + Vec3{size.x * (1.2f * u(rng) - 0.1f), size.y * (1.2f * u(rng) - 0.1f),
                               size.z * (1.2f * u(rng) - 0.1f)};
    const float z = 2 * u(rng) - 1, phi = 6.2831853f * u(rng), r = std::sqrt(std::max(0.0f, 1 - z * z));
    Ray ray{o, {r * std::cos(phi), r * std::sin(phi), z}};
    if (i % 3 == 0) ray.tfar = u(rng) * b.diagonal() * 0.5f;
    rays.push_back(ray);
  }
  return rays;
}

// The camera's rays through every pixel centre and a jittered point, at width x height.
std::vector<Ray> camera_rays(const CameraSpec& spec, int width, int height) {
  Camera camera(spec, width, height);
  std::vector<Ray> rays;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      rays.push_back(camera.ray(x + 0.5f, y + 0.5f));
      rays.push_back(camera.ray(x + 0.25f, y + 0.7f));
    }
  return rays;
}

// Every ray's hit (triangle and distance, exactly) and occlusion through the parts equal the whole scene's BVH.
void expect_same_as_whole(const Scene& scene, const std::vector<Ray>& rays, int parts, const std::string& what) {
  SCOPED_TRACE(what + ", " + std::to_string(parts) + " parts");
  RayTracer whole(scene);
  PartitionedTracer split(scene, partition_scene(scene, parts));
  ASSERT_EQ(split.parts().size(), static_cast<size_t>(parts));
  std::vector<Hit> expected(rays.size()), got(rays.size());
  whole.intersect(rays, expected);
  split.intersect(rays, got);
  size_t differ = 0, hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    hits += expected[i].valid() ? 1 : 0;
    if (expected[i].triangle != got[i].triangle || (expected[i].valid() && expected[i].t != got[i].t)) ++differ;
  }
  EXPECT_EQ(differ, 0u) << "of " << rays.size() << " rays";
  EXPECT_GT(hits, rays.size() / 4);  // the rays do meet the scene
  std::vector<uint8_t> blocked_whole(rays.size()), blocked_split(rays.size());
  whole.occluded(rays, blocked_whole);
  split.occluded(rays, blocked_split);
  EXPECT_TRUE(blocked_whole == blocked_split);
  // Some rays needed more than one part (the routing is exercised).
  uint64_t visits = 0;
  for (uint64_t v : split.rays_per_part()) visits += v;
  EXPECT_GT(visits, rays.size());
}

TEST(Partition, EveryTriangleIsInOnePartAndCostsAreEven) {
  auto scene = Scene::builtin("room");
  ASSERT_TRUE(scene);
  for (int n : {1, 2, 3, 5, 8}) {
    auto parts = partition_scene(*scene, n);
    ASSERT_EQ(parts.size(), static_cast<size_t>(n));
    std::vector<int> owner(scene->triangle_count(), 0);
    double total = 0, most = 0;
    for (const ScenePart& p : parts) {
      EXPECT_FALSE(p.triangles.empty());
      EXPECT_TRUE(std::is_sorted(p.triangles.begin(), p.triangles.end()));
      for (uint32_t t : p.triangles) {
        ++owner[t];
        for (int c = 0; c < 3; ++c) {
          const Vec3 v = scene->vertex(t, c);
          EXPECT_TRUE(v.x >= p.bounds.lo.x && v.y >= p.bounds.lo.y && v.z >= p.bounds.lo.z && v.x <= p.bounds.hi.x &&
                      v.y <= p.bounds.hi.y && v.z <= p.bounds.hi.z);
        }
      }
      total += p.cost;
      most = std::max(most, p.cost);
    }
    EXPECT_TRUE(std::all_of(owner.begin(), owner.end(), [](int o) { return o == 1; })) << n << " parts";
    EXPECT_NEAR(total, 1.0, 1e-9);
    // Bisection at the running cost: within a few triangles' cost of even (the room has few, large triangles).
    EXPECT_LE(most * n, 1.35) << n << " parts";
  }
}

TEST(Partition, AScanOfFewerTrianglesThanPartsMakesOnePartPerTriangle) {
  Scene s;
  const uint32_t m = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {1, 1, 1}});
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, m);
  ASSERT_TRUE(s.finalize("quad"));
  auto parts = partition_scene(s, 5);
  EXPECT_EQ(parts.size(), 2u);
}

TEST(Partition, HitsThroughPartsEqualTheWholeSceneOnTheBuiltins) {
  for (const char* name : {"cornell", "room"}) {
    auto scene = Scene::builtin(name);
    ASSERT_TRUE(scene);
    const auto rays = random_rays(*scene, 20000, 7);
    for (int parts : {2, 3, 5}) expect_same_as_whole(*scene, rays, parts, name);
  }
}

TEST(Partition, HitsThroughPartsEqualTheWholeSceneOnLostEmpire) {
  auto loaded = test::lost_empire_with_torches();
  if (!loaded) GTEST_SKIP() << "no " << test::kLostEmpireObj;
  auto& scene = *loaded;
  ASSERT_TRUE(scene) << scene.error().message;
  auto rays = random_rays(*scene, 20000, 11);
  const auto view = camera_rays(CameraSpec{{-8, 16, 20}, {6, 12, 0}, {0, 1, 0}, 70}, 80, 60);
  rays.insert(rays.end(), view.begin(), view.end());
  for (int parts : {2, 3, 5}) expect_same_as_whole(*scene, rays, parts, "lost_empire");
  // The cost-based split evens the estimate out.
  for (int parts : {2, 3, 5}) {
    double most = 0;
    for (const ScenePart& p : partition_scene(*scene, parts)) most = std::max(most, p.cost);
    EXPECT_LE(most * parts, 1.01) << parts << " parts";
  }
}

// A renderer traces a tile's camera rays as one coherent stream (Embree's SIMD packets); through parts they are
// traced ray by ray. Both must give the same hits, or a partitioned farm's camera would see another image.
void expect_tiles_coherent_as_single(const Scene& scene, const CameraSpec& spec, int width, int height, int spp,
                                     const std::string& what) {
  SCOPED_TRACE(what);
  RayTracer tracer(scene);
  const Camera camera(spec, width, height);
  ImageSpec image;
  image.width = width;
  image.height = height;
  image.spp = spp;
  image.sampler = "sobol";
  size_t points = 0, differ = 0;
  for (const TileRect& rect : make_tiles(width, height, 16)) {
    TileWork work;
    trace_tile(scene, tracer, camera, image, rect, work);  // coherent, as the renderer traces
    std::vector<Ray> rays;
    for (size_t j = 0; j < work.points.size(); ++j) rays.push_back(Ray{work.eye, -work.points.wo[j]});
    std::vector<Hit> single(rays.size());
    tracer.intersect(rays, single);  // one by one, as a part traces
    for (size_t j = 0; j < rays.size(); ++j)
      if (single[j].triangle != work.points.triangle[j] || single[j].t != work.distance[j]) ++differ;
    points += rays.size();
  }
  EXPECT_EQ(differ, 0u) << "of " << points << " camera hits";
  EXPECT_GT(points, static_cast<size_t>(width) * height * spp / 2);
}

TEST(Partition, CameraRaysInPacketsHitWhatTheyHitOneByOne) {
  auto cornell = Scene::builtin("cornell");
  ASSERT_TRUE(cornell);
  expect_tiles_coherent_as_single(*cornell, CameraSpec{{278, 273, -800}, {278, 273, 0}, {0, 1, 0}, 39.3f}, 96, 96, 4,
                                  "cornell");
  auto loaded = test::lost_empire_with_torches();
  if (!loaded) GTEST_SKIP() << "no " << test::kLostEmpireObj;
  ASSERT_TRUE(*loaded) << loaded->error().message;
  expect_tiles_coherent_as_single(**loaded, CameraSpec{{-8, 16, 20}, {6, 12, 0}, {0, 1, 0}, 70}, 160, 120, 4,
                                  "lost_empire");
}

// Five clusters along x, one part each: four rings the ray passes through the middle of, then a wall. The ray
// visits every part in turn and is answered by the last; a ray stopped short of the wall hits nothing and is not
// occluded; one that hits a ring stops in the first part.
TEST(Partition, ARayCrossingEveryPartIsAnsweredByTheLast) {
  Scene s;
  const uint32_t m = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {}});
  const uint32_t lamp = s.add_material(Material{"lamp", {}, {1, 1, 1}});
  for (int k = 0; k < 4; ++k) {
    const float x = 10.0f * k;
    // A square ring around the x axis (inner half-size 1, outer 2), as four quads.
    s.add_quad({x, -2, -2}, {x, 2, -2}, {x, 2, -1}, {x, -2, -1}, m);
    s.add_quad({x, -2, 1}, {x, 2, 1}, {x, 2, 2}, {x, -2, 2}, m);
    s.add_quad({x, -2, -1}, {x, -1, -1}, {x, -1, 1}, {x, -2, 1}, m);
    s.add_quad({x, 1, -1}, {x, 2, -1}, {x, 2, 1}, {x, 1, 1}, m);
  }
  s.add_quad({40, -2, -2}, {40, 2, -2}, {40, 2, 2}, {40, -2, 2}, lamp);
  ASSERT_TRUE(s.finalize("rings"));
  // One part per cluster (8 triangles per ring, then the wall's 2), made by hand: this is about the routing.
  std::vector<ScenePart> parts(5);
  for (uint32_t t = 0; t < s.triangle_count(); ++t) parts[std::min<uint32_t>(t / 8, 4)].triangles.push_back(t);
  for (ScenePart& p : parts) {
    std::vector<Vec3> corners;
    for (uint32_t t : p.triangles)
      for (int c = 0; c < 3; ++c) corners.push_back(s.vertex(t, c));
    p.bounds = bounds_of(corners);
  }
  PartitionedTracer tracer(s, parts);
  const uint32_t wall = static_cast<uint32_t>(s.triangle_count() - 2);
  std::vector<Ray> rays{Ray{{-5, 0.1f, 0.2f}, {1, 0, 0}}, Ray{{-5, 0.1f, 0.2f}, {1, 0, 0}, 0, 30},
                        Ray{{-5, 1.5f, 0.2f}, {1, 0, 0}}};
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  ASSERT_TRUE(hits[0].valid());
  EXPECT_GE(hits[0].triangle, wall);
  EXPECT_FLOAT_EQ(hits[0].t, 45.0f);
  EXPECT_FALSE(hits[1].valid());
  ASSERT_TRUE(hits[2].valid());
  EXPECT_FLOAT_EQ(hits[2].t, 5.0f);
  // The first ray visits all five parts, the second the three before x = 30, the third only the first.
  EXPECT_EQ(tracer.rays_per_part(), (std::vector<uint64_t>{3, 2, 2, 1, 1}));
  std::vector<uint8_t> blocked(rays.size());
  tracer.occluded(rays, blocked);
  EXPECT_EQ(blocked, (std::vector<uint8_t>{1, 0, 1}));
}

}  // namespace
}  // namespace lf
