#include "render/tracing/tied_hits.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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

TEST(TiedHits, OverlappingFacesArePartnersAndNeighboursAreNot) {
  Scene s = tied_scene();
  TiedHits ties(s);
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
TEST(TiedHits, TheFaceTowardsTheRayWinsWhicheverWasReported) {
  Scene s = tied_scene();
  TiedHits ties(s);
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

// Faces that only share edges and corners, each triangle with its own vertices (as add_triangle writes them): a
// unit quad on z = 0 whose diagonal runs from (0, 0) to (1, 1) (triangles 0, 1); a box's edge where a top facing +y
// meets a side facing +x along x = 3, y = 1 (2, 3 and 4, 5); a fan of six triangles around (5.5, 0.5, 0) (6-11).
Scene edge_scene() {
  Scene s;
  const uint32_t m = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {}});
  const uint32_t lamp = s.add_material(Material{"lamp", {}, {1, 1, 1}});
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, m);
  s.add_quad({2, 1, 0}, {2, 1, 1}, {3, 1, 1}, {3, 1, 0}, m);
  s.add_quad({3, 0, 0}, {3, 1, 0}, {3, 1, 1}, {3, 0, 1}, m);
  const Vec3 centre{5.5f, 0.5f, 0};
  for (int k = 0; k < 6; ++k) {
    const float a = 2 * kPi * static_cast<float>(k) / 6, b = 2 * kPi * static_cast<float>(k + 1) / 6;
    s.add_triangle(centre, centre + Vec3{0.5f * std::cos(a), 0.5f * std::sin(a), 0},
                   centre + Vec3{0.5f * std::cos(b), 0.5f * std::sin(b), 0}, m);
  }
  s.add_quad({0, 0, 5}, {1, 0, 5}, {1, 1, 5}, {0, 1, 5}, lamp);
  EXPECT_TRUE(s.finalize("edges"));
  return s;
}

// Every face a BVH could report for the ray (each contains the hit point) settles to one face at one distance.
void expect_one_answer(const TiedHits& ties, const Ray& ray, std::vector<uint32_t> reportable, uint32_t expected,
                       const char* what) {
  for (uint32_t reported : reportable) {
    const Hit settled = ties.settle(ray, Hit{reported, 1.0f});
    EXPECT_EQ(settled.triangle, expected) << what << ", reported " << reported;
    EXPECT_EQ(settled.t, ties.settle(ray, Hit{reportable.front(), 1.0f}).t) << what << ", reported " << reported;
  }
}

// A ray on an edge or corner that faces share hits each of them; a packet and a single ray, or two parts' BVHs, can
// report different ones. The rule picks one whichever was reported: the lowest id of those facing the ray.
TEST(TiedHits, AHitOnASharedEdgeOrCornerSettlesToOneFace) {
  Scene s = edge_scene();
  TiedHits ties(s);
  EXPECT_EQ(ties.tied_triangles(), 0u) << "no face here overlaps another";
  expect_one_answer(ties, Ray{{0.5f, 0.5f, 2}, {0, 0, -1}}, {0, 1}, 0, "the quad's diagonal");
  expect_one_answer(ties, Ray{{4, 2, 0.5f}, normalize(Vec3{-1, -1, 0})}, {3, 4}, 3, "the box's edge");
  expect_one_answer(ties, Ray{{5.5f, 0.5f, 2}, {0, 0, -1}}, {6, 7, 8, 9, 10, 11}, 6, "the fan's centre");
  // The faces at a corner are found by position: the quad's corner (1, 1) is written once per triangle.
  EXPECT_EQ(ties.fan(0, 2).size(), 2u);
  EXPECT_EQ(ties.fan(6, 0).size(), 6u);
}

// A ray through the diagonal of a wall's quad, from Lost Empire (one of its camera rays): a floor beyond the wall
// has a corner at the diagonal's end, and the ray meets the floor too, farther on and inside it. That is no tie: the
// wall is what the ray hits, whichever of its two triangles was reported, even though the floor has the lower id.
TEST(TiedHits, AFaceThatSharesACornerButIsMetFartherOnIsNoTie) {
  Scene s;
  const uint32_t m = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {}});
  const uint32_t lamp = s.add_material(Material{"lamp", {}, {1, 1, 1}});
  s.add_triangle({-7, 15, 20}, {-5, 15, 21}, {-5, 15, 17}, m);  // 0: the floor, facing +y
  s.add_triangle({-7, 15, 19}, {-7, 15, 20}, {-7, 16, 19}, m);  // 1, 2: the wall, facing -x
  s.add_triangle({-7, 15, 20}, {-7, 16, 20}, {-7, 16, 19}, m);
  s.add_quad({-10, 20, 18}, {-9, 20, 18}, {-9, 20, 19}, {-10, 20, 19}, lamp);
  ASSERT_TRUE(s.finalize("wall and floor"));
  TiedHits ties(s);
  const Ray ray{{-8, 16, 20}, {0.804641306f, -0.522382975f, -0.282255888f}};
  for (uint32_t reported : {1u, 2u}) {
    const Hit settled = ties.settle(ray, Hit{reported, 1.24278975f});
    EXPECT_EQ(settled.triangle, 1u) << "reported " << reported;
    EXPECT_NEAR(settled.t, 1.24278975f, 1e-5f) << "reported " << reported;
  }
}

// Away from every edge nothing changes: the face and distance the BVH reported stand. Next to an edge (within
// kEdgeBand) both overloads agree, whether the barycentrics come from the BVH or are worked out here.
TEST(TiedHits, AHitAwayFromEdgesIsLeftAsReported) {
  Scene s = edge_scene();
  TiedHits ties(s);
  const Ray inside{{0.25f, 0.75f, 2}, {0, 0, -1}};
  const Hit kept = ties.settle(inside, Hit{1, 2.0f});
  EXPECT_EQ(kept.triangle, 1u);
  EXPECT_EQ(kept.t, 2.0f) << "the BVH's own distance";
  EXPECT_EQ(ties.settle(inside, Hit{1, 2.0f}, 0.25f, 0.5f).t, 2.0f);
  const Ray near_diagonal{{0.5f + 2e-6f, 0.5f, 2}, {0, 0, -1}};
  for (uint32_t reported : {0u, 1u}) {
    const Hit computed = ties.settle(near_diagonal, Hit{reported, 2.0f});
    // What a BVH would give there (u, v: the weights of corners 1 and 2) on each of the quad's triangles.
    const Hit given = reported == 0 ? ties.settle(near_diagonal, Hit{0, 2.0f}, 2e-6f, 0.5f)
                                    : ties.settle(near_diagonal, Hit{1, 2.0f}, 0.5f, 0.5f);
    EXPECT_EQ(computed.triangle, 0u);
    EXPECT_EQ(given.triangle, 0u);
    EXPECT_EQ(computed.t, given.t);
  }
}

}  // namespace
}  // namespace lf
