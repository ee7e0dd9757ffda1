#include "actors/kinds/tile_plan.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace lf {
namespace {

// A tile of `pixels` pixels in a row with `spp` samples each; sample s hits a surface unless `miss(s)`, and pixel p
// sees an emitter when `emits(p)`.
template <typename Miss, typename Emits>
TileWork tile(int pixels, int spp, Miss miss, Emits emits) {
  TileWork w;
  w.rect = TileRect{0, 0, pixels, 1};
  w.spp = spp;
  w.emitted.assign(static_cast<size_t>(pixels * spp), RGB{});
  for (uint32_t s = 0; s < static_cast<uint32_t>(pixels * spp); ++s) {
    if (emits(s / spp) && s % spp == 0) w.emitted[s] = RGB{1, 1, 1};
    if (miss(s)) continue;
    w.points.push_back(Vec3{float(s), 0, 0}, Vec3{0, 0, 1}, Vec3{0, 0, 1}, 0, s);
    w.sample_of_point.push_back(s);
  }
  return w;
}

TileWork full_tile(int pixels, int spp) {
  return tile(pixels, spp, [](uint32_t) { return false; }, [](int) { return false; });
}

std::vector<std::pair<size_t, size_t>> ranges(const TilePlan& plan) {
  std::vector<std::pair<size_t, size_t>> out;
  for (const Batch& b : plan.batches) out.emplace_back(b.begin, b.end);
  return out;
}

using Ranges = std::vector<std::pair<size_t, size_t>>;

TEST(TilePlan, PlainBatchesCutThePointsInOrder) {
  const TileWork w = full_tile(5, 2);  // 10 points
  const TilePlan plan = plan_batches(w, {}, {.batch = 4});
  EXPECT_EQ(ranges(plan), (Ranges{{0, 4}, {4, 8}, {8, 10}}));
  EXPECT_TRUE(plan.order.empty());
  EXPECT_TRUE(plan.pixel.empty());
  for (const Batch& b : plan.batches) {
    EXPECT_EQ(b.part, -1);
    EXPECT_FALSE(b.foldable);
    EXPECT_EQ(plan.reply_size(b, false), b.end - b.begin);
  }
}

TEST(TilePlan, AnEmptyTileHasNoBatches) {
  const TileWork w = tile(3, 2, [](uint32_t) { return true; }, [](int) { return false; });
  EXPECT_TRUE(plan_batches(w, {}, {.batch = 4, .fold = true}).batches.empty());
}

TEST(TilePlan, FoldingBatchesEndBetweenPixels) {
  // 4 pixels of 3 samples; pixel 1 loses a sample to a miss: points per pixel 3, 2, 3, 3.
  const TileWork w = tile(4, 3, [](uint32_t s) { return s == 4; }, [](int) { return false; });
  const TilePlan plan = plan_batches(w, {}, {.batch = 4, .fold = true});
  // 4 points end inside pixel 1 (points 3..4): the batch runs to its end; then 5..8 ends inside pixel 3.
  EXPECT_EQ(ranges(plan), (Ranges{{0, 5}, {5, 11}}));
  EXPECT_EQ(plan.pixel, (std::vector<uint32_t>{0, 0, 0, 1, 1, 2, 2, 2, 3, 3, 3}));
  EXPECT_EQ(plan.batches[0].pixels, 2u);
  EXPECT_EQ(plan.batches[1].pixels, 2u);
  EXPECT_TRUE(plan.batches[0].foldable && plan.batches[1].foldable);
  EXPECT_EQ(plan.reply_size(plan.batches[1], true), 2u);
  EXPECT_EQ(plan.reply_size(plan.batches[1], false), 6u);
}

TEST(TilePlan, ABatchWithAPixelThatSeesAnEmitterIsNotFolded) {
  const TileWork w = tile(4, 2, [](uint32_t) { return false; }, [](int p) { return p == 2; });
  const TilePlan plan = plan_batches(w, {}, {.batch = 4, .fold = true});
  ASSERT_EQ(ranges(plan), (Ranges{{0, 4}, {4, 8}}));
  EXPECT_TRUE(plan.batches[0].foldable);
  EXPECT_FALSE(plan.batches[1].foldable);
}

TEST(TilePlan, PointsAreGroupedByPartInPointOrderAndTheUnplacedLast) {
  const TileWork w = full_tile(3, 2);  // samples 0..5
  // Sample -> part; 7 is beyond the 2 parts: found in none (sent to any replica).
  const std::vector<uint32_t> part{1, 0, 7, 1, 0, 0};
  const TilePlan plan = plan_batches(w, part, {.batch = 2, .parts = 2});
  EXPECT_EQ(plan.order, (std::vector<uint32_t>{1, 4, 5, 0, 3, 2}));
  EXPECT_EQ(ranges(plan), (Ranges{{0, 2}, {2, 3}, {3, 5}, {5, 6}}));  // a batch never spans two parts
  std::vector<int64_t> parts;
  for (const Batch& b : plan.batches) parts.push_back(b.part);
  EXPECT_EQ(parts, (std::vector<int64_t>{0, 0, 1, -1}));
}

TEST(TilePlan, APixelSplitBetweenPartsIsNotFolded) {
  const TileWork w = full_tile(3, 2);
  // Pixel 0 (samples 0, 1) lies in parts 0 and 1; pixels 1 and 2 each in one.
  const std::vector<uint32_t> part{0, 1, 0, 0, 1, 1};
  const TilePlan plan = plan_batches(w, part, {.batch = 8, .fold = true, .parts = 2});
  ASSERT_EQ(ranges(plan), (Ranges{{0, 3}, {3, 6}}));
  EXPECT_EQ(plan.pixel, (std::vector<uint32_t>{0, 1, 1, 0, 2, 2}));
  EXPECT_FALSE(plan.batches[0].foldable);
  EXPECT_FALSE(plan.batches[1].foldable);
  const TilePlan whole = plan_batches(w, std::vector<uint32_t>{0, 0, 0, 0, 1, 1}, {.batch = 8, .fold = true, .parts = 2});
  EXPECT_TRUE(whole.batches[0].foldable && whole.batches[1].foldable);
}

bool same_bits(const std::vector<RGB>& a, const std::vector<RGB>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(RGB)) == 0;
}

