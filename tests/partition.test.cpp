// A partitioned scene (issue 14): partition { parts = N } puts the scene's parts in N geometry actors, and `direct`
// and `pathtrace` trace their rays through them. The image is the unpartitioned farm's, bit for bit, on the Cornell
// box and on Lost Empire; a geometry actor killed mid-frame is a clear error, and nothing is left running.
#include <gtest/gtest.h>

#include <csignal>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;

class PartitionTest : public FarmFixture {
 protected:
  Image render(std::vector<std::string> args, const std::string& out, std::string* err = nullptr) {
    args.insert(args.end(), {"--output", path(out)});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << r.err;
    expect_no_leftovers(r);
    if (err) *err = r.err;
    auto img = read_image(path(out));
    EXPECT_TRUE(img.ok()) << r.err;
    return img.ok() ? *img : Image();
  }
  static double brightness(const Image& img) {
    double sum = 0;
    for (const RGB& p : img.pixels) sum += average(p);
    return sum;
  }
};

TEST_F(PartitionTest, TheCornellBoxIsTheSameWhetherItsSceneIsSplitOrNot) {
  const std::string script = write("cornell.lua", R"(scene { builtin = "cornell" }
image { width = 48, height = 48, spp = 4, tile = 16 }
if param("parts", 0) > 0 then partition { parts = param("parts", 0) } end
local op = param("op", "direct") == "direct" and lightop "direct" { light_samples = 2 }
                                              or lightop "pathtrace" { max_depth = 5 }
renderers { count = 2, lighting = op }
)");
  for (const char* op : {"direct", "pathtrace"}) {
    SCOPED_TRACE(op);
    const std::string set_op = std::string("op=") + op;
    const Image whole = render({"run", script, "--set", set_op}, std::string(op) + "-whole.exr");
    ASSERT_GT(brightness(whole), 0) << "a black image proves nothing";
    for (int parts : {2, 3, 5}) {
      std::string err;
      const Image split = render({"run", script, "--set", set_op, "--set", "parts=" + std::to_string(parts)},
                                 std::string(op) + "-" + std::to_string(parts) + ".exr", &err);
      EXPECT_TRUE(split.pixels == whole.pixels) << parts << " parts";
      // The rays did travel: every part answered trace requests, and the op says how many it sent.
      for (int p = 0; p < parts; ++p)
        EXPECT_NE(err.find("geometry." + std::to_string(p) + "     rays "), std::string::npos) << err;
      EXPECT_NE(err.find("trace_requests "), std::string::npos) << err;
    }
  }
}

