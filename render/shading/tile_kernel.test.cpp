// Adaptive sampling's rule, pixel by pixel: how many of a pixel's samples get lit from the spread of its first
// shade_spp, and the pixel it then resolves to.
#include <gtest/gtest.h>

#include "render/shading/tile_kernel.hpp"

namespace lf {
namespace {

// A 3 x 1 tile, 16 samples a pixel, 4 lit, whose lit samples give `values` (one row per pixel, grey).
struct Tile {
  ImageSpec image;
  TileWork work;
  std::vector<RGB> radiance;
  explicit Tile(const std::vector<std::vector<float>>& values) {
    image.spp = 16;
    image.shade_spp = 4;
    image.adaptive_spp = 16;
    image.adaptive_threshold = 0.05;
    work.rect = {0, 0, 3, 1};
    work.spp = 16;
    work.shaded = 4;
    work.emitted.assign(3 * 16, RGB{});
    for (size_t p = 0; p < values.size(); ++p)
      for (size_t k = 0; k < values[p].size(); ++k) {
        work.sample_of_point.push_back(static_cast<uint32_t>(p * 16 + k));
        radiance.push_back({values[p][k], values[p][k], values[p][k]});
      }
  }
};

TEST(AdaptiveSampling, APixelGetsSamplesByItsOwnSpread) {
  // Flat: no spread. One bright sample in four: standard error 1, far above 0.05 (capped at 16). A little spread:
  // standard error 0.0577, so 4 x (0.0577 / 0.05)^2 = 5.3 samples would do: the next doubling, 8.
  Tile t({{0.5f, 0.5f, 0.5f, 0.5f}, {0, 0, 0, 4}, {1, 1.2f, 1, 1.2f}});
  EXPECT_EQ(adaptive_shaded_counts(t.image, t.work, t.radiance), (std::vector<uint32_t>{4, 16, 8}));
  // One stop brighter on display: the same noise is twice as visible.
  t.image.exposure = 1;
  EXPECT_EQ(adaptive_shaded_counts(t.image, t.work, t.radiance), (std::vector<uint32_t>{4, 16, 16}));
  // A sample that hit nothing is a zero of the pixel's lighting, not left out.
  Tile missing({{0.5f, 0.5f, 0.5f}, {}, {}});
  EXPECT_EQ(adaptive_shaded_counts(missing.image, missing.work, missing.radiance)[0], 16);
}

TEST(AdaptiveSampling, APixelWithNoMoreSamplesResolvesAsWithout) {
  Tile t({{0.5f, 0.25f, 0.5f, 0.125f}, {0, 0, 0, 4}, {1, 1.2f, 1, 1.2f}});
  t.work.emitted[5] = {2, 2, 2};  // a seen, unlit sample of pixel 0 that meets a light
  std::vector<RGB> plain, adaptive;
  resolve_tile(t.work, t.radiance, plain);
  // Pixel 1 took 4 more samples of value 2 each: its lighting is (4 + 8) / 8.
  TileWork more;
  more.rect = t.work.rect;
  more.spp = 16;
  for (uint32_t k = 4; k < 8; ++k) more.sample_of_point.push_back(16 + k);
  const std::vector<RGB> more_radiance(4, RGB{2, 2, 2});
  resolve_adaptive_tile(t.work, t.radiance, more, more_radiance, std::vector<uint32_t>{4, 8, 4}, adaptive);
  EXPECT_TRUE(adaptive[0] == plain[0]);
  EXPECT_TRUE(adaptive[2] == plain[2]);
  EXPECT_FLOAT_EQ(adaptive[1].x, 1.5f);
  EXPECT_FLOAT_EQ(plain[1].x, 1.0f);
  EXPECT_FLOAT_EQ(plain[0].x, (0.5f + 0.25f + 0.5f + 0.125f) / 4 + 2.0f / 16);
}

}  // namespace
}  // namespace lf
