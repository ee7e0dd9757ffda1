#include "actors/runtime/answered_points.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace lf {

namespace {

// One material of each kind a point can be on: Lambert, Phong (with its Lambert lobe), mirror, glass, a lamp, a
// coated metal_rough base, and a Lambert surface with a mirror term.
std::vector<Material> one_of_each() {
  std::vector<Material> m(7);
  m[0].kd = {0.5f, 0.5f, 0.5f};
  m[1].type = Material::Type::glossy, m[1].kd = {0.4f, 0.4f, 0.4f}, m[1].ks = {0.2f, 0.2f, 0.2f}, m[1].ns = 40;
  m[2].type = Material::Type::mirror, m[2].ks = {0.9f, 0.9f, 0.9f};
  m[3].type = Material::Type::glass;
  m[4].ke = {5, 5, 5};
  m[5].type = Material::Type::metal_rough, m[5].kd = {0.8f, 0.2f, 0.1f}, m[5].metallic = 0;
  m[6].kd = {0.5f, 0.5f, 0.5f}, m[6].kr = {0.3f, 0.3f, 0.3f};
  return m;
}

// Points cycling over the materials, each with its own position and key.
ShadingPoints points_over(size_t count, size_t materials, bool with_triangles) {
  ShadingPoints p;
  for (size_t i = 0; i < count; ++i) {
    const Vec3 at{static_cast<float>(i), 0, 0};
    if (with_triangles)
      p.push_back(at, {0, 1, 0}, {0, 1, 0}, static_cast<uint32_t>(i % materials), 1000 + i, static_cast<uint32_t>(7 * i));
    else
      p.push_back(at, {0, 1, 0}, {0, 1, 0}, static_cast<uint32_t>(i % materials), 1000 + i);
  }
  return p;
}

}  // namespace

// Each op's answer ends decide which points it is asked about: the points left out are exactly those whose material
// has none of those lobes (and, for emission, does not emit), and the points kept are whole and in order.
TEST(AnsweredPoints, KeepExactlyThePointsWhoseMaterialsTheAnswerReaches) {
  const auto materials = one_of_each();
  struct Case {
    const char* ends;
    std::vector<uint32_t> reached;  // materials
  } cases[] = {
      {"G", {1, 5}},                   // glossy: the Phong lobe, metal_rough's coat
      {"S", {2, 3, 6}},                // specular: mirror, glass, the mirror term
      {"D", {0, 1, 5, 6}},             // irradiance
      {"DG", {0, 1, 5, 6}},            // direct
      {"L", {4}},                      // emission
      {"LDGS", {0, 1, 2, 3, 4, 5, 6}},  // everything (and the lamp, whose kd is black)
      {"", {}},
  };
  for (bool with_triangles : {false, true}) {
    const ShadingPoints points = points_over(40, materials.size(), with_triangles);
    for (const auto& c : cases) {
      SCOPED_TRACE(std::string("ends '") + c.ends + "', triangles " + (with_triangles ? "yes" : "no"));
      const auto ends = AnswerEnds::parse(c.ends);
      ASSERT_TRUE(ends);
      EXPECT_EQ(ends->letters(), c.ends);
      const AnsweredPoints a = answered_points(points, materials, *ends);
      std::vector<uint32_t> expected;
      for (uint32_t i = 0; i < points.size(); ++i)
        if (std::find(c.reached.begin(), c.reached.end(), points.material[i]) != c.reached.end()) expected.push_back(i);
      if (expected.size() == points.size()) {
        EXPECT_TRUE(a.all);
        EXPECT_TRUE(a.index.empty());
        continue;
      }
      ASSERT_FALSE(a.all);
      EXPECT_EQ(a.index, expected);
      ASSERT_EQ(a.points.size(), expected.size());
      EXPECT_EQ(a.points.triangle.size(), with_triangles ? expected.size() : 0u);
      for (size_t k = 0; k < expected.size(); ++k) {
        const uint32_t i = expected[k];
        EXPECT_EQ(a.points.position[k].x, points.position[i].x);
        EXPECT_EQ(a.points.material[k], points.material[i]);
        EXPECT_EQ(a.points.key[k], points.key[i]);
        if (with_triangles) EXPECT_EQ(a.points.triangle[k], points.triangle[i]);
      }
    }
  }
}

// A material index the scene does not have is kept, for the receiver to refuse as before; letters other than
// L, D, G, S are no answer ends.
TEST(AnsweredPoints, KeepUnknownMaterialsAndRefuseUnknownLetters) {
  const auto materials = one_of_each();
  ShadingPoints p;
  p.push_back({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 0, 1);
  p.push_back({1, 0, 0}, {0, 1, 0}, {0, 1, 0}, 99, 2);
  const AnsweredPoints a = answered_points(p, materials, *AnswerEnds::parse("S"));
  ASSERT_FALSE(a.all);
  EXPECT_EQ(a.index, std::vector<uint32_t>{1});
  EXPECT_FALSE(AnswerEnds::parse("DX"));
  EXPECT_FALSE(AnswerEnds::parse("d"));
}

}  // namespace lf
