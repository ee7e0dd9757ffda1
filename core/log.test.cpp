// Rate-limited warnings: at most one line a second, the next one counting what was held back.
#include "core/log.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace lf {
namespace {

TEST(RateLimitedLog, OneLineASecondWithTheCountOfTheRest) {
  std::vector<std::string> lines;
  RateLimitedLog log([&](const std::string& l) { lines.push_back(l); });
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 1000; ++i) log.warn("bad message", t0 + std::chrono::microseconds(i));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "bad message");
  log.warn("bad message", t0 + std::chrono::milliseconds(1500));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1], "bad message (and 999 more like it in the last second)");
  log.warn("bad message", t0 + std::chrono::seconds(5));
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[2], "bad message");
}

}  // namespace
}  // namespace lf
