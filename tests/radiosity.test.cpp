// Radiosity rings as real processes: every layout gives the serial solver's answer, the `radiosity` LightOp shows
// the analytic furnace, bad settings are clear errors, and lost ring nodes are restarted without changing the answer.
#include <gtest/gtest.h>

#include <signal.h>

#include <cstring>
#include <map>
#include <tuple>

#include "radiosity/config.hpp"
#include "radiosity/ply.hpp"
#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

struct Ply {
  std::vector<Vec3> position;
  std::vector<RGB> radiosity;
  size_t faces = 0;
};

// Reads what radiosity::write_ply writes.
Ply read_ply(const std::string& path) {
  Ply ply;
  const std::string bytes = read_file(path);
  const size_t end = bytes.find("end_header\n");
  if (end == std::string::npos) return ply;
  size_t vertices = 0;
  std::sscanf(bytes.c_str() + bytes.find("element vertex"), "element vertex %zu", &vertices);
  std::sscanf(bytes.c_str() + bytes.find("element face"), "element face %zu", &ply.faces);
  const char* at = bytes.data() + end + std::strlen("end_header\n");
  for (size_t i = 0; i < vertices; ++i, at += 27) {
    float f[6];
    std::memcpy(f, at, sizeof f);
    ply.position.push_back({f[0], f[1], f[2]});
    ply.radiosity.push_back({f[3], f[4], f[5]});
  }
  return ply;
}

// The numbers of the "shooters" array in the stats JSON.
std::vector<uint32_t> shooters_in(const std::string& json) {
  std::vector<uint32_t> out;
  size_t at = json.find("\"shooters\"");
  if (at == std::string::npos) return out;
  at = json.find('[', at);
  const size_t end = json.find(']', at);
  for (size_t i = at + 1; i < end;) {
    while (i < end && !std::isdigit(static_cast<unsigned char>(json[i]))) ++i;
    if (i >= end) break;
    out.push_back(static_cast<uint32_t>(std::strtoul(json.c_str() + i, nullptr, 10)));
    while (i < end && std::isdigit(static_cast<unsigned char>(json[i]))) ++i;
  }
  return out;
}

class RadiosityFarm : public FarmFixture {};

constexpr const char* kRingScript = R"(
scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1 }
local ring = radiosity { rings = param("rings", 1), ring_length = param("length", 1), balance = param("balance", "none"),
                         patch_size = 110, element_size = 55, subdivide = 0.15, max_iterations = 20,
                         samples_per_packet = 8, ply = param("ply", "out.ply") }
renderers { lighting = ring }
)";

// The ring in each layout, with and without load balancing, against the serial solver on the same mesh: the same
// shooters one after another and the same radiosity at every vertex (1e-4 relative).
TEST_F(RadiosityFarm, EveryLayoutGivesTheSerialSolversAnswer) {
  const std::string script = write("ring.lua", kRingScript);
  struct Case {
    int rings, length;
    const char* balance;
  };
  for (const Case c : {Case{1, 1, "none"}, Case{1, 3, "none"}, Case{1, 3, "static"}, Case{2, 2, "none"},
                       Case{2, 2, "static+dynamic"}}) {
    const std::string name = std::to_string(c.rings) + "x" + std::to_string(c.length) + "-" + c.balance;
    const std::string ply = path(name + ".ply"), stats = path(name + ".json");
    auto r = run_lightfarm({"run", script, "--output", path(name + ".png"), "--stats-json", stats, "--set",
                            "rings=" + std::to_string(c.rings), "--set", "length=" + std::to_string(c.length), "--set",
                            std::string("balance=") + c.balance, "--set", "ply=" + ply});
    ASSERT_EQ(r.status, 0) << name << "\n" << r.err;
    expect_no_leftovers(r);

    Value::Map params{{"rings", c.rings}, {"ring_length", c.length}, {"balance", c.balance}, {"patch_size", 110.0},
                      {"element_size", 55.0}, {"subdivide", 0.15}, {"max_iterations", 20}, {"samples_per_packet", 8}};
    const auto config = radiosity::read_ring_config(ParamTable(params, "test"));
    auto scene = Scene::builtin("cornell");
    ASSERT_TRUE(scene);
    auto plan = radiosity::plan_ring(*scene, config);
    ASSERT_TRUE(plan);
    const radiosity::SceneVisibility vis(plan->mesh);
    const auto serial = radiosity::solve_serial(plan->mesh, config.solver, std::cref(vis));
    std::vector<uint32_t> expected_shooters;
    for (const auto& it : serial.iterations) expected_shooters.push_back(it.shooter);
    EXPECT_EQ(shooters_in(read_file(stats)), expected_shooters) << name;

    std::vector<radiosity::Element> leaves;
    for (const auto& e : serial.elements)
      if (e.leaf) leaves.push_back(e);
    radiosity::add_ambient(plan->mesh, leaves);
    const RadiosityField expected = radiosity::vertex_field(plan->mesh, leaves);
    const Ply got = read_ply(ply);
    ASSERT_EQ(got.position.size(), expected.position.size()) << name;
    EXPECT_EQ(got.faces, expected.triangles.size()) << name;
    // Vertices come out in element order, which differs between layouts: match them by surface position.
    std::map<std::tuple<float, float, float, float, float, float>, RGB> want;
    for (size_t i = 0; i < expected.position.size(); ++i) {
      const Vec3 p = expected.position[i];
      want[{p.x, p.y, p.z, expected.radiosity[i].x, expected.radiosity[i].y, expected.radiosity[i].z}] = expected.radiosity[i];
    }
    size_t matched = 0;
    double worst = 0;
    for (size_t i = 0; i < got.position.size(); ++i) {
      const Vec3 p = got.position[i];
      // Nearest expected vertex at this position (positions repeat across surfaces that meet at an edge).
      double best = INFINITY;
      for (auto it = want.lower_bound({p.x, p.y, p.z, -INFINITY, -INFINITY, -INFINITY});
           it != want.end() && std::get<0>(it->first) == p.x && std::get<1>(it->first) == p.y && std::get<2>(it->first) == p.z; ++it) {
        double d = 0;
        for (int k = 0; k < 3; ++k)
          d = std::max(d, std::abs(static_cast<double>(got.radiosity[i][k] - it->second[k])) / std::max(1.0, static_cast<double>(it->second[k])));
        best = std::min(best, d);
      }
      if (best <= 1e-4) ++matched;
      worst = std::max(worst, best);
    }
    EXPECT_EQ(matched, got.position.size()) << name << ": worst relative difference " << worst;
  }
}

