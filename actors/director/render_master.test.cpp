#include "actors/director/render_master.hpp"

#include <gtest/gtest.h>

#include <set>

namespace lf {

TEST(RenderMaster, HandsOutEveryTileOnceAndCoversTheImage) {
  RenderMaster m(50, 30, 16);  // 4 x 2 tiles, the last column and row partial
  EXPECT_EQ(m.total(), 8u);
  std::set<uint64_t> ids;
  int pixels = 0;
  while (auto t = m.next("r0")) {
    EXPECT_TRUE(ids.insert(t->id).second);
    pixels += t->rect.pixel_count();
  }
  EXPECT_EQ(ids.size(), 8u);
  EXPECT_EQ(pixels, 50 * 30);
}

TEST(RenderMaster, HandsTilesOutInMortonOrder) {
  RenderMaster m(64, 64, 16);  // 4 x 4 tiles
  std::vector<std::pair<int, int>> got;
  while (auto t = m.next("r0")) got.emplace_back(t->rect.x0 / 16, t->rect.y0 / 16);
  std::vector<std::pair<int, int>> z{{0, 0}, {1, 0}, {0, 1}, {1, 1}, {2, 0}, {3, 0}, {2, 1}, {3, 1},
                                     {0, 2}, {1, 2}, {0, 3}, {1, 3}, {2, 2}, {3, 2}, {2, 3}, {3, 3}};
  EXPECT_EQ(got, z);
}

TEST(RenderMaster, AcceptsOnlyFromTheHolderAndOnlyOnce) {
  RenderMaster m(16, 16, 16);
  auto t = m.next("r0");
  ASSERT_TRUE(t);
  std::vector<float> rgb(3 * 256, 0.5f);
  EXPECT_EQ(m.complete("r1", t->id, rgb), RenderMaster::Outcome::not_holder);
  EXPECT_EQ(m.complete("r0", t->id, std::vector<float>(3)), RenderMaster::Outcome::wrong_size);
  EXPECT_EQ(m.complete("r0", 99, rgb), RenderMaster::Outcome::unknown_tile);
  EXPECT_EQ(m.complete("r0", t->id, rgb), RenderMaster::Outcome::accepted);
  EXPECT_EQ(m.complete("r0", t->id, std::vector<float>(3 * 256, 9.0f)), RenderMaster::Outcome::already_done);
  EXPECT_TRUE(m.finished());
  EXPECT_EQ(m.film().at(3, 3), (RGB{0.5f, 0.5f, 0.5f}));  // the late duplicate did not overwrite
}

TEST(RenderMaster, ReleasedTilesGoToSomeoneElse) {
  RenderMaster m(32, 16, 16);
  auto a = m.next("r0");
  auto b = m.next("r0");
  ASSERT_TRUE(a && b);
  EXPECT_FALSE(m.next("r1"));
  EXPECT_EQ(m.release("r0"), 2u);
  auto c = m.next("r1");
  ASSERT_TRUE(c);
  std::vector<float> rgb(3 * 256, 1.0f);
  EXPECT_EQ(m.complete("r0", c->id, rgb), RenderMaster::Outcome::not_holder);  // the old holder lost it
  EXPECT_EQ(m.complete("r1", c->id, rgb), RenderMaster::Outcome::accepted);
}

}  // namespace lf