// partition { colocate = true }: each replica of a `pathtrace` pool holds a part itself and is sent the points that
// lie in it, so its rays that stay in the part are traced in its own process. The pixels are the whole farm's (a
// pixel whose samples lie in two parts is answered in two replies and still summed in sample order), the replicas
// say they traced part visits at home, and the geometry actors are asked about fewer rays than without.
TEST_F(PartitionTest, ReplicasThatHoldTheirPartGiveTheSamePixelsAndSendFewerRays) {
  const std::string script = write("colocate.lua", R"(scene { builtin = "cornell" }
image { width = 48, height = 48, spp = 4, tile = 16 }
if param("parts", 0) > 0 then partition { parts = param("parts", 0), colocate = param("colocate", false) } end
local op = lightop "pathtrace" { max_depth = 5 }
renderers { count = 2, lighting = multiplexer { op, replicas = param("replicas", 3) } }
)");
  const Image whole = render({"run", script}, "whole.exr");
  ASSERT_GT(brightness(whole), 0);
  // Rays the geometry actors traced, summed from the run's figures ("geometry.N  rays R").
  const auto rays_at_parts = [&](const std::string& stats, int parts) {
    int64_t sum = 0;
    for (int p = 0; p < parts; ++p) {
      const std::string key = "\"name\": \"geometry." + std::to_string(p) + "\"";
      const auto named = stats.find(key);
      const auto from = stats.rfind("\"rays\": ", named);
      if (named == std::string::npos || from == std::string::npos) return int64_t{-1};
      sum += std::stoll(stats.substr(from + 8));
    }
    return sum;
  };
  for (int parts : {2, 3}) {
    SCOPED_TRACE(std::to_string(parts) + " parts");
    const std::string set_parts = "parts=" + std::to_string(parts);
    auto apart = run_lightfarm({"run", script, "--set", set_parts, "--quiet", "--output", path("apart.exr"),
                                "--stats-json", path("apart.json")});
    ASSERT_EQ(apart.status, 0) << apart.err;
    auto home = run_lightfarm({"run", script, "--set", set_parts, "--set", "colocate=true", "--quiet", "--output",
                               path("home.exr"), "--stats-json", path("home.json")});
    ASSERT_EQ(home.status, 0) << home.err;
    expect_no_leftovers(home);
    const auto home_image = read_image(path("home.exr"));
    ASSERT_TRUE(home_image.ok());
    EXPECT_TRUE(home_image->pixels == whole.pixels);
    const std::string home_stats = read_file(path("home.json")), apart_stats = read_file(path("apart.json"));
    EXPECT_EQ(apart_stats.find("\"local_part_visits\": 0,") != std::string::npos, true) << apart_stats;
    const auto local = home_stats.find("\"local_part_visits\": ");
    ASSERT_NE(local, std::string::npos) << home_stats;
    EXPECT_GT(std::stoll(home_stats.substr(local + 21)), 1000) << home_stats;
    const int64_t sent_apart = rays_at_parts(apart_stats, parts), sent_home = rays_at_parts(home_stats, parts);
    ASSERT_GT(sent_home, 0) << home_stats;
    EXPECT_LT(sent_home, sent_apart) << home_stats;
  }
}

// A replica that holds a part is a replica like any other: killed mid-frame, its packets go to the others, which
// trace its part through the geometry actor, and the pixels are still the whole farm's.
TEST_F(PartitionTest, AReplicaThatHoldsAPartKilledMidFrameLosesNothing) {
  const std::string script = write("home-kill.lua", R"(scene { builtin = "cornell" }
image { width = 64, height = 64, spp = 96, tile = 16 }
if param("parts", 0) > 0 then partition { parts = param("parts", 0), colocate = true } end
renderers { count = 2, lighting = multiplexer { lightop "pathtrace" { max_depth = 5 }, replicas = 3 } }
)");
  const Image whole = render({"run", script}, "whole.exr");
  ASSERT_GT(brightness(whole), 0);
  Farm farm({"run", script, "--set", "parts=3", "--output", path("killed.exr")});
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60))
      << farm.err_so_far();
  const auto victims = actor_pids(farm.tag(), "pathtrace.1");
  ASSERT_EQ(victims.size(), 1u);
  ::kill(victims[0], SIGKILL);
  auto r = farm.wait(120);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("replica 'pathtrace.1' of 'pathtrace' is gone"), std::string::npos) << r.err;
  expect_no_leftovers(r);
  const auto killed = read_image(path("killed.exr"));
  ASSERT_TRUE(killed.ok());
  EXPECT_TRUE(killed->pixels == whole.pixels);
}

// The directional cache (Jansen & Reinhard, §3) is filled in setup and frozen, so it does not depend on the layout
// either: a split scene and one renderer or two give the same pixels, and the op reports how often the cache answered.
TEST_F(PartitionTest, TheDirectionalCacheGivesTheSamePixelsOnEveryLayout) {
  const std::string script = write("cache.lua", R"(scene { builtin = "cornell" }
image { width = 48, height = 48, spp = 4, tile = 16 }
if param("parts", 0) > 0 then partition { parts = param("parts", 0) } end
renderers { count = param("renderers", 2), lighting = lightop "pathtrace" {
  max_depth = 5, directional_cache = true, cache_cells = 4, cache_fill_spp = 64 } }
)");
  std::string err;
  const Image whole = render({"run", script}, "whole.exr", &err);
  ASSERT_GT(brightness(whole), 0);
  const auto at = err.find("cache_hit_ratio ");
  ASSERT_NE(at, std::string::npos) << err;
  EXPECT_GT(std::stod(err.substr(at + 16)), 0.3) << err;
  const Image split = render({"run", script, "--set", "parts=3"}, "split.exr");
  const Image one = render({"run", script, "--set", "renderers=1"}, "one.exr");
  EXPECT_TRUE(split.pixels == whole.pixels) << "split into 3 parts";
  EXPECT_TRUE(one.pixels == whole.pixels) << "one renderer";
}

