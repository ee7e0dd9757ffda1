#include "radiosity/solver.hpp"

#include <gtest/gtest.h>

#include "radiosity/ply.hpp"
#include "render/test_support.hpp"

namespace lf::radiosity {
namespace {

TEST(FormFactor, MatchesLambertAboveTheHorizonAndClipsBelowIt) {
  const Polygon square{{Vec3{-1, 2, -1}, Vec3{1, 2, -1}, Vec3{1, 2, 1}, Vec3{-1, 2, 1}}, 4};  // faces down
  EXPECT_NEAR(point_to_polygon({0, 0, 0}, {0, 1, 0}, square),  // the reference normalizes in float
              test::form_factor({0, 0, 0}, {0, 1, 0}, {square.v[0], square.v[1], square.v[2], square.v[3]}), 1e-6);
  // Seen from behind it sends nothing.
  EXPECT_EQ(point_to_polygon({0, 3, 0}, {0, -1, 0}, square), 0.0);
  // A wall standing on the receiver's plane, half of it sunk below: only the upper half counts.
  const Polygon wall{{Vec3{-1, -1, 2}, Vec3{-1, 1, 2}, Vec3{1, 1, 2}, Vec3{1, -1, 2}}, 4};
  const Polygon upper{{Vec3{-1, 0, 2}, Vec3{-1, 1, 2}, Vec3{1, 1, 2}, Vec3{1, 0, 2}}, 4};
  EXPECT_NEAR(point_to_polygon({0, 0, 0}, {0, 1, 0}, wall), point_to_polygon({0, 0, 0}, {0, 1, 0}, upper), 1e-9);
  EXPECT_GT(point_to_polygon({0, 0, 0}, {0, 1, 0}, upper), 0.01);
}

TEST(Tiling, ChildrenCoverTheParent) {
  const Polygon q{{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{2, 0, 1}, Vec3{0, 0, 1}}, 4};
  const Polygon t{{Vec3{0, 0, 0}, Vec3{2, 0, 0}, Vec3{0, 0, 1}, Vec3{}}, 3};
  for (const Polygon& p : {q, t}) {
    for (int k : {1, 2, 3, 5}) {
      double area = 0;
      for (const auto& c : tile(p, k)) area += c.area();
      EXPECT_EQ(tile(p, k).size(), static_cast<size_t>(k * k));
      EXPECT_NEAR(area, p.area(), 1e-5);
    }
    double area = 0;
    for (const auto& c : split4(p)) area += c.area();
    EXPECT_NEAR(area, p.area(), 1e-5);
  }
}

Mesh furnace_mesh(float rho, float radiosity) {
  Scene s;
  const uint32_t m = s.add_material({"furnace", {rho, rho, rho}, RGB{1, 1, 1} * (radiosity / kPi)});
  test::add_closed_box(s, m);
  auto mesh = build_mesh(s, {0.5f, 0.25f});
  EXPECT_TRUE(mesh) << mesh.error().message;
  return *mesh;
}

// A closed box that emits E everywhere and reflects rho converges to B = E / (1 - rho).
TEST(SerialSolver, FurnaceConvergesToTheClosedForm) {
  for (float rho : {0.5f, 0.8f}) {
    const Mesh mesh = furnace_mesh(rho, 2.0f);
    ASSERT_EQ(mesh.patches.size(), 24u);
    SolverSettings settings;
    settings.converge = 1e-4;
    const SceneVisibility vis(mesh);
    const auto result = solve_serial(mesh, settings, std::cref(vis));
    EXPECT_LT(result.unshot_fraction, 1e-4);
    const double expected = 2.0 / (1.0 - rho);
    size_t leaves = 0;
    for (const auto& e : result.elements) {
      if (!e.leaf) continue;
      ++leaves;
      EXPECT_NEAR(average(e.radiosity) / expected, 1.0, 0.01) << "rho " << rho;
    }
    EXPECT_EQ(leaves, 96u);
  }
}

// Each shot sends the shooter's power to the other faces of a closed box; none is made or lost on the way
// (up to the sampling of each element at its Gauss points).
TEST(SerialSolver, EnergyIsConservedPerIteration) {
  const Mesh mesh = furnace_mesh(0.6f, 1.0f);
  SolverSettings settings;
  settings.max_iterations = 60;
  settings.converge = 0;
  const SceneVisibility vis(mesh);
  const auto result = solve_serial(mesh, settings, std::cref(vis));
  ASSERT_EQ(result.iterations.size(), 60u);
  double previous = 1.0;
  for (const auto& it : result.iterations) {
    EXPECT_NEAR(it.power_arrived / it.power_shot, 1.0, 0.02) << "shooter " << it.shooter;
    // What arrives is reflected (rho) and the rest absorbed, so unshot power only falls.
    EXPECT_LE(it.unshot_fraction, previous + 1e-12);
    previous = it.unshot_fraction;
  }
}

TEST(SerialSolver, CornellBoxLightsTheRoomPlausiblyAndSubdividesAtShadows) {
  auto scene = Scene::builtin("cornell");
  ASSERT_TRUE(scene);
  auto mesh = build_mesh(*scene, {100.0f, 50.0f});
  ASSERT_TRUE(mesh);
  SolverSettings settings;
  settings.subdivide = 0.15f;
  settings.max_iterations = 40;
  const SceneVisibility vis(*mesh);
  const auto result = solve_serial(*mesh, settings, std::cref(vis));
  uint64_t split = 0;
  for (const auto& it : result.iterations) split += it.elements_split;
  EXPECT_GT(split, 0u);
  // Reflected light: the red wall is red, the green wall green, the ceiling lit only indirectly.
  RGB red_wall, green_wall;
  for (const auto& e : result.elements) {
    if (!e.leaf) continue;
    const Vec3 c = e.polygon.centroid(), n = e.polygon.normal();
    if (n.x < -0.9f && c.x > 540) red_wall += e.radiosity;
    if (n.x > 0.9f && c.x < 10) green_wall += e.radiosity;
  }
  EXPECT_GT(red_wall.x, 3 * red_wall.y);
  EXPECT_GT(green_wall.y, 2 * green_wall.x);
  const RadiosityField field = vertex_field(*mesh, result.elements);
  EXPECT_FALSE(field.triangles.empty());
  auto back = RadiosityField::from_bytes(field.to_bytes());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->position.size(), field.position.size());
  EXPECT_FALSE(RadiosityField::from_bytes(field.to_bytes().substr(0, 40)));
}

}  // namespace
}  // namespace lf::radiosity

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "radiosity/ply.hpp"

