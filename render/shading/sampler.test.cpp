#include "render/shading/sampler.hpp"

#include <gtest/gtest.h>

#include <array>
#include <set>
#include <vector>

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

TEST(Sampler, TheIndependentSamplerDrawsWhatRngDraws) {
  // Images made before the Sobol sampler existed stay bit-identical: same numbers, same order.
  for (uint32_t sub : {0u, 3u}) {
    Rng r(sample_key(7, 2), streams::pathtrace + (static_cast<uint64_t>(sub) << 32));
    Sampler s(SamplerKind::independent, sample_key(7, 2), streams::pathtrace, sub, 4);
    for (int i = 0; i < 20; ++i) {
      s.at_dimension(static_cast<uint32_t>(100 - i));  // dimensions are the Sobol sampler's business only
      if (i % 3 == 0) {
        const float a = r.uniform(), b = r.uniform();
        const Uniform2 p = s.uniform2();
        EXPECT_EQ(p.u, a);
        EXPECT_EQ(p.v, b);
      } else {
        EXPECT_EQ(s.uniform(), r.uniform());
      }
    }
  }
}

// Every elementary interval of area 1/256 (2^a x 2^(8-a) cells) holds exactly one of a pixel's first 256 points:
// a (0, 8, 2)-net, in every dimension pair and after scrambling.
TEST(Sampler, ThePixelsFirst256SobolPointsAreANetInEveryDimension) {
  for (uint64_t pixel : {0ull, 12345ull}) {
    for (uint32_t dimension : {0u, 1u, 7u}) {
      std::vector<Uniform2> points;
      for (uint32_t i = 0; i < 256; ++i) {
        Sampler s(SamplerKind::sobol, sobol_sample_key(pixel, i), streams::camera);
        s.at_dimension(dimension);
        points.push_back(s.uniform2());
      }
      for (int a = 0; a <= 8; ++a) {
        const int nx = 1 << a, ny = 1 << (8 - a);
        std::vector<int> cells(256, 0);
        for (const Uniform2& p : points) {
          ASSERT_GE(p.u, 0.0f);
          ASSERT_LT(p.u, 1.0f);
          ++cells[static_cast<size_t>(static_cast<int>(p.u * nx) * ny + static_cast<int>(p.v * ny))];
        }
        for (int c : cells) ASSERT_EQ(c, 1) << "pixel " << pixel << " dimension " << dimension << " cells " << nx << "x" << ny;
      }
      // 1D draws: 256 points in 256 strata.
      std::vector<int> strata(256, 0);
      for (uint32_t i = 0; i < 256; ++i) {
        Sampler s(SamplerKind::sobol, sobol_sample_key(pixel, i), streams::direct);
        s.at_dimension(dimension);
        ++strata[static_cast<size_t>(s.uniform() * 256)];
      }
      for (int c : strata) ASSERT_EQ(c, 1);
    }
  }
}

// point1 and point2 skip reversals that undo each other and read dimension 1 from byte tables: they must give
// exactly the numbers of the plain definition (scramble the index, take the dimension, scramble it).
TEST(Sampler, SobolPointsEqualThePlainDefinition) {
  Rng pick(99, 1);
  for (int n = 0; n < 100000; ++n) {
    const uint32_t index = n < 4096 ? static_cast<uint32_t>(n) : pick.next();
    const uint64_t seed = (static_cast<uint64_t>(pick.next()) << 32) | pick.next();
    const sobol::DimensionSeeds k = sobol::dimension_seeds(seed);
    const uint32_t shuffled = sobol::owen_scramble(index, k.shuffle);
    const float u = sobol::to_unit(sobol::owen_scramble(sobol::dimension0(shuffled), k.first));
    const float v = sobol::to_unit(sobol::owen_scramble(sobol::dimension1(shuffled), k.second));
    const Uniform2 p = sobol::point2(index, seed);
    ASSERT_EQ(p.u, u) << "index " << index;
    ASSERT_EQ(p.v, v) << "index " << index;
    ASSERT_EQ(sobol::point1(index, seed), u) << "index " << index;
    ASSERT_EQ(sobol::reversed_dimension1(index), sobol::reverse_bits(sobol::dimension1(index)));
  }
}

TEST(Sampler, SobolSequencesOfPixelsAndDimensionsAreScrambledApart) {
  // The first point differs between pixels, streams and dimensions, and over many pixels it is uniform.
  std::set<float> firsts;
  std::array<int, 32> bins{};
  for (uint64_t pixel = 0; pixel < 32000; ++pixel) {
    Sampler s(SamplerKind::sobol, sobol_sample_key(pixel, 0), streams::camera);
    const float u = s.uniform();
    firsts.insert(u);
    ++bins[static_cast<size_t>(u * 32)];
  }
  EXPECT_GT(firsts.size(), 31000u);
  double chi2 = 0;
  for (int b : bins) chi2 += (b - 1000.0) * (b - 1000.0) / 1000.0;
  EXPECT_LT(chi2, 61.1);
  Sampler a(SamplerKind::sobol, sobol_sample_key(5, 0), streams::camera), b(SamplerKind::sobol, sobol_sample_key(5, 0), streams::direct);
  EXPECT_NE(a.uniform(), b.uniform());
  EXPECT_NE(a.uniform(), a.uniform()) << "consecutive dimensions";
  // Several paths per camera sample are consecutive points of the pixel's sequence.
  EXPECT_EQ(Sampler(SamplerKind::sobol, sobol_sample_key(5, 1), streams::direct, 0, 4).uniform(),
            Sampler(SamplerKind::sobol, sobol_sample_key(5, 0), streams::direct, 4, 1).uniform());
}

}  // namespace lf