// A closed box that emits E = pi Ke and reflects rho, as an OBJ: through the `radiosity` LightOp every pixel
// shows Ke (seen directly) + Ke rho / (1 - rho) (its reflected radiosity / pi) = Ke / (1 - rho).
TEST_F(RadiosityFarm, RadiosityLightOpShowsTheFurnace) {
  write("box.mtl", "newmtl furnace\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  write("box.obj",
        "mtllib box.mtl\nusemtl furnace\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 4 3 7 8\nf 1 4 8 5\nf 2 6 7 3\n");
  const std::string script = write("furnace.lua", R"(
scene { file = "box.obj" }
camera { eye = {0.5, 0.5, 0.1}, at = {0.5, 0.5, 1}, fov = 60 }
image { width = 24, height = 24, spp = 1 }
renderers { lighting = radiosity { rings = 1, ring_length = 2, patch_size = 0.5, element_size = 0.25, converge = 0.0005 } }
)");
  auto r = run_lightfarm({"run", script, "--output", path("furnace.exr")});
  ASSERT_EQ(r.status, 0) << r.err;
  expect_no_leftovers(r);
  auto img = read_image(path("furnace.exr"));
  ASSERT_TRUE(img.ok());
  for (const RGB& p : img->pixels) ASSERT_NEAR(average(p), 2.0, 0.02);
}