namespace lf::radiosity {
namespace {

// Two writers of the same PLY at once (two farms in one folder): each writes under a name of its own and the
// last rename wins, so the file is always one whole solution, never a mix, and no temporary file is left.
TEST(Ply, ConcurrentWritersNeverCorruptEachOther) {
  auto field = [](size_t triangles) {
    RadiosityField f;
    for (size_t t = 0; t < triangles; ++t) {
      const uint32_t base = static_cast<uint32_t>(f.position.size());
      for (int c = 0; c < 3; ++c) {
        f.position.push_back({float(t), float(c), 0});
        f.radiosity.push_back({1, 1, 1});
        f.emission.push_back({0, 0, 0});
      }
      f.triangles.push_back({base, base + 1, base + 2});
    }
    return f;
  };
  const RadiosityField small = field(10), large = field(5000);
  const auto dir = std::filesystem::temp_directory_path() / ("lightfarm-ply-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "room.ply").string();
  std::thread a([&] {
    for (int i = 0; i < 40; ++i) EXPECT_TRUE(write_ply(small, path).ok());
  });
  std::thread b([&] {
    for (int i = 0; i < 40; ++i) EXPECT_TRUE(write_ply(large, path).ok());
  });
  a.join();
  b.join();
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const std::string bytes = text.str();
  const size_t header_end = bytes.find("end_header\n") + 11;
  const bool is_small = bytes.find("element vertex 30\n") != std::string::npos;
  const size_t vertices = is_small ? 30 : 15000, faces = is_small ? 10 : 5000;
  EXPECT_EQ(bytes.size(), header_end + vertices * 27 + faces * 13);  // 6 floats + 3 bytes; 1 + 3 u32
  size_t files = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir)) files += f.is_regular_file();
  EXPECT_EQ(files, 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace lf::radiosity
