// The irradiance cache's lookup structures: the frozen grids answer as the octree does, and a cache built for
// lookups that never relax answers them exactly as one built for the widest.
#include <gtest/gtest.h>

#include <cmath>
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

// Asked for elevation bands, a lookup gives the same irradiance, and bands that sum to it: each record's bands
// scaled to its gradient-extrapolated irradiance, weighed as the irradiance is. Records whose light came from one band
// give that band alone; and the bands cost a Lambert lookup (which asks for none) nothing.
TEST(IrradianceCache, BandsSumToTheIrradianceTheLookupGives) {
  auto recs = records(3000, 6);
  for (size_t i = 0; i < recs.size(); ++i) {
    const size_t band = i % 3 == 0 ? 2 : i % kElevationBands;  // a third from band 2 alone, the rest spread
    if (i % 3 == 0) {
      recs[i].bands[band] = recs[i].irradiance;
    } else {
      for (size_t j = 0; j < kElevationBands; ++j) recs[i].bands[j] = recs[i].irradiance * (1.0f / kElevationBands);
    }
  }
  IrradianceCache cache(0.2f, 17.3f), only_band_two(0.2f, 17.3f);
  for (size_t i = 0; i < recs.size(); ++i) {
    cache.insert(recs[i]);
    if (i % 3 == 0) only_band_two.insert(recs[i]);
  }
  cache.freeze();
  only_band_two.freeze();
  const float bounds[3] = {1, 2, 4};
  size_t answered = 0, answered_two = 0;
  for (const Query& q : queries(4000, 7)) {
    RGB plain, e;
    ElevationBands bands;
    const int at = cache.lookup_first(q.x, q.n, bounds, e, nullptr, &bands);
    ASSERT_EQ(at, cache.lookup_first(q.x, q.n, bounds, plain));
    if (at < 0) continue;
    ++answered;
    EXPECT_EQ(e.x, plain.x);
    EXPECT_EQ(e.z, plain.z);
    RGB sum{};
    for (const RGB& b : bands) sum += b;
    EXPECT_NEAR(sum.x, e.x, 1e-4f * (1 + e.x));
    EXPECT_NEAR(sum.y, e.y, 1e-4f * (1 + e.y));
    EXPECT_NEAR(sum.z, e.z, 1e-4f * (1 + e.z));
    if (only_band_two.lookup_first(q.x, q.n, bounds, e, nullptr, &bands) >= 0) {
      ++answered_two;
      for (size_t j = 0; j < kElevationBands; ++j)
        if (j != 2) EXPECT_EQ(bands[j], RGB{}) << j;
      EXPECT_NEAR(bands[2].y, e.y, 1e-5f * (1 + e.y));
    }
  }
  EXPECT_GT(answered, 1000u);
  EXPECT_GT(answered_two, 300u);
}

// A record does not serve a parallel surface just behind its own (the ceiling above a light panel hung 1 cm under
// it, where the panel's records, which see the open room, made a bright rim), but does serve points of a curved
// surface that lie behind its tangent plane as far as the curvature between their normals explains.
TEST(IrradianceCache, ARecordDoesNotServeTheSurfaceBehindItsOwn) {
  IrradianceRecord panel{};
  panel.position = {0, 0, 0};
  panel.normal = {0, -1, 0};  // facing down, as a panel's emitting face
  panel.irradiance = {1, 1, 1};
  panel.harmonic_distance = 1.0f;  // it sees the open room: it reaches a * R = 20 cm
  IrradianceCache cache(0.2f, 10.0f, 1.0f);
  cache.insert(panel);
  cache.freeze();
  RGB e;
  // The ceiling 1 cm above, facing down too, 5 cm along: behind the panel's plane, not curving.
  EXPECT_FALSE(cache.lookup({0.05f, 0.01f, 0}, {0, -1, 0}, e));
  // The panel's own plane, 5 cm along: served.
  EXPECT_TRUE(cache.lookup({0.05f, 0, 0}, {0, -1, 0}, e));
  // In front of it (below): served.
  EXPECT_TRUE(cache.lookup({0.05f, -0.01f, 0}, {0, -1, 0}, e));
  // A sphere of radius 1 through the record, 10 cm along its surface: behind the tangent plane by 1 - cos(0.1), with
  // its normal turned by 0.1 rad. Served.
  const float t = 0.1f;
  const Vec3 on_sphere{std::sin(t), 1 - std::cos(t), 0};  // the sphere's centre at (0, 1, 0), below it the record
  const Vec3 normal{std::sin(t), -std::cos(t), 0};
  EXPECT_TRUE(cache.lookup(on_sphere, normal, e));
}

}  // namespace
}  // namespace lf
