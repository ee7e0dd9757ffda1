#include "render/sampler.hpp"

#include <gtest/gtest.h>

#include <array>
#include <set>

namespace lf {

TEST(Sampler, SameKeyAndStreamGiveTheSameSequence) {
  Rng a(sample_key(10, 3), streams::direct), b(sample_key(10, 3), streams::direct);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.next(), b.next());
}

TEST(Sampler, NeighbouringKeysAndStreamsDiffer) {
  std::set<uint32_t> firsts;
  for (uint64_t p = 0; p < 64; ++p)
    for (uint64_t s = 0; s < 16; ++s) firsts.insert(Rng(sample_key(p, s), streams::camera).next());
  EXPECT_GT(firsts.size(), 1000u);
  EXPECT_NE(Rng(sample_key(1, 1), streams::camera).next(), Rng(sample_key(1, 1), streams::direct).next());
}

TEST(Sampler, UniformIsUniform) {
  // Chi-square over 32 bins of 320k draws across many keys (critical value 61.1 at p = 0.001, 31 dof).
  std::array<int, 32> bins{};
  const int draws_per_key = 10, keys = 32000;
  for (int k = 0; k < keys; ++k) {
    Rng r(sample_key(static_cast<uint64_t>(k), 0), 5);
    for (int i = 0; i < draws_per_key; ++i) {
      float u = r.uniform();
      ASSERT_GE(u, 0.0f);
      ASSERT_LT(u, 1.0f);
      ++bins[static_cast<size_t>(u * 32)];
    }
  }
  const double expected = double(draws_per_key) * keys / 32;
  double chi2 = 0;
  for (int b : bins) chi2 += (b - expected) * (b - expected) / expected;
  EXPECT_LT(chi2, 61.1);
}

}  // namespace lf
