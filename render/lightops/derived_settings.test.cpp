// Settings derived from the scene and the image: the hemisphere and the error bound follow the lit samples a pixel,
// and a record's least radius is the reach of a few of the camera's pixels there.
#include "render/lightops/derived_settings.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

TEST(DerivedSettings, CacheHemisphereFollowsTheLitSamples) {
  EXPECT_EQ(cache_hemisphere(16).theta, 8);  // the constant default it replaces, at 16 lit samples
  EXPECT_EQ(cache_hemisphere(16).phi, 24);
  int previous = 0;
  for (int lit : {1, 4, 16, 64, 256, 4096}) {
    const HemisphereStrata s = cache_hemisphere(lit);
    EXPECT_EQ(s.phi, 3 * s.theta);
    EXPECT_GE(s.count(), previous) << lit;
    previous = s.count();
  }
  // About 12 rays per lit sample between the bounds.
  EXPECT_NEAR(cache_hemisphere(64).count() / (12.0 * 64), 1.0, 0.1);
  EXPECT_EQ(cache_hemisphere(0).theta, 6);
  EXPECT_EQ(cache_hemisphere(1).theta, 6);
  EXPECT_EQ(cache_hemisphere(100000).theta, 24);
}

TEST(DerivedSettings, CacheAccuracyTightensAsThePixelsNoiseFalls) {
  EXPECT_FLOAT_EQ(cache_accuracy(16), 0.2f);  // the constant default it replaces, at 16 lit samples
  EXPECT_FLOAT_EQ(cache_accuracy(64), 0.1f);  // halved for four times the samples
  EXPECT_NEAR(cache_accuracy(32), 0.2f / std::sqrt(2.0f), 1e-6f);
  EXPECT_FLOAT_EQ(cache_accuracy(256), 0.05f);
  EXPECT_FLOAT_EQ(cache_accuracy(4096), 0.05f);  // no finer than 0.05
  EXPECT_FLOAT_EQ(cache_accuracy(4), 0.3f);      // no coarser than 0.3
  EXPECT_FLOAT_EQ(cache_accuracy(0), 0.3f);
}

TEST(DerivedSettings, RecordRadiusFloorIsAFewPixelsThere) {
  const int w = 200, h = 100;
  const Camera camera(CameraSpec{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60}, w, h);
  SceneContext ctx;
  EXPECT_EQ(record_radius_floor(ctx, {0, 0, -10}, {0, 0, 1}, 2, 0.2f), 0.0f) << "no camera, no floor";
  ctx.camera = &camera;
  const float pixel_at_10 = 10 * camera.pixel_angle();
  // Facing the camera: 2 pixels' reach under a = 0.2 is R = 2 pixels / 0.2.
  EXPECT_NEAR(record_radius_floor(ctx, {0, 0, -10}, {0, 0, 1}, 2, 0.2f), 2 * pixel_at_10 / 0.2f, 1e-5f);
  // Twice as far: twice the floor; reach 0: none.
  EXPECT_NEAR(record_radius_floor(ctx, {0, 0, -20}, {0, 0, 1}, 2, 0.2f), 4 * pixel_at_10 / 0.2f, 1e-5f);
  EXPECT_EQ(record_radius_floor(ctx, {0, 0, -10}, {0, 0, 1}, 0, 0.2f), 0.0f);
  // Seen at 60 degrees from its normal, a pixel covers twice the surface; at grazing angles at most four times.
  const Vec3 tilted{0, std::sin(kPi / 3), std::cos(kPi / 3)};
  EXPECT_NEAR(record_radius_floor(ctx, {0, 0, -10}, tilted, 2, 0.2f), 2 * 2 * pixel_at_10 / 0.2f, 1e-4f);
  EXPECT_NEAR(record_radius_floor(ctx, {0, 0, -10}, {0, 1, 0}, 2, 0.2f), 4 * 2 * pixel_at_10 / 0.2f, 1e-4f);
}

}  // namespace
}  // namespace lf
