// Arvo's spherical triangle sampling against closed forms: an octant's solid angle, every sampled direction on the
// triangle, and the projected solid angle (Lambert's contour formula) from the sampled directions.
#include "render/lights/spherical_triangle.hpp"

#include <gtest/gtest.h>

#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

TEST(SphericalTriangle, AnOctantIsAnEighthOfTheSphere) {
  EXPECT_NEAR(spherical_triangle_solid_angle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), kPi / 2, 1e-6);
  EXPECT_NEAR(spherical_triangle_solid_angle({0, 0, 0}, {5, 0, 0}, {0, 0, 2}, {0, 3, 0}), kPi / 2, 1e-6);
  // Seen edge-on, or from a corner, it covers nothing.
  EXPECT_EQ(spherical_triangle_solid_angle({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 0, 1}), 0.0);
  EXPECT_EQ(spherical_triangle_solid_angle({1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 0.0);
}

TEST(SphericalTriangle, SampledDirectionsLandOnTheTriangleUniformlyInSolidAngle) {
  const Vec3 x{0.2f, 0.1f, -0.3f};
  const Vec3 p0{-1, 1, -1}, p1{1.5f, 1.2f, -0.5f}, p2{0, 0.8f, 2};
  const Vec3 n = normalize(cross(p1 - p0, p2 - p0));
  double omega = 0;
  Rng rng(7, 1);
  const int count = 200000;
  double projected = 0;  // the mean of cos(theta) at x (normal +y) over the sampled directions, times omega
  for (int i = 0; i < count; ++i) {
    const auto d = sample_spherical_triangle(x, p0, p1, p2, rng.uniform(), rng.uniform(), omega);
    ASSERT_TRUE(d.has_value());
    // On the triangle: where the ray meets its plane, barycentrics within [0, 1].
    const float t = dot(p0 - x, n) / dot(*d, n);
    ASSERT_GT(t, 0);
    const Vec3 y = x + *d * t;
    const float a0 = dot(cross(p1 - y, p2 - y), n), a1 = dot(cross(p2 - y, p0 - y), n), a2 = dot(cross(p0 - y, p1 - y), n);
    const float total = dot(cross(p1 - p0, p2 - p0), n);
    ASSERT_GE(a0 / total, -1e-4f);
    ASSERT_GE(a1 / total, -1e-4f);
    ASSERT_GE(a2 / total, -1e-4f);
    projected += std::max(0.0f, d->y);
  }
  EXPECT_NEAR(omega, spherical_triangle_solid_angle(x, p0, p1, p2), 1e-12);
  // Lambert: the projected solid angle over pi is the point-to-polygon form factor.
  const double form = test::form_factor(x, {0, 1, 0}, {p0, p1, p2});
  EXPECT_NEAR(projected / count * omega / kPi / form, 1.0, 0.01);
}

TEST(SphericalTriangle, TinyOrFlatTrianglesAreLeftToAreaSampling) {
  double omega = 1;
  EXPECT_FALSE(sample_spherical_triangle({0, 0, 0}, {100, 0, 0}, {100, 0.001f, 0}, {100, 0, 0.001f}, 0.5f, 0.5f, omega));
  EXPECT_LT(omega, kMinSampledSolidAngle);
  EXPECT_FALSE(sample_spherical_triangle({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {1, 0, 1}, 0.5f, 0.5f, omega));
}

}  // namespace
}  // namespace lf
