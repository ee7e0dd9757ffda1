// `lightfarm scene`: the description of an OBJ room — counts, flux as a closed form, textures found and missing,
// warnings, and a suggested camera whose view holds every corner of the scene's bounds.
#include "render/scene/scene_report.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "render/math.hpp"

namespace lf {
namespace {

// The path tracer as the report suggests it alone: pooled over this machine's cores.
std::string pathtrace_alone() {
  const unsigned cores = std::clamp(std::thread::hardware_concurrency(), 1u, 64u);
  const std::string op = "lightop \"pathtrace\" {}";
  return "renderers { lighting = " + (cores > 1 ? "multiplexer { " + op + ", replicas = " + std::to_string(cores) + " }" : op) + " }";
}

TEST(SceneReport, DescribesARoomAndFramesIt) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-report-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string obj = (dir / "room.obj").string();
  // A 2 x 2 x 2 room open at the front (floor, ceiling, back and side walls as quads, wound to face inwards as a
  // modelling package writes a room) and a 0.6 x 0.6 lamp emitting 10, facing down.
  std::ofstream(obj) << "mtllib room.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
                        "v -0.3 1.99 -0.3\nv 0.3 1.99 -0.3\nv 0.3 1.99 0.3\nv -0.3 1.99 0.3\n"
                        "usemtl white\nf 4 3 2 1\nf 5 6 7 8\nf 1 2 6 5\nf 1 5 8 4\nf 2 3 7 6\n"
                        "usemtl lamp\nf 9 10 11 12\nusemtl nope\nf 1 2 3\n";
  std::ofstream(dir / "room.mtl") << "newmtl white\nKd 0.7 0.7 0.7\nmap_Kd wood.png\nnewmtl lamp\nKd 0.5 0.5 0.5\n"
                                     "Ke 10 10 10\nmap_Kd wood.png\nmap_d cutout.png\n";
  std::ofstream(dir / "wood.png") << "not really a png";
  auto text = describe_scene(obj);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const std::string& t = *text;
  EXPECT_NE(t.find("  triangles  13\n"), std::string::npos) << t;
  EXPECT_NE(t.find("  bounds     {-1, 0, -1} to {1, 2, 1}, diagonal 3.464\n"), std::string::npos) << t;
  EXPECT_NE(t.find("    white  diffuse  kd {0.7, 0.7, 0.7}  faces 10\n"), std::string::npos) << t;
  // Flux of a one-sided Lambertian emitter: pi * area * Le = pi * 0.36 * 10.
  char flux[32];
  std::snprintf(flux, sizeof flux, "%.4g", kPi * 0.36 * 10);
  EXPECT_NE(t.find("  emitters   2 triangles, flux " + std::string(flux) + "\n"), std::string::npos) << t;
  // The lamp lights a room open at the front: part of its flux leaves (light_checks.test.cpp checks the share).
  EXPECT_NE(t.find("  flux " + std::string(flux) + "  escaping "), std::string::npos) << t;
  EXPECT_NE(t.find("  textures   2 files (1 missing)\n    cutout.png  map_d of 1  (missing)\n    wood.png  map_Kd of 2\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("usemtl 'nope' names no material"), std::string::npos) << t;
  // Diffuse surfaces only (the lamp too, and the grey default), which gather most of their light from each other:
  // a network of direct light and a cache.
  EXPECT_NE(t.find("  lobes      D (diffuse) on 3 materials\n"), std::string::npos) << t;
  const auto at_open = t.find("  open       ");
  ASSERT_NE(at_open, std::string::npos) << t;
  EXPECT_LT(std::atoi(t.c_str() + at_open + 13), 50) << t;
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
  EXPECT_NE(text->find(pathtrace_alone()), std::string::npos) << *text;
  EXPECT_EQ(text->find("irradiance"), std::string::npos) << *text;
}

// An object under an open sky (a block on a large ground): most of what its surfaces gather comes from outside the
// scene, the light bouncing between them is the small part a cache would hold, and a path tracer's paths end
// early: the suggestion is the path tracer. The same block inside a closed box gets the cache.
TEST(SceneReport, AnObjectUnderAnOpenSkyGetsThePathTracer) {
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-report-open-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  auto describe = [&](bool boxed) {
    const std::string obj = (dir / (boxed ? "boxed.obj" : "open.obj")).string();
    std::ofstream f(obj);
    f << "mtllib open.mtl\n"
         "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"                         // the ground
         "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\n"                 // the block's foot
         "v -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n"                 // and top
         "v -10 20 -10\nv 10 20 -10\nv 10 20 10\nv -10 20 10\n"                     // a lid for the box
         "usemtl grey\nf 4 3 2 1\nf 9 12 11 10\nf 9 10 6 5\nf 10 11 7 6\nf 11 12 8 7\nf 12 9 5 8\n";
    if (boxed) f << "f 13 14 15 16\nf 1 2 14 13\nf 2 3 15 14\nf 3 4 16 15\nf 4 1 13 16\n";
    f.close();
    std::ofstream(dir / "open.mtl") << "newmtl grey\nKd 0.5 0.5 0.5\n";
    return describe_scene(obj);
  };
  const auto open = describe(false), boxed = describe(true);
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(open.ok()) << open.error().message;
  ASSERT_TRUE(boxed.ok()) << boxed.error().message;
  const auto open_at = open->find("  open       "), boxed_at = boxed->find("  open       ");
  ASSERT_NE(open_at, std::string::npos) << *open;
  ASSERT_NE(boxed_at, std::string::npos) << *boxed;
  EXPECT_GT(std::atoi(open->c_str() + open_at + 13), 80) << *open;
  EXPECT_EQ(std::atoi(boxed->c_str() + boxed_at + 13), 0) << *boxed;
  EXPECT_NE(open->find(pathtrace_alone()), std::string::npos) << *open;
  EXPECT_EQ(open->find("irradiance"), std::string::npos) << *open;
  EXPECT_NE(boxed->find("lightop \"irradiance\""), std::string::npos) << *boxed;
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