// A job of frames over a ring: the ring solves once, in the farm's setup, and its solution serves every frame (its
// nodes and the op that fetches it answer each frame's PHASE setup at once); each frame equals a farm of that frame
// alone, bit for bit.
TEST_F(RadiosityFarm, AJobSolvesOnceAndEveryFrameIsItsOwnFarms) {
  const std::string script = write("ring_job.lua", R"(
scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1, output = param("out", "r.####.exr") }
local function view(f) return { eye = {238 + 40 * f, 273, -800}, at = {278, 273, 0} } end
if param("frame", 0) > 0 then camera(view(param("frame", 0))) else frames { first = 1, last = 3, camera = view } end
renderers { lighting = radiosity { rings = 1, ring_length = 2, patch_size = 110, element_size = 55, subdivide = 0.15,
                                   max_iterations = 20, samples_per_packet = 8 } }
)");
  auto job = run_lightfarm({"run", script, "--set", "out=" + path("r.####.exr"), "--checkpoint-every", "0"});
  ASSERT_EQ(job.status, 0) << job.err;
  expect_no_leftovers(job);
  EXPECT_NE(job.err.find("frames 3, setups 1"), std::string::npos) << job.err;
  EXPECT_EQ(job.err.find("ring node"), std::string::npos) << "no node was lost or restarted: " << job.err;
  auto single = run_lightfarm({"run", script, "--set", "frame=3", "--set", "out=" + path("single.exr")});
  ASSERT_EQ(single.status, 0) << single.err;
  auto a = read_image(path("r.0003.exr")), b = read_image(path("single.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->pixels == b->pixels) << "frame 3 differs from a farm of frame 3 alone";
}

// Composed with the lighting network as a final gather, irradiance { input = radiosity } + direct, the solution
// lights the Cornell box like the path tracer does: mean radiance within 6 % (measured 3 % at 48x48 with 60
// shooters, 0.997 at 32x32), light pixels left out.
TEST_F(RadiosityFarm, FinalGatherOnTheSolutionAgreesWithThePathTracer) {
  const std::string reference = write("pt.lua", R"(
scene { builtin = "cornell" }
image { width = 32, height = 32, spp = 256 }
renderers { count = 2, lighting = lightop "pathtrace" {} }
)");
  const std::string network = write("gather.lua", R"(
scene { builtin = "cornell" }
image { width = 32, height = 32, spp = 2 }
local solution = radiosity { rings = 1, ring_length = 2, patch_size = 110, element_size = 55, max_iterations = 60 }
renderers { lighting = lightop "combine" { inputs = { lightop "direct" {}, lightop "irradiance" { input = solution } } } }
)");
  auto a = run_lightfarm({"run", reference, "--output", path("pt.exr")});
  auto b = run_lightfarm({"run", network, "--output", path("gather.exr")});
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  expect_no_leftovers(b);
  auto ref = read_image(path("pt.exr"));
  auto got = read_image(path("gather.exr"));
  ASSERT_TRUE(ref.ok() && got.ok());
  double sum_ref = 0, sum_got = 0;
  for (size_t i = 0; i < ref->pixels.size(); ++i) {
    if (average(ref->pixels[i]) > 1.0f || average(got->pixels[i]) > 1.0f) continue;  // the light
    sum_ref += average(ref->pixels[i]);
    sum_got += average(got->pixels[i]);
  }
  EXPECT_NEAR(sum_got / sum_ref, 1.0, 0.06);
  std::printf("final gather / path tracer mean: %.4f\n", sum_got / sum_ref);
}

TEST_F(RadiosityFarm, BadSettingsAndUnwritablePlyAreClearErrors) {
  const std::string script = write("ring.lua", kRingScript);
  auto r = run_lightfarm({"run", script, "--output", path("x.png"), "--set", "ply=/nonexistent/dir/out.ply"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("radiosity: cannot write '/nonexistent/dir/out.ply'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("x.png")));
  expect_no_leftovers(r);

  const std::string bad = write("bad.lua", "scene { builtin = \"cornell\" }\n"
                                           "renderers { lighting = radiosity { rings = 2, shooter_samples = 10 } }\n");
  r = run_lightfarm({"run", bad, "--output", path("y.png")});
  EXPECT_EQ(r.status, 2);  // a script error, as for every other bad script
  EXPECT_NE(r.err.find("bad.lua:2: radiosity: shooter_samples must be a square number"), std::string::npos) << r.err;
  expect_no_leftovers(r);
}

// A ring node's elements exist nowhere else: one that dies mid-solve is restarted and the ring goes back to its
// last checkpoint (or, with none, to the start), and repeats what was lost exactly: the PLY and the image are the
// fault-free ones, byte for byte. Two nodes killed at once, and no checkpoints, likewise.
TEST_F(RadiosityFarm, RingNodesKilledMidSolveAreRestartedAndTheSolutionIsTheFaultFreeOne) {
  const std::string script = write("ring.lua", R"(
scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1 }
renderers { lighting = radiosity { rings = 2, ring_length = 2, patch_size = 60, converge = 0, max_iterations = 40,
                                   checkpoint_every = param("every", 2), ply = param("ply", "out.ply") } }
)");
  auto reference = run_lightfarm({"run", script, "--output", path("ref.png"), "--set", "ply=" + path("ref.ply")});
  ASSERT_EQ(reference.status, 0) << reference.err;
  EXPECT_NE(reference.err.find("iteration 40, unshot energy"), std::string::npos) << reference.err;

  struct Case {
    std::string name, every;
    std::vector<std::string> victims;
    std::string resumed;
  };
  for (const Case& c : {Case{"checkpoint", "2", {"radiosity.1.0"}, "goes back to its checkpoint after iteration"},
                        Case{"scratch", "0", {"radiosity.0.0", "radiosity.1.1"}, "starts the solve again"}}) {
    SCOPED_TRACE(c.name);
    const std::string ply = path(c.name + ".ply"), png = path(c.name + ".png"), stats = path(c.name + ".json");
    Farm farm({"run", script, "--output", png, "--set", "ply=" + ply, "--set", "every=" + c.every, "--stats-json", stats});
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("iteration 3,") != std::string::npos; }, 60))
        << farm.err_so_far();
    for (const auto& victim : c.victims) {
      auto pids = actor_pids(farm.tag(), victim);
      ASSERT_EQ(pids.size(), 1u) << victim;
      ::kill(pids[0], SIGKILL);
    }
    auto r = farm.wait(120);
    ASSERT_EQ(r.status, 0) << r.err;
    for (const auto& victim : c.victims)
      EXPECT_NE(r.err.find("ring node '" + victim + "' was killed by signal 9 (Killed); restarting it (1 of at most 3)"),
                std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.resumed), std::string::npos) << r.err;
    EXPECT_EQ(read_file(ply), read_file(path("ref.ply")));
    EXPECT_EQ(read_file(png), read_file(path("ref.png")));
    const std::string json = read_file(stats);
    size_t recoveries = 0;
    for (size_t at = json.find("\"lost_at_iteration\""); at != std::string::npos; at = json.find("\"lost_at_iteration\"", at + 1))
      ++recoveries;
    EXPECT_EQ(recoveries, c.victims.size()) << json;
    expect_no_leftovers(r);
  }
}

}  // namespace
}  // namespace lf::test