// Data locality: in a partitioned farm a renderer, and an op that traces only through the parts, build no BVH of the
// whole scene (without a host agent sharing one), and say so in their figures; `irradiance`, which traces its own
// rays, keeps one.
TEST_F(PartitionTest, AnOpThatTracesThroughThePartsHoldsNoBvhOfItsOwn) {
  const std::string script = write("nobvh.lua", R"(scene { builtin = "cornell" }
image { width = 32, height = 32, spp = 2, tile = 16, edge_spp = 0 }  -- rays to count: no outline's extra samples
farm { host_agents = false }
partition { parts = 2 }
local direct = lightop "direct" {}
renderers { count = 1, lighting = lightop "combine" { inputs = { direct, lightop "irradiance" { input = direct } } } }
)");
  auto r = run_lightfarm({"run", script, "--quiet", "--output", path("nobvh.exr"), "--stats-json", path("stats.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  expect_no_leftovers(r);
  const std::string stats = read_file(path("stats.json"));
  // An actor's figures: its object's keys are sorted, so its "detail" comes before its "name".
  const auto at = [&](const std::string& name) {
    const auto named = stats.find("\"name\": \"" + name + "\"");
    if (named == std::string::npos) return std::string();
    const auto from = stats.rfind("\"busy_seconds\"", named);
    return stats.substr(from, named - from);
  };
  EXPECT_NE(at("direct").find("\"whole_scene_bvh\": false"), std::string::npos) << stats;
  EXPECT_NE(at("irradiance").find("\"whole_scene_bvh\": true"), std::string::npos) << stats;
  // The renderer's camera rays went to the parts too: 32 x 32 pixels x 2 samples, and one for each sample adaptive
  // sampling added in the tiles' second rounds.
  const std::string renderer = at("renderer-0");
  EXPECT_NE(renderer.find("\"whole_scene_bvh\": false"), std::string::npos) << stats;
  const auto figure = [&](const std::string& name) {
    const auto from = renderer.find("\"" + name + "\": ");
    return from == std::string::npos ? -1 : std::stol(renderer.substr(from + name.size() + 4));
  };
  const long added = figure("adaptive_samples");
  EXPECT_GT(added, 0) << "no second round: nothing was traced through the parts for it\n" << stats;
  EXPECT_EQ(figure("traced_rays"), 2048 + added) << stats;
}

// A real interior with thin double-sided blocks (coplanar back-to-back faces, which the tie rule settles) and a
// three-bounce path tracer: the split farm's pixels are the whole farm's, at 2, 3 and 5 parts and with replicas
// that hold their parts.
TEST_F(PartitionTest, LostEmpireIsTheSameWhetherItsSceneIsSplitOrNot) {
  const std::string obj = kSource + "/../shared/scenes/lost_empire/lost_empire.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << "no " << obj;
  const std::string script = write("empire.lua", "scene { file = \"" + obj + R"(" }
material "Torch" { emission = {9, 9, 6} }
camera { eye = {-8, 16, 20}, at = {6, 12, 0}, fov = 70 }
image { width = 64, height = 48, spp = 2, tile = 16 }
if param("parts", 0) > 0 then partition { parts = param("parts", 0), colocate = param("colocate", false) } end
local op = lightop "pathtrace" { max_depth = 3 }
renderers { count = 2, lighting = param("colocate", false) and multiplexer { op, replicas = 3 } or op }
)");
  const Image whole = render({"run", script}, "whole.exr");
  ASSERT_GT(brightness(whole), 0);
  for (int parts : {2, 3, 5}) {
    const Image split = render({"run", script, "--set", "parts=" + std::to_string(parts)},
                               "split-" + std::to_string(parts) + ".exr");
    EXPECT_TRUE(split.pixels == whole.pixels) << parts << " parts";
  }
  // Replicas that hold their parts (a pool of 3 over 3 parts) shade where they trace, with the same pixels.
  const Image home = render({"run", script, "--set", "parts=3", "--set", "colocate=true"}, "home.exr");
  EXPECT_TRUE(home.pixels == whole.pixels) << "replicas holding their parts";
}

// A part is held by one process only: losing it mid-frame stops the farm with a message that says so, writes no
// image, and leaves nothing running.
TEST_F(PartitionTest, AGeometryActorKilledMidFrameIsAClearError) {
  const std::string script = write("slow.lua", R"(scene { builtin = "cornell" }
image { width = 128, height = 128, spp = 256, tile = 16 }
partition { parts = 3 }
renderers { count = 2, lighting = lightop "pathtrace" { max_depth = 8 } }
)");
  Farm farm({"run", script, "--output", path("killed.exr")});
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60))
      << farm.err_so_far();
  const auto victims = actor_pids(farm.tag(), "geometry.1");
  ASSERT_EQ(victims.size(), 1u);
  ::kill(victims[0], SIGKILL);
  auto r = farm.wait(60);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("actor 'geometry.1' (pid " + std::to_string(victims[0]) + ") was killed by signal 9"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("the part of the scene it held is not held anywhere else"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("killed.exr")));
  expect_no_leftovers(r);
}

