// A job's frames without Lua: --frames lists, output patterns, keyframed cameras and the rules between them.
#include "farm/job.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/params.hpp"

namespace lf {
namespace {

template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

Value vec(double x, double y, double z) { return Value::Array{x, y, z}; }

Value key(double frame, Value eye, Value at, double fov = 40) {
  return Value::Map{{"frame", frame}, {"eye", std::move(eye)}, {"at", std::move(at)}, {"fov", fov}};
}

TEST(FrameList, NumbersAndRangesAscendingOnce) {
  EXPECT_EQ(parse_frame_list("3"), std::vector<int>({3}));
  EXPECT_EQ(parse_frame_list("1-4,10,3"), std::vector<int>({1, 2, 3, 4, 10}));
  EXPECT_EQ(parse_frame_list("7-7"), std::vector<int>({7}));
  EXPECT_EQ(error_of([] { parse_frame_list("5-2"); }), "--frames '5-2': range 5-2 runs backwards (give numbers and ranges, e.g. 1-240,300)");
  EXPECT_NE(error_of([] { parse_frame_list("1,,2"); }).find("'' is not a frame number"), std::string::npos);
  EXPECT_NE(error_of([] { parse_frame_list("a"); }).find("'a' is not a frame number"), std::string::npos);
  EXPECT_NE(error_of([] { parse_frame_list("1-"); }).find("is not a frame number"), std::string::npos);
}

TEST(FrameOutput, TheLastRunOfHashesInTheFileNameTakesTheNumber) {
  EXPECT_EQ(frame_output("walk.####.png", 7), "walk.0007.png");
  EXPECT_EQ(frame_output("walk.##.png", 12345), "walk.12345.png");
  EXPECT_EQ(frame_output("out/#/walk_###.exr", 3), "out/#/walk_003.exr") << "a folder's # is not the frame's";
  EXPECT_EQ(frame_output("plain.png", 3), "plain.png");
  EXPECT_TRUE(has_frame_pattern("a/walk.#.png"));
  EXPECT_FALSE(has_frame_pattern("a#/walk.png"));
}

TEST(CameraKeys, PassThroughEveryKeyAndHoldBeyondTheEnds) {
  const auto keys = read_camera_keys({key(1, vec(0, 0, -10), vec(0, 0, 0), 30), key(5, vec(10, 0, -10), vec(0, 0, 0), 50),
                                      key(9, vec(10, 0, 0), vec(0, 1, 0), 30)},
                                     CameraSpec{});
  ASSERT_EQ(keys.size(), 3u);
  for (const auto& k : keys) {
    const CameraSpec c = interpolate_camera(keys, k.frame);
    EXPECT_EQ(c.eye, k.camera.eye);
    EXPECT_EQ(c.at, k.camera.at);
    EXPECT_EQ(c.fov, k.camera.fov);
  }
  EXPECT_EQ(interpolate_camera(keys, -3).eye, keys[0].camera.eye);
  EXPECT_EQ(interpolate_camera(keys, 20).eye, keys[2].camera.eye);
  EXPECT_DOUBLE_EQ(interpolate_camera(keys, 3).fov, 40) << "fov is linear between keys";
  // Two keys: the spline is the straight line between them, at constant speed.
  const auto line = read_camera_keys({key(0, vec(0, 0, -10), vec(0, 0, 0)), key(4, vec(8, 0, -10), vec(8, 0, 0))}, CameraSpec{});
  EXPECT_NEAR(interpolate_camera(line, 1).eye[0], 2, 1e-12);
  EXPECT_NEAR(interpolate_camera(line, 3).at[0], 6, 1e-12);
}

TEST(CameraKeys, TheCurveIsSmoothThroughAKey) {
  // Keys on a circle: the velocity just before and just after the middle key agree (C1), which a polyline's do not.
  std::vector<Value> raw;
  for (int i = 0; i < 5; ++i) {
    const double a = i * 0.5;
    raw.push_back(key(i * 2, vec(10 * std::cos(a), 0, 10 * std::sin(a)), vec(0, 0, 0)));
  }
  const auto keys = read_camera_keys(raw, CameraSpec{});
  const double h = 1e-5;
  const auto before = interpolate_camera(keys, 4 - h).eye, at = interpolate_camera(keys, 4).eye,
             after = interpolate_camera(keys, 4 + h).eye;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR((at[c] - before[c]) / h, (after[c] - at[c]) / h, 1e-3);
  // Halfway between keys it lies near the circle (radius 10), not on the chord (9.69).
  const auto mid = interpolate_camera(keys, 3).eye;
  EXPECT_NEAR(std::hypot(mid[0], mid[2]), 10.0, 0.05);
}

TEST(CameraKeys, KeysMustBeInOrderAndEachACamera) {
  EXPECT_EQ(error_of([] { read_camera_keys({key(3, vec(0, 0, -1), vec(0, 0, 0)), key(3, vec(1, 0, -1), vec(0, 0, 0))}, CameraSpec{}); }),
            "camera: keys[2]: frame 3 does not come after the key before it (3); keys go in order of frame");
  EXPECT_EQ(error_of([] { read_camera_keys({Value::Map{{"eye", vec(0, 0, -1)}}}, CameraSpec{}); }), "camera: keys[1] has no frame");
  EXPECT_EQ(error_of([] { read_camera_keys({key(1, vec(0, 0, 0), vec(0, 0, 0))}, CameraSpec{}); }),
            "camera: keys[1]: camera: eye and at are the same point");
  EXPECT_NE(error_of([] { read_camera_keys({Value::Map{{"frame", 1}, {"eys", vec(0, 0, 1)}}}, CameraSpec{}); }).find("eys"),
            std::string::npos);
}

TEST(ExpandFrames, SelectionOutputsAndCamerasPerFrame) {
  JobSpec job;
  job.declared = true;
  job.first = 1, job.last = 9, job.step = 2;
  EXPECT_EQ(job.numbers(), std::vector<int>({1, 3, 5, 7, 9}));
  CameraSpec base;
  job.camera_of_frame[3] = Value::Map{{"eye", vec(1, 2, 3)}};
  auto frames = expand_frames(job, base, "t.###.png", {});
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames[1].number, 3);
  EXPECT_EQ(frames[1].output, "t.003.png");
  EXPECT_EQ(frames[1].camera.eye, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(frames[1].camera.at, base.at) << "what the function leaves out comes from camera { }";
  EXPECT_EQ(frames[0].camera.eye, base.eye);
  EXPECT_TRUE(frames[1].selected);
  frames = expand_frames(job, base, "t.###.png", {5, 9});
  ASSERT_EQ(frames.size(), 5u) << "the job's frames, the first with the camera the farm is set up from";
  EXPECT_FALSE(frames[0].selected);
  EXPECT_TRUE(frames[2].selected);
  EXPECT_FALSE(frames[3].selected);
  EXPECT_TRUE(frames[4].selected);
  EXPECT_EQ(frames[4].output, "t.009.png");
  EXPECT_EQ(error_of([&] { expand_frames(job, base, "t.###.png", {4}); }),
            "--frames: frame 4 is not one of the script's frames (1-9 by 2)");
  EXPECT_NE(error_of([&] { expand_frames(job, base, "t.png", {}); }).find("has no #### where the frame number goes"),
            std::string::npos);
  job.last = 1;
  EXPECT_EQ(expand_frames(job, base, "t.png", {}).at(0).output, "t.png") << "one frame needs no ####";
}

}  // namespace
}  // namespace lf
