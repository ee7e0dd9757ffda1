// Adaptive sampling's rule, pixel by pixel: how many of a pixel's samples get lit from the spread of its neighbours'
// first shade_spp, that the mean stays unbiased, and the pixel it then resolves to.
#include <gtest/gtest.h>

#include <random>

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

TEST(AdaptiveSampling, APixelGetsSamplesByItsNeighboursSpread) {
  // Flat: no spread. One bright sample in four: standard error 1, far above 0.05. A little spread: standard error
  // 0.0577. The middle pixel's neighbours pool 0 and 0.0133: 0.0408, within 0.05; the outer two see the bright one
  // (capped at 16), whatever their own samples.
  Tile t({{0.5f, 0.5f, 0.5f, 0.5f}, {0, 0, 0, 4}, {1, 1.2f, 1, 1.2f}});
  EXPECT_EQ(adaptive_shaded_counts(t.image, t.work, t.radiance), (std::vector<uint32_t>{16, 4, 16}));
  // One stop brighter on display: the same noise is twice as visible: 4 x (0.0408 / 0.025)^2 = 10.7, so 16.
  t.image.exposure = 1;
  EXPECT_EQ(adaptive_shaded_counts(t.image, t.work, t.radiance), (std::vector<uint32_t>{16, 16, 16}));
  // A sample that hit nothing is a zero of the pixel's lighting, not left out: pixel 0's three of 0.5 and a zero
  // spread (0.125), which its neighbour sees.
  Tile missing({{0.5f, 0.5f, 0.5f}, {}, {}});
  EXPECT_EQ(adaptive_shaded_counts(missing.image, missing.work, missing.radiance), (std::vector<uint32_t>{4, 16, 4}));
}

// Light that is rare and bright (a pixel's sample is 10 one time in 20, else 0: mean 0.5), over 100 tiles of 16 x 16:
// the pixels' mean after adaptive sampling is the true mean. A pixel that decided on its own first 4 samples would
// keep 0 whenever none of them was bright (81 % of pixels) and average about 0.12.
TEST(AdaptiveSampling, RareBrightLightKeepsItsMeanWhateverThePixelsGet) {
  std::mt19937 rng(7);
  auto sample = [&] { return std::uniform_real_distribution<float>(0, 1)(rng) < 0.05f ? 10.0f : 0.0f; };
  ImageSpec image;
  image.spp = 64;
  image.shade_spp = 4;
  image.adaptive_spp = 64;
  image.adaptive_threshold = 0.05;
  double sum = 0;
  size_t pixels = 0, refined = 0;
  for (int tile = 0; tile < 100; ++tile) {
    TileWork first;
    first.rect = {0, 0, 16, 16};
    first.spp = 64;
    first.shaded = 4;
    first.emitted.assign(256 * 64, RGB{});
    std::vector<RGB> first_radiance;
    for (uint32_t p = 0; p < 256; ++p)
      for (uint32_t k = 0; k < 4; ++k) {
        first.sample_of_point.push_back(p * 64 + k);
        const float v = sample();
        first_radiance.push_back({v, v, v});
      }
    const std::vector<uint32_t> counts = adaptive_shaded_counts(image, first, first_radiance);
    TileWork more;
    more.rect = first.rect;
    more.spp = 64;
    std::vector<RGB> more_radiance;
    for (uint32_t p = 0; p < 256; ++p) {
      refined += counts[p] > 4;
      for (uint32_t k = 4; k < counts[p]; ++k) {
        more.sample_of_point.push_back(p * 64 + k);
        const float v = sample();
        more_radiance.push_back({v, v, v});
      }
    }
    std::vector<RGB> resolved;
    resolve_adaptive_tile(first, first_radiance, more, more_radiance, counts, resolved);
    for (const RGB& c : resolved) sum += c.x;
    pixels += resolved.size();
  }
  EXPECT_GT(refined, pixels / 4) << "adaptive sampling did nothing: nothing was tested";
  EXPECT_LT(refined, pixels) << "every pixel refined: nothing was tested";
  // Standard error of this mean: about 0.006.
  EXPECT_NEAR(sum / static_cast<double>(pixels), 0.5, 0.025);
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