// Bad scripts say what is wrong, with file and line.
TEST_F(PartitionTest, ABadPartitionIsAScriptError) {
  const std::string twice = write("twice.lua", R"(scene { builtin = "cornell" }
partition { parts = 2 }
partition { parts = 3 }
renderers { lighting = lightop "direct" {} }
)");
  auto r = run_lightfarm({"graph", twice});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("twice.lua:3: partition is declared twice"), std::string::npos) << r.err;
  const std::string zero = write("zero.lua", R"(scene { builtin = "cornell" }
partition { parts = 0 }
renderers { lighting = lightop "direct" {} }
)");
  r = run_lightfarm({"graph", zero});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("zero.lua:2:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("parts"), std::string::npos) << r.err;
  // More parts than triangles: found when the director splits the scene, before anything starts.
  const std::string many = write("many.lua", R"(scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1 }
partition { parts = 64 }
renderers { lighting = lightop "direct" {} }
)");
  r = run_lightfarm({"run", many, "--output", path("many.exr")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("many.lua:3: partition: the scene has "), std::string::npos) << r.err;
  expect_no_leftovers(r);
  // The graph shows the parts.
  const std::string ok = write("ok.lua", R"(scene { builtin = "cornell" }
partition { parts = 2 }
renderers { lighting = lightop "direct" {} }
)");
  r = run_lightfarm({"graph", ok});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"geometry.1\" [label=\"geometry.1\\n(geometry)\", shape=cylinder]"), std::string::npos) << r.out;
  // And whose rays they answer: the renderers' and the op's.
  EXPECT_NE(r.out.find("\"geometry.1\" -> \"renderers\" [style=dotted, label=\"rays\"];"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"geometry.0\" -> \"direct\" [style=dotted, label=\"rays\"];"), std::string::npos) << r.out;
  // With colocate, which part each replica holds (replica j: part j mod 2).
  const std::string home = write("home.lua", R"(scene { builtin = "cornell" }
partition { parts = 2, colocate = true }
renderers { lighting = multiplexer { lightop "direct" {}, replicas = 3 } }
)");
  r = run_lightfarm({"graph", home});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("[label=\"direct.1\\n(direct, holds part 1)\"]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[label=\"direct.2\\n(direct, holds part 0)\"]"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace lf::test
