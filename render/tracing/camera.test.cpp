#include "render/tracing/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lf {
namespace {

CameraSpec lens(double aperture, double focus_distance = 0) {
  CameraSpec spec;
  spec.eye = {1, 2, 3};
  spec.at = {1, 2, 13};  // 10 ahead
  spec.fov = 40;
  spec.aperture = aperture;
  spec.focus_distance = focus_distance;
  return spec;
}

// Where a ray crosses the plane `depth` ahead of the eye along the view (+z here).
Vec3 at_depth(const Ray& r, float eye_z, float depth) {
  const float t = (eye_z + depth - r.origin.z) / r.direction.z;
  return r.origin + r.direction * t;
}

TEST(Camera, WithoutALensEveryLensSampleIsThePinholesRay) {
  const Camera pinhole(lens(0), 64, 48);
  EXPECT_FALSE(pinhole.has_lens());
  const Ray a = pinhole.ray(10.3f, 20.7f), b = pinhole.ray(10.3f, 20.7f, 0.9f, 0.1f);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.direction, b.direction);
}

// Thin-lens geometry: rays through one image point from anywhere on the lens meet on the focal plane, leave from
// the lens disk, and at another depth z spread over aperture x |1 - z / focus| (similar triangles).
TEST(Camera, LensRaysMeetOnTheFocalPlaneAndSpreadElsewhere) {
  for (double focus : {0.0, 4.0}) {
    const Camera camera(lens(0.5, focus), 64, 48);
    ASSERT_TRUE(camera.has_lens());
    const float fd = focus > 0 ? static_cast<float>(focus) : 10.0f;  // 0: focused on `at`
    const Ray pinhole = camera.ray(40.25f, 11.5f);
    const Vec3 sharp = at_depth(pinhole, 3, fd);
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < 16; ++i)
      for (int j = 0; j < 16; ++j) {
        const Ray r = camera.ray(40.25f, 11.5f, (i + 0.5f) / 16, (j + 0.5f) / 16);
        EXPECT_NEAR(length(r.direction), 1.0f, 1e-5f);
        EXPECT_NEAR(r.origin.z, 3.0f, 1e-6f) << "the lens faces the view";
        EXPECT_LE(length(r.origin - Vec3{1, 2, 3}), 0.25f + 1e-6f) << "inside the lens";
        EXPECT_LT(length(at_depth(r, 3, fd) - sharp), 1e-5f * fd) << "through the focal point";
        const float x = at_depth(r, 3, 2 * fd).x;
        lo = std::min(lo, x), hi = std::max(hi, x);
      }
    // The lens's horizontal extent (the concentric map reaches the rim at u = 0 and 1 on v = 0.5) at depth 2 fd:
    // 0.5 x |1 - 2| = 0.5, less what the 16 strata miss of the rim.
    EXPECT_NEAR(hi - lo, 0.5f, 0.5f / 16 * 2) << "focus " << focus;
    const Ray rim_left = camera.ray(40.25f, 11.5f, 0, 0.5f), rim_right = camera.ray(40.25f, 11.5f, 1, 0.5f);
    const float at_lens = rim_right.origin.x - rim_left.origin.x;
    EXPECT_NEAR(std::abs(at_lens), 0.5f, 1e-5f) << "u = 0 and 1 are the rim";
    EXPECT_NEAR(at_depth(rim_right, 3, 2 * fd).x - at_depth(rim_left, 3, 2 * fd).x, -at_lens, 1e-4f)
        << "past the focus the rays have crossed";
  }
}

TEST(Camera, TheSpecReadsTheLensAndRefusesANegativeOne) {
  ParamTable p(Value::Map{{"aperture", 0.1}, {"focus_distance", 3.0}}, "camera");
  const CameraSpec spec = CameraSpec::read(p);
  EXPECT_EQ(spec.aperture, 0.1);
  EXPECT_EQ(spec.focus_distance, 3.0);
  auto back = CameraSpec::from_value(spec.to_value());
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->aperture, 0.1);
  EXPECT_EQ(CameraSpec{}.to_value().find("aperture"), nullptr) << "a pinhole's CONFIG is what it was";
  ParamTable bad(Value::Map{{"aperture", -1.0}}, "camera");
  EXPECT_THROW(CameraSpec::read(bad), ParamError);
  // Focus on a point: its distance along the view (the default camera looks down +z from z = -800).
  ParamTable point(Value::Map{{"aperture", 10.0}, {"focus", Value::Array{100.0, 50.0, 200.0}}}, "camera");
  EXPECT_DOUBLE_EQ(CameraSpec::read(point).focus_distance, 1000.0);
  ParamTable behind(Value::Map{{"focus", Value::Array{0.0, 0.0, -900.0}}}, "camera");
  try {
    CameraSpec::read(behind);
    ADD_FAILURE() << "a focus point behind the camera was taken";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "camera: the focus point is not in front of the camera");
  }
  ParamTable both(Value::Map{{"focus", Value::Array{0.0, 0.0, 0.0}}, {"focus_distance", 5.0}}, "camera");
  EXPECT_THROW(CameraSpec::read(both), ParamError);
}

}  // namespace
}  // namespace lf
