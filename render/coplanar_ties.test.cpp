#include "render/coplanar_ties.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace lf {
namespace {

// A unit quad at z = 0 facing +z (triangles 0, 1), its back-to-back twin facing -z (2, 3), a smaller decal facing +z
// over part of it (4, 5), and a neighbour quad that only shares an edge with the first (6, 7).
Scene tied_scene() {
  Scene s;
  const uint32_t m = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {}});
  const uint32_t lamp = s.add_material(Material{"lamp", {}, {1, 1, 1}});
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, m);
  s.add_quad({0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}, m);
  s.add_quad({0.2f, 0.2f, 0}, {0.6f, 0.2f, 0}, {0.6f, 0.6f, 0}, {0.2f, 0.6f, 0}, m);
  s.add_quad({1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, m);
  s.add_quad({0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}, lamp);
  EXPECT_TRUE(s.finalize("tied"));
  return s;
}

TEST(CoplanarTies, OverlappingFacesArePartnersAndNeighboursAreNot) {
  Scene s = tied_scene();
  CoplanarTies ties(s);
  for (uint32_t t : {0u, 1u}) {
    auto p = ties.partners(t);
    EXPECT_TRUE(std::find(p.begin(), p.end(), 2u) != p.end() || std::find(p.begin(), p.end(), 3u) != p.end()) << t;
    for (uint32_t other : p) EXPECT_LT(other, 6u) << "the neighbour only shares an edge";
  }
  EXPECT_TRUE(ties.partners(6).empty());
  EXPECT_TRUE(ties.partners(7).empty());
  EXPECT_TRUE(ties.partners(8).empty());  // the lamp, alone in its plane
  // The decal overlaps the quad and its twin.
  EXPECT_FALSE(ties.partners(4).empty());
}

// Whatever face a BVH reported, the settled hit is the face turned towards the ray, then the lowest id, at one
// distance.
TEST(CoplanarTies, TheFaceTowardsTheRayWinsWhicheverWasReported) {
  Scene s = tied_scene();
  CoplanarTies ties(s);
  const Ray from_above{{0.8f, 0.9f, 2}, {0, 0, -1}};
  const Ray from_below{{0.8f, 0.9f, -2}, {0, 0, 1}};
  const Ray through_decal{{0.3f, 0.25f, 2}, {0, 0, -1}};
  std::vector<uint32_t> answers;
  for (uint32_t reported : {1u, 2u}) {  // the faces a BVH can report there: both contain the point
    const Hit above = ties.settle(from_above, Hit{reported, 2.0f});
    const Hit below = ties.settle(from_below, Hit{reported, 2.0f});
    ASSERT_TRUE(above.valid() && below.valid());
    EXPECT_GT(s.normal(above.triangle).z, 0) << "seen from above: the face towards +z";
    EXPECT_LT(s.normal(below.triangle).z, 0) << "seen from below: the twin";
    EXPECT_FLOAT_EQ(above.t, 2.0f);
    answers.push_back(above.triangle);
    answers.push_back(below.triangle);
  }
  for (size_t i = 2; i < answers.size(); ++i) EXPECT_EQ(answers[i], answers[i % 2]) << "the same face every time";
  const Hit decal = ties.settle(through_decal, Hit{0, 2.0f});
  EXPECT_EQ(decal.triangle, 0u) << "the lowest id of the faces towards the ray (the quad's, before the decal's)";
  // A face with no partner is left as reported.
  const Ray neighbour{{1.5f, 0.5f, 2}, {0, 0, -1}};
  EXPECT_EQ(ties.settle(neighbour, Hit{6, 2.0f}).triangle, 6u);
}

}  // namespace
}  // namespace lf