// Every plan, answered as a LightOp answers it (folded batches summed by fold_by_pixel), resolves to the bits of
// the tile resolved unsent: batch sizes, folding, parts and their combinations.
TEST(TilePlan, EveryPlanResolvesToTheSameBitsAsTheUnsentTile) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int round = 0; round < 40; ++round) {
    const int pixels = 1 + round % 9, spp = 1 + round % 4;
    const TileWork w = tile(pixels, spp, [&](uint32_t) { return u(rng) < 0.2f; }, [&](int) { return u(rng) < 0.15f; });
    std::vector<RGB> radiance(w.points.size());
    for (RGB& r : radiance) r = RGB{u(rng), u(rng), u(rng)};
    std::vector<RGB> expected;
    resolve_tile(w, radiance, expected);
    std::vector<uint32_t> part(static_cast<size_t>(pixels * spp));
    for (uint32_t& p : part) p = static_cast<uint32_t>(rng() % 4);  // 3: in no part
    for (size_t batch : {1, 2, 5, 64})
      for (bool fold : {false, true})
        for (size_t parts : {0, 3}) {
          const TilePlan plan = plan_batches(w, part, {.batch = batch, .fold = fold, .parts = parts});
          size_t sent = 0;
          TileRadiance got(plan);
          for (const Batch& b : plan.batches) {
            ASSERT_LE(b.end - b.begin, batch + (fold ? static_cast<size_t>(spp) : 0));
            std::vector<RGB> reply;
            std::vector<uint32_t> samples;
            for (size_t j = b.begin; j < b.end; ++j) {
              const uint32_t i = plan.order.empty() ? static_cast<uint32_t>(j) : plan.order[j];
              reply.push_back(radiance[i]);
              samples.push_back(w.sample_of_point[i]);
            }
            sent += reply.size();
            if (b.foldable) {
              std::vector<RGB> sums;
              fold_by_pixel(reply, samples, spp, sums);
              ASSERT_EQ(sums.size(), plan.reply_size(b, true));
              reply = sums;
            }
            scatter_reply(plan, b, b.foldable, reply, got);
          }
          EXPECT_EQ(sent, w.points.size());
          std::vector<RGB> image;
          resolve_tile(w, got.point, got.pixel, got.folded, image);
          EXPECT_TRUE(same_bits(image, expected)) << "batch " << batch << " fold " << fold << " parts " << parts;
        }
  }
}

}  // namespace
}  // namespace lf
