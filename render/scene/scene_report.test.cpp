// `lightfarm scene`: the description of an OBJ room — counts, flux as a closed form, textures found and missing,
// warnings, and a suggested camera whose view holds every corner of the scene's bounds.
#include "render/scene/scene_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "render/math.hpp"

namespace lf {
namespace {

TEST(SceneReport, DescribesARoomAndFramesIt) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-report-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string obj = (dir / "room.obj").string();
  // A 2 x 2 x 2 room (floor, ceiling, back wall as quads) and a 0.6 x 0.6 lamp emitting 10.
  std::ofstream(obj) << "mtllib room.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
                        "v -0.3 1.99 -0.3\nv 0.3 1.99 -0.3\nv 0.3 1.99 0.3\nv -0.3 1.99 0.3\n"
                        "usemtl white\nf 1 2 3 4\nf 8 7 6 5\nf 5 6 2 1\nusemtl lamp\nf 12 11 10 9\nusemtl nope\nf 1 2 3\n";
  std::ofstream(dir / "room.mtl") << "newmtl white\nKd 0.7 0.7 0.7\nmap_Kd wood.png\nnewmtl lamp\nKd 0.5 0.5 0.5\n"
                                     "Ke 10 10 10\nmap_Kd wood.png\nmap_d cutout.png\n";
  std::ofstream(dir / "wood.png") << "not really a png";
  auto text = describe_scene(obj);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const std::string& t = *text;
  EXPECT_NE(t.find("  triangles  9\n"), std::string::npos) << t;
  EXPECT_NE(t.find("  bounds     {-1, 0, -1} to {1, 2, 1}, diagonal 3.464\n"), std::string::npos) << t;
  EXPECT_NE(t.find("    white  diffuse  kd {0.7, 0.7, 0.7}  faces 6\n"), std::string::npos) << t;
  // Flux of a one-sided Lambertian emitter: pi * area * Le = pi * 0.36 * 10.
  char flux[32];
  std::snprintf(flux, sizeof flux, "%.4g", kPi * 0.36 * 10);
  EXPECT_NE(t.find("  emitters   2 triangles, flux " + std::string(flux) + "\n"), std::string::npos) << t;
  // The lamp lights an open room (three walls): part of its flux leaves (light_checks.test.cpp checks the share).
  EXPECT_NE(t.find("  flux " + std::string(flux) + "  escaping "), std::string::npos) << t;
  EXPECT_NE(t.find("  textures   2 files (1 missing)\n    cutout.png  map_d of 1  (missing)\n    wood.png  map_Kd of 2\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("usemtl 'nope' names no material"), std::string::npos) << t;
  // Diffuse surfaces only (the lamp too, and the grey default): a network of direct light and a cache.
  EXPECT_NE(t.find("  lobes      D (diffuse) on 3 materials\n"), std::string::npos) << t;
  EXPECT_NE(t.find("renderers { lighting = lightop \"combine\" { inputs = { direct, indirect } } }"), std::string::npos) << t;

  // The suggested camera sees every corner of the bounds within its 45-degree field of view.
  const auto at_camera = t.find("camera { eye = {");
  ASSERT_NE(at_camera, std::string::npos) << t;
  Vec3 eye, at;
  ASSERT_EQ(std::sscanf(t.c_str() + at_camera, "camera { eye = {%f, %f, %f}, at = {%f, %f, %f}", &eye.x, &eye.y, &eye.z,
                        &at.x, &at.y, &at.z),
            6);
  const Vec3 forward = normalize(at - eye);
  for (float x : {-1.0f, 1.0f})
    for (float y : {0.0f, 2.0f})
      for (float z : {-1.0f, 1.0f}) {
        const float angle = std::acos(std::min(1.0f, dot(forward, normalize(Vec3{x, y, z} - eye)))) * 180.0f / kPi;
        EXPECT_LT(angle, 22.5f) << x << " " << y << " " << z;
      }
  EXPECT_EQ(describe_scene((dir / "none.obj").string()).error().message,
            "scene file '" + (dir / "none.obj").string() + "' not found");
  std::filesystem::remove_all(dir);
}

// A material-test setup: a small knob in front of a large backdrop, lit by a lamp on the same side (-z). The camera
// looks from that side, where the backdrop's lit face and the knob are, not at the backdrop's unlit back (+z, the
// view every scene got before: an image of zeros).
// Metal surfaces only (glTF's metal-roughness model everywhere, a black lamp): a cache would hold only the metals'
// multiply scattered light, so the suggestion is the path tracer, which the light-path check finds complete.
TEST(SceneReport, AllGlossyScenesGetThePathTracer) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-report-glossy-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string obj = (dir / "balls.obj").string();
  std::ofstream(obj) << "mtllib balls.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -0.3 1.99 -0.3\nv 0.3 1.99 -0.3\n"
                        "v 0.3 1.99 0.3\nv -0.3 1.99 0.3\nusemtl gold\nf 1 2 3 4\nusemtl lamp\nf 8 7 6 5\n";
  std::ofstream(dir / "balls.mtl") << "newmtl gold\nKd 0.9 0.7 0.3\nPr 0.4\nPm 1\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n";
  auto text = describe_scene(obj);
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(text.ok()) << text.error().message;
  EXPECT_NE(text->find("  lobes      D (diffuse) on 1 material, G (glossy) on 1 material\n"), std::string::npos) << *text;
  EXPECT_NE(text->find("renderers { lighting = lightop \"pathtrace\" {} }"), std::string::npos) << *text;
  EXPECT_EQ(text->find("irradiance"), std::string::npos) << *text;
}

TEST(SceneReport, TheSuggestedCameraLooksAtTheLitSide) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-report-lit-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string obj = (dir / "knob.obj").string();
  std::ofstream(obj) << "mtllib knob.mtl\n"
                        "v -5 0 0\nv 5 0 0\nv 5 5 0\nv -5 5 0\n"                      // backdrop in z = 0
                        "v -0.5 4 -3\nv 0.5 4 -3\nv 0.5 4 -2\nv -0.5 4 -2\n"          // lamp, 4 up, in front
                        "v -0.3 0 -1.3\nv 0.3 0 -1.3\nv 0.3 0.6 -1.3\nv -0.3 0.6 -1.3\n"  // knob's front face
                        "usemtl grey\nf 1 2 3 4\nf 9 10 11 12\nusemtl lamp\nf 5 6 7 8\n";
  std::ofstream(dir / "knob.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 5 5 5\n";
  auto text = describe_scene(obj);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const auto at_camera = text->find("camera { eye = {");
  ASSERT_NE(at_camera, std::string::npos) << *text;
  Vec3 eye, at;
  ASSERT_EQ(std::sscanf(text->c_str() + at_camera, "camera { eye = {%f, %f, %f}, at = {%f, %f, %f}", &eye.x, &eye.y,
                        &eye.z, &at.x, &at.y, &at.z),
            6);
  EXPECT_LT(eye.z, at.z - 1) << *text;
  std::filesystem::remove_all(dir);
}

// A glTF file's own cameras are listed by the names camera { gltf = ... } takes, an animated one with its length.
TEST(SceneReport, AGltfFilesCamerasAreListedWithTheirAnimation) {
  auto text = describe_scene(std::string(LIGHTFARM_SOURCE_DIR) + "/render/scene/testdata/camera_walk.gltf");
  ASSERT_TRUE(text.ok()) << text.error().message;
  EXPECT_NE(text->find("camera { gltf = \"Camera\" }  (animated, 1 s: frame n at n / fps)"), std::string::npos) << *text;
}

}  // namespace
}  // namespace lf
