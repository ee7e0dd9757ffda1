// The irradiance cache's lookup structures: the frozen grids answer as the octree does, and a cache built for
// lookups that never relax answers them exactly as one built for the widest.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "render/caches/irradiance_cache.hpp"

namespace lf {
namespace {

void set(Vec3& v, int axis, float value) { (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = value; }

// Records on a few planes of a 10-wide box, with distances from very near to open space, so records land in
// several octree levels and several frozen grids.
std::vector<IrradianceRecord> records(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<IrradianceRecord> out;
  for (size_t i = 0; i < count; ++i) {
    IrradianceRecord r{};
    const int plane = static_cast<int>(i % 3);
    r.position = {10 * u(rng), 10 * u(rng), 10 * u(rng)};
    set(r.position, plane, static_cast<float>(i % 2) * 10);  // on a face of the box
    r.normal = {0, 0, 0};
    set(r.normal, plane, i % 2 ? -1.0f : 1.0f);
    r.irradiance = {u(rng), u(rng), u(rng)};
    r.harmonic_distance = 0.05f + 20 * u(rng) * u(rng) * u(rng);
    for (int ch = 0; ch < 3; ++ch) {
      r.rotational[ch] = {0.1f * u(rng), 0.1f * u(rng), 0.1f * u(rng)};
      r.translational[ch] = {0.01f * u(rng), 0.01f * u(rng), 0.01f * u(rng)};
    }
    out.push_back(r);
  }
  return out;
}

struct Query {
  Vec3 x, n;
};

std::vector<Query> queries(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Query> out;
  for (size_t i = 0; i < count; ++i) {
    Query q{{10 * u(rng), 10 * u(rng), 10 * u(rng)}, {0, 0, 0}};
    const int plane = static_cast<int>(i % 3);
    set(q.x, plane, static_cast<float>(i % 2) * 10 + (u(rng) - 0.5f) * 0.02f);
    set(q.n, plane, i % 2 ? -1.0f : 1.0f);
    out.push_back(q);
  }
  return out;
}

TEST(IrradianceCache, FrozenGridsAnswerAsTheOctreeDoes) {
  const auto recs = records(3000, 1);
  IrradianceCache open(0.2f, 17.3f), frozen(0.2f, 17.3f);
  for (const auto& r : recs) open.insert(r), frozen.insert(r);
  frozen.freeze();
  const float bounds[3] = {1, 2, 4};
  size_t answered = 0;
  for (const Query& q : queries(4000, 2)) {
    RGB a, b;
    uint32_t na = 0, nb = 0;
    const int ia = open.lookup_first(q.x, q.n, bounds, a, &na);
    const int ib = frozen.lookup_first(q.x, q.n, bounds, b, &nb);
    ASSERT_EQ(ia, ib);
    ASSERT_EQ(na, nb);
    if (ia < 0) continue;
    ++answered;
    // The octree visits records in another order: the sums agree to rounding.
    EXPECT_NEAR(a.x, b.x, 1e-4f * (1 + std::abs(b.x)));
    EXPECT_NEAR(a.z, b.z, 1e-4f * (1 + std::abs(b.z)));
  }
  EXPECT_GT(answered, 1000u);  // the test asks where records are, not only in empty space
}

TEST(IrradianceCache, ACacheBuiltForItsOwnBoundAnswersAsTheWidestOne) {
  const auto recs = records(3000, 3);
  for (float relax : {1.0f, 2.0f}) {
    IrradianceCache widest(0.2f, 17.3f), own(0.2f, 17.3f, relax);
    for (const auto& r : recs) widest.insert(r), own.insert(r);
    widest.freeze();
    own.freeze();
    const float one[1] = {1}, two[2] = {1, 2};
    const std::span<const float> bounds = relax == 1 ? std::span<const float>(one) : std::span<const float>(two);
    size_t answered = 0;
    for (const Query& q : queries(4000, 4)) {
      RGB a, b;
      uint32_t na = 0, nb = 0;
      const int ia = widest.lookup_first(q.x, q.n, bounds, a, &na);
      ASSERT_EQ(ia, own.lookup_first(q.x, q.n, bounds, b, &nb));
      ASSERT_EQ(na, nb);
      if (ia < 0) continue;
      ++answered;
      // Both visit the same records in record order: the same sums, bit for bit.
      EXPECT_EQ(a.x, b.x);
      EXPECT_EQ(a.y, b.y);
      EXPECT_EQ(a.z, b.z);
    }
    EXPECT_GT(answered, 1000u);
    // Wider than it was built for: it would miss records, so it says so.
    const float four[3] = {1, 2, 4};
    RGB e;
    EXPECT_THROW(own.lookup_first(queries(1, 5)[0].x, queries(1, 5)[0].n, four, e), std::invalid_argument);
  }
}

}  // namespace
}  // namespace lf
