// The pixels on a light's outline: every pixel a light partly covers is among them, a light's inside and what is
// far from it are not, and their extra seen samples bring an outline pixel's emission closer to the truth without
// moving it, the same on any tiling.
#include <gtest/gtest.h>

#include <cmath>

#include "render/shading/emitter_edges.hpp"
#include "render/shading/tile_kernel.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {
namespace {

constexpr int kSize = 64;

ImageSpec image_of(int spp, int edge_spp) {
  ImageSpec image;
  image.width = image.height = kSize;
  image.spp = spp;
  image.edge_spp = edge_spp;
  image.tile = kSize;
  return image;
}

// The share of pixel (x, y) where the camera sees a light's front, from n x n stratified pinhole rays (through a
// lens, each with its own lens point).
float light_share(const Scene& scene, const RayTracer& tracer, const Camera& camera, int x, int y, int n) {
  std::vector<Ray> rays;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const float u = (static_cast<float>(i) + 0.5f) / static_cast<float>(n), v = (static_cast<float>(j) + 0.5f) / static_cast<float>(n);
      rays.push_back(camera.ray(static_cast<float>(x) + u, static_cast<float>(y) + v, std::fmod(u * 7.31f, 1.0f), std::fmod(v * 3.17f, 1.0f)));
    }
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  int lit = 0;
  for (size_t k = 0; k < rays.size(); ++k)
    if (hits[k].valid() && scene.material(scene.material_of(hits[k].triangle)).emissive() &&
        dot(scene.normal(hits[k].triangle), rays[k].direction) < 0)
      ++lit;
  return static_cast<float>(lit) / static_cast<float>(rays.size());
}

// Up at the ceiling's light from above the tall block: it fills about half the image's width.
CameraSpec looking_up() {
  CameraSpec spec;
  spec.eye = {278, 400, 280};
  spec.at = {278, 548, 280};
  spec.up = {0.4, 0, 1};  // turned, so that its outline crosses pixels at a slant
  spec.fov = 70;
  return spec;
}

void expect_outline_marked(const CameraSpec& spec, const char* what) {
  auto scene = Scene::builtin("cornell");
  RayTracer tracer(*scene);
  const Camera camera(spec, kSize, kSize);
  const EmitterEdges edges = emitter_edges(*scene, camera, image_of(4, 64));
  ASSERT_EQ(edges.samples, 64);
  std::vector<float> share(static_cast<size_t>(kSize) * kSize);
  size_t partly = 0, inside = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float s = share[static_cast<size_t>(y) * kSize + x] = light_share(*scene, tracer, camera, x, y, 16);
      if (s > 0 && s < 1) {
        ++partly;
        EXPECT_TRUE(edges.at(x, y)) << what << ": pixel " << x << "," << y << " is " << s << " light, not marked";
      } else if (s == 1) {
        ++inside;
      }
    }
  EXPECT_GT(partly, 100u) << what;
  EXPECT_GT(inside, 500u) << what;
  // Far from the outline nothing is, inside the light (its two triangles' shared edge is not an outline) or out:
  // every marked pixel is within 3 pixels of one the light partly covers.
  size_t deep_inside = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      bool near = false;
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= kSize || v >= kSize) continue;
          const float s = share[static_cast<size_t>(v) * kSize + u];
          near = near || (s > 0 && s < 1);
        }
      deep_inside += !near && share[static_cast<size_t>(y) * kSize + x] == 1;
      EXPECT_TRUE(near || !edges.at(x, y)) << what << ": pixel " << x << "," << y << " marked, far from the light's outline";
    }
  EXPECT_GT(deep_inside, 300u) << what;
}

TEST(EmitterEdges, EveryPixelALightPartlyCoversIsMarkedAndItsInsideIsNot) {
  expect_outline_marked(looking_up(), "pinhole");
  CameraSpec spec = looking_up();
  spec.aperture = 20;  // through a lens the outline spreads by the blur at its depth
  spec.focus_distance = 100;
  expect_outline_marked(spec, "lens");
}

TEST(EmitterEdges, NoneWhenTheImageAsksForNoMoreThanItsSamples) {
  auto scene = Scene::builtin("cornell");
  const Camera camera(CameraSpec{}, kSize, kSize);
  EXPECT_EQ(emitter_edges(*scene, camera, image_of(16, 16)).samples, 0);
  EXPECT_EQ(emitter_edges(*scene, camera, image_of(16, 0)).count(), 0u);
  EXPECT_FALSE(emitter_edges(*scene, camera, image_of(16, 0)).at(10, 10));
  EXPECT_EQ(ImageSpec::default_edge_spp(16), 256);
  EXPECT_EQ(ImageSpec::default_edge_spp(1024), 4096);
  EXPECT_EQ(ImageSpec::default_edge_spp(8192), 8192);
}

// The emission each pixel's samples see (their lighting left at zero).
std::vector<RGB> seen_image(const Scene& scene, const RayTracer& tracer, const Camera& camera, const ImageSpec& image) {
  const EmitterEdges edges = emitter_edges(scene, camera, image);
  std::vector<RGB> out(static_cast<size_t>(kSize) * kSize), pixels;
  TileWork work;
  for (const TileRect& rect : make_tiles(kSize, kSize, image.tile)) {
    trace_tile(scene, tracer, camera, image, rect, work, edges);
    resolve_tile(work, std::vector<RGB>(work.points.size()), pixels);
    for (int y = rect.y0, i = 0; y < rect.y1; ++y)
      for (int x = rect.x0; x < rect.x1; ++x, ++i) out[static_cast<size_t>(y) * kSize + x] = pixels[static_cast<size_t>(i)];
  }
  return out;
}

TEST(EmitterEdges, OutlinePixelsSeeTheLightWithLessNoiseAndTheSameMean) {
  auto scene = Scene::builtin("cornell");
  RayTracer tracer(*scene);
  CameraSpec spec;
  spec.eye = {278, 400, -300};  // the light seen at a slant: a band a few pixels high
  spec.at = {278, 548, 280};
  const Camera camera(spec, kSize, kSize);
  const std::vector<RGB> truth = seen_image(*scene, tracer, camera, image_of(1024, 0));
  const std::vector<RGB> plain = seen_image(*scene, tracer, camera, image_of(4, 0));
  const std::vector<RGB> outlined = seen_image(*scene, tracer, camera, image_of(4, 64));
  const EmitterEdges edges = emitter_edges(*scene, camera, image_of(4, 64));
  double se_plain = 0, se_outlined = 0, sum_truth = 0, sum_outlined = 0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const size_t i = static_cast<size_t>(y) * kSize + x;
      if (!edges.at(x, y)) {
        EXPECT_TRUE(outlined[i] == plain[i]) << "an unmarked pixel keeps its samples: " << x << "," << y;
        continue;
      }
      se_plain += std::pow(average(plain[i]) - average(truth[i]), 2);
      se_outlined += std::pow(average(outlined[i]) - average(truth[i]), 2);
      sum_truth += average(truth[i]);
      sum_outlined += average(outlined[i]);
    }
  // 16 times the seen samples: about a quarter of the error (stratification does better); at most half.
  EXPECT_LT(se_outlined, 0.25 * se_plain);
  EXPECT_NEAR(sum_outlined / sum_truth, 1.0, 0.02);
  // Each pixel's extra samples are its own, whatever the tiles.
  ImageSpec tiled = image_of(4, 64);
  tiled.tile = 8;
  EXPECT_TRUE(seen_image(*scene, tracer, camera, tiled) == outlined);
}

}  // namespace
}  // namespace lf
