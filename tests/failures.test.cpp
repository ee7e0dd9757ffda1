// Pools, packets and failures (issue 4): multiplexed networks render the same pixels as plain ones, and a frame
// survives a renderer or replica killed or stopped in the middle of it — with the fault-free image, bit for bit.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <sstream>
#include <thread>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kCornell = kSource + "/examples/cornell.lua";
const std::string kPool = kSource + "/examples/cornell_pool.lua";
const std::string kSlowPool = kSource + "/tests/scripts/slow_pool.lua";
const std::string kNested = kSource + "/tests/scripts/nested_pool.lua";
const std::string kSubset = kSource + "/tests/scripts/subset_pool.lua";

class FailureTest : public FarmFixture {
 protected:

  // Runs to completion and returns the image (fails the test if the run failed or left processes).
  Image render(const std::vector<std::string>& args, const std::string& out) {
    std::vector<std::string> all = args;
    all.insert(all.end(), {"--output", path(out)});
    auto r = run_lightfarm(all);
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
    auto img = read_image(path(out));
    EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.error().message);
    return img.ok() ? *img : Image();
  }

  // Starts `args`, waits until a quarter of the frame is done, applies `fault` to the actor named `victim`, and
  // returns the finished run.
  RunResult render_with_fault(std::vector<std::string> args, const std::string& out, const std::string& victim,
                              int signal) {
    args.insert(args.end(), {"--output", path(out)});
    Farm farm(args);
    EXPECT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 20%") != std::string::npos; }, 60))
        << farm.err_so_far();
    auto pids = actor_pids(farm.tag(), victim);
    EXPECT_EQ(farm.err_so_far().find("render 100%"), std::string::npos) << "the frame ended before the fault";
    EXPECT_EQ(pids.size(), 1u) << "no actor named " << victim;
    if (!pids.empty()) ::kill(pids[0], signal);
    auto r = farm.wait(120);
    EXPECT_TRUE(wait_no_leftovers(r.tag).empty()) << "processes left behind";
    return r;
  }

  // Starts `args`, kills the actor named `victim` with SIGKILL once the farm's log shows `progress` (a fixed delay
  // after start landed in start-up on a loaded machine), and waits for the run into `r`.
  void kill_once_reported(const std::vector<std::string>& args, const std::string& progress, const std::string& victim,
                          RunResult& r) {
    Farm farm(args);
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find(progress) != std::string::npos; }, 60))
        << farm.err_so_far();
    auto pids = actor_pids(farm.tag(), victim);
    ASSERT_EQ(pids.size(), 1u);
    ::kill(pids[0], SIGKILL);
    r = farm.wait(60);
  }
};

std::vector<std::string> small(const std::string& script, std::vector<std::string> sets) {
  std::vector<std::string> args{"run", script};
  for (auto& s : sets) args.insert(args.end(), {"--set", s});
  return args;
}

TEST_F(FailureTest, MultiplexedNetworksRenderThePlainNetworksPixels) {
  const std::vector<std::string> common{"width=64", "height=64", "spp=4", "tile=16"};
  auto sets = [&](std::vector<std::string> extra) {
    extra.insert(extra.end(), common.begin(), common.end());
    return extra;
  };
  Image plain = render(small(kCornell, sets({})), "plain.exr");
  for (const char* dispatch : {"clients", "process"})
    for (const char* strategy : {"least_loaded", "round_robin", "random"}) {
      SCOPED_TRACE(std::string(dispatch) + " " + strategy);
      const std::string stats = path(std::string("pool-") + dispatch + "-" + strategy + ".json");
      auto args = small(kPool, sets({std::string("strategy=") + strategy, "replicas=3", "split=300",
                                     std::string("dispatch=") + dispatch}));
      args.insert(args.end(), {"--stats-json", stats});
      Image pooled = render(args, std::string("pool-") + dispatch + "-" + strategy + ".exr");
      EXPECT_TRUE(pooled.pixels == plain.pixels);
      // Dispatched by its clients, the pool is no process; otherwise its multiplexer is one, with a pid.
      // (Keys are written in order: the flag comes before the name, a pid after it.)
      const std::string json = read_file(stats);
      const size_t name = json.find("\"name\": \"direct\"");
      ASSERT_NE(name, std::string::npos) << json;
      const size_t open = json.rfind('{', name);
      const std::string entry = json.substr(open, json.find('}', name) - open);
      const bool clients = std::string(dispatch) == "clients";
      EXPECT_EQ(entry.find("\"dispatched_by_clients\": true") != std::string::npos, clients) << entry;
      EXPECT_EQ(entry.find("\"pid\"") == std::string::npos, clients) << entry;
    }
  Image nested = render({"run", kNested}, "nested.exr");
  EXPECT_TRUE(nested.pixels == plain.pixels) << "pool of pools";
  Image sync = render(small(kCornell, {"width=16", "height=16", "spp=2", "tile=16", "mode=sync"}), "sync.exr");
  Image async = render(small(kCornell, {"width=16", "height=16", "spp=2", "tile=16"}), "async.exr");
  EXPECT_TRUE(sync.pixels == async.pixels) << "sync mode";
}

TEST_F(FailureTest, PooledPhotonMapsShareTheirSharesReplicaToReplica) {
  // Each replica shoots a third of the photons and sends its share to the other two (pool_part): every replica
  // builds the map of all three shares, the one map a single replica would build.
  const std::string glass = kSource + "/examples/cornell_glass.lua";
  auto sets = [](const char* replicas) {
    return small(kSource + "/examples/cornell_glass.lua",
                 {"width=48", "height=48", "spp=2", "photons=60000", std::string("photon_replicas=") + replicas});
  };
  Image one = render(sets("1"), "one.exr");
  Image three = render(sets("3"), "three.exr");
  EXPECT_TRUE(one.pixels == three.pixels) << "a pool of photon maps answers like one map";
}

TEST_F(FailureTest, KilledRendererReplicaOrStoppedReplicaLeaveTheImageUnchanged) {
  // spp=64 and slowed replicas: the frame lasts a couple of seconds, so faults land well inside it.
  const auto args = small(kSlowPool, {"spp=64", "slowdown=6", "renderers=2", "heartbeat_timeout=1.5"});
  Image reference = render(small(kSlowPool, {"spp=64", "renderers=1"}), "reference.exr");

  struct Case {
    const char* victim;
    int signal;
    const char* says;
  };
  for (const Case& c : {Case{"renderer-1", SIGKILL, "renderer 'renderer-1' was killed by signal 9 (Killed); its "},
                        Case{"direct.1", SIGKILL, "replica 'direct.1' was killed by signal 9 (Killed); 'direct' sends its work"},
                        Case{"direct.0", SIGSTOP, "replica 'direct.0' stopped answering (no heartbeat for 1.5 s); it was killed"}}) {
    SCOPED_TRACE(c.victim);
    auto r = render_with_fault(args, std::string(c.victim) + ".exr", c.victim, c.signal);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    auto img = read_image(path(std::string(c.victim) + ".exr"));
    ASSERT_TRUE(img.ok());
    EXPECT_TRUE(img->pixels == reference.pixels) << "the image changed after losing " << c.victim;
  }
}

// Renderers that hand in their tiles two to a message (and ask for two) render the same pixels, and a renderer
// killed while it held a finished tile not yet sent loses nothing: its tiles go to the other.
TEST_F(FailureTest, TilesInBatchesRenderTheSamePixelsAndSurviveAKilledRenderer) {
  Image reference = render(small(kSlowPool, {"spp=64", "renderers=1"}), "reference.exr");
  Image batched = render(small(kSlowPool, {"spp=64", "renderers=3", "tiles_per_message=2"}), "batched.exr");
  EXPECT_TRUE(batched.pixels == reference.pixels) << "tiles in batches changed the image";
  auto r = render_with_fault(small(kSlowPool, {"spp=64", "slowdown=6", "renderers=2", "tiles_per_message=2"}),
                             "killed.exr", "renderer-1", SIGKILL);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("renderer 'renderer-1' was killed by signal 9 (Killed); its "), std::string::npos) << r.err;
  auto img = read_image(path("killed.exr"));
  ASSERT_TRUE(img.ok());
  EXPECT_TRUE(img->pixels == reference.pixels) << "the image changed after losing a renderer holding a batch";
}

// Clients of a pool that connect to a subset of its replicas (subset = 1 of 4: renderer-0 to direct.0, renderer-1
// to direct.1) render the pixels of clients that connect to all; when direct.0 is killed mid-frame, renderer-0
// connects its next spare and the image is still the same. Only renderer-0 held direct.0, so only it says so.
TEST_F(FailureTest, ClientsOfAPoolConnectToASubsetAndASpareTakesALostReplicasPlace) {
  Image reference = render(small(kSubset, {"spp=64", "subset=0"}), "all.exr");
  auto r = render_with_fault(small(kSubset, {"spp=64", "slowdown=6"}), "subset.exr", "direct.0", SIGKILL);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("renderer-0: warning: replica 'direct.0' of 'direct' is gone"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("renderer-1: warning: replica 'direct.0'"), std::string::npos)
      << "direct.0 was a spare of renderer-1, never connected: " << r.err;
  auto img = read_image(path("subset.exr"));
  ASSERT_TRUE(img.ok());
  EXPECT_TRUE(img->pixels == reference.pixels) << "a subset, or the spare that replaced direct.0, changed the image";
}

TEST_F(FailureTest, LosingTheLastReplicaOrEveryRendererStopsTheFarmNamingIt) {
  auto one_replica = render_with_fault(
      {"run", kPool, "--set", "replicas=1", "--set", "spp=64", "--set", "light_samples=4"}, "x.png", "direct.0", SIGKILL);
  EXPECT_EQ(one_replica.status, 1);
  EXPECT_NE(one_replica.err.find("lightfarm: error: lost the last replica of 'direct': direct.0 was killed by signal 9"),
            std::string::npos)
      << one_replica.err;
  auto one_renderer = render_with_fault(small(kSlowPool, {"spp=64", "slowdown=6", "renderers=1"}), "y.exr", "renderer-0", SIGKILL);
  EXPECT_EQ(one_renderer.status, 1);
  EXPECT_NE(one_renderer.err.find("lightfarm: error: every renderer was lost: renderer-0 was killed by signal 9"),
            std::string::npos)
      << one_renderer.err;
  EXPECT_FALSE(fs::exists(path("x.png")));
  EXPECT_FALSE(fs::exists(path("y.exr")));
}

}  // namespace
}  // namespace lf::test

namespace lf::test {
namespace {

// Liveness apart from work (issue 12): one shade batch that computes for about two seconds — 4096 points, 4096
// light samples each — in a farm whose heartbeat timeout is one second. The actor's heartbeat thread keeps
// beating through it, so the farm finishes (before, the director declared the actor dead).
TEST_F(FailureTest, ALongShadeIsNotTakenForDeath) {
  const std::string script = write("long.lua", "scene { builtin = \"cornell\" }\nimage { width = 64, height = 64, spp = 1 }\n"
                                               "farm { heartbeat_timeout = 1 }\n"
                                               "renderers { count = 1, lighting = lightop \"direct\" { light_samples = 4096 } }\n");
  auto r = run_lightfarm({"run", script, "--quiet", "--output", path("long.png")});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.find("silent"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(path("long.png")));
  expect_no_leftovers(r);
}

// Nothing an actor starts outlives the farm: an exec actor leaves a child in its process group and one that
// escaped it with setsid; after the farm, neither is running (both carry the farm's tag in their environment).
TEST_F(FailureTest, WhatAnActorStartedDiesWithTheFarm) {
  const std::string script = write("forking.lua", "scene { builtin = \"cornell\" }\nimage { width = 32, height = 32, spp = 1 }\n"
                                                  "local f = lightop.exec { cmd = {\"" LIGHTFARM_SOURCE_DIR
                                                  "/tests/actors/forking_actor.sh\"}, name = \"forking\" }\n"
                                                  "renderers { count = 1, lighting = f }\n");
  for (const bool interrupt : {false, true}) {
    Farm farm({"run", script, "--quiet", "--output", path("f.png")});
    if (interrupt) {
      ASSERT_TRUE(Farm::eventually([&] { return !actor_pids(farm.tag(), "forking").empty(); }, 10.0));
      ::kill(farm.pid(), SIGTERM);
    }
    auto r = farm.wait();
    EXPECT_EQ(r.status, interrupt ? 128 + SIGTERM : 0) << r.err;
    auto left = wait_no_leftovers(r.tag);
    std::string names;
    for (pid_t p : left) names += read_file("/proc/" + std::to_string(p) + "/cmdline") + "; ";
    EXPECT_TRUE(left.empty()) << (interrupt ? "after SIGTERM: " : "") << left.size() << " left: " << names;
  }
}

// A photon-map replica lost while the pool shoots and shares its photons: its share exists nowhere else. The
// farm says so at once, without first claiming that the others take its work. 32 M photons: each replica shoots for
// several seconds, so its progress shows (a step says nothing before its first second). With 8 M, a clean-clone run
// once saw only photonmap.0 report, at 100 %, and photonmap.1 finish unseen.
TEST_F(FailureTest, APhotonReplicaLostDuringSetupIsNamedOnce) {
  RunResult r;
  ASSERT_NO_FATAL_FAILURE(kill_once_reported({"run", kSource + "/examples/cornell_glass.lua", "--set", "photons=32000000",
                                              "--set", "width=64", "--set", "height=64", "--set", "spp=1", "--output",
                                              path("glass.png")},
                                             "photonmap.1: shooting photons", "photonmap.1", r));
  EXPECT_EQ(r.status, 1) << r.err;
  std::vector<std::string> naming;  // the lines that speak of the lost replica
  std::istringstream lines(r.err);
  for (std::string line; std::getline(lines, line);)
    if (line.find("'photonmap.1'") != std::string::npos) naming.push_back(line);
  ASSERT_EQ(naming.size(), 1u) << r.err;
  EXPECT_EQ(naming[0], "lightfarm: error: replica 'photonmap.1' was killed by signal 9 (Killed) during setup; the replicas "
                       "of 'photonmap' share their setup (photonmap), so its share cannot be redone");
  EXPECT_FALSE(fs::exists(path("glass.png")));
  EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
}

// The same for a pool of `direct` learning lights: its replicas learn the cells in shares.
TEST_F(FailureTest, ALearningReplicaLostDuringSetupIsNamedOnce) {
  const std::string script = write("learning.lua", R"(scene { builtin = "cornell" }
image { width = 64, height = 64, spp = 1 }
renderers { count = 1, lighting = multiplexer { lightop "direct" { light_sampling = "learned", learned_samples = 400000 },
                                               replicas = 2 } }
)");
  RunResult r;
  ASSERT_NO_FATAL_FAILURE(
      kill_once_reported({"run", script, "--output", path("learning.png")}, "direct.1: learning lights", "direct.1", r));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("lightfarm: error: replica 'direct.1' was killed by signal 9 (Killed) during setup; the replicas "
                       "of 'direct' share their setup (direct), so its share cannot be redone"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("learning.png")));
  EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
}

// A renderer and a pool replica that die before saying hello (LIGHTFARM_FAULT aborts them at start) are left out:
// the pool is configured without the replica, the other renderer takes every tile, and the image is the
// fault-free one. (The chaos soak found frames failing when a kill landed before the render.)
TEST_F(FailureTest, RenderersAndReplicasLostAtStartUpAreLeftOut) {
  const auto args = small(kPool, {"width=48", "height=48", "spp=4"});
  Image reference = render(args, "reference.exr");
  auto run = args;
  run.insert(run.end(), {"--output", path("faulty.exr")});
  auto r = run_lightfarm(run, {"LIGHTFARM_FAULT=crash-at-start:renderer-1,direct.1"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("renderer 'renderer-1' was killed by signal 6 (Aborted)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("replica 'direct.1' was killed by signal 6 (Aborted)"), std::string::npos) << r.err;
  EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
  auto img = read_image(path("faulty.exr"));
  ASSERT_TRUE(img.ok()) << r.err;
  EXPECT_TRUE(img->pixels == reference.pixels);
}

// Ctrl-Z and fg (issue 12): SIGTSTP to the director stops its actors and itself; three times the heartbeat timeout
// later SIGCONT resumes them all, nobody is taken for dead, and the image is the one an unpaused run makes.
TEST_F(FailureTest, CtrlZThenFgResumesTheFarm) {
  const auto args = small(kSlowPool, {"spp=64", "slowdown=3", "heartbeat_timeout=1"});
  Image reference = render(small(kSlowPool, {"spp=64", "heartbeat_timeout=1"}), "reference.exr");
  auto run = args;
  run.insert(run.end(), {"--output", path("paused.exr")});
  Farm farm(run);
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 20%") != std::string::npos; }, 60))
      << farm.err_so_far();
  const auto replicas = actor_pids(farm.tag(), "direct.0");
  ASSERT_EQ(replicas.size(), 1u);
  ::kill(farm.pid(), SIGTSTP);
  EXPECT_TRUE(Farm::eventually([&] { return process_state(farm.pid()) == 'T' && process_state(replicas[0]) == 'T'; }, 5))
      << "director " << process_state(farm.pid()) << ", replica " << process_state(replicas[0]);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  ::kill(farm.pid(), SIGCONT);
  auto r = farm.wait(120);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err.find("silent"), std::string::npos) << r.err;
  EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
  auto img = read_image(path("paused.exr"));
  ASSERT_TRUE(img.ok()) << r.err;
  EXPECT_TRUE(img->pixels == reference.pixels);
}

// A director stopped from outside (SIGSTOP cannot be caught) for longer than the heartbeat timeout: its actors
// leave, and the director says why instead of blaming the first of them.
TEST_F(FailureTest, AStoppedDirectorSaysItWasStoppedInsteadOfBlamingAnActor) {
  auto run = small(kSlowPool, {"spp=64", "slowdown=3", "heartbeat_timeout=1"});
  run.insert(run.end(), {"--output", path("stopped.exr")});
  Farm farm(run);
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 20%") != std::string::npos; }, 60))
      << farm.err_so_far();
  ::kill(farm.pid(), SIGSTOP);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  ::kill(farm.pid(), SIGCONT);
  auto r = farm.wait(60);
  EXPECT_EQ(r.status, 1) << r.err;
  const auto says = r.err.find("lightfarm: error: this director was stopped for ");
  EXPECT_NE(says, std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" s, longer than heartbeat_timeout (1 s): its actors took it for dead", says), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("lost the last replica"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("stopped.exr")));
  EXPECT_TRUE(wait_no_leftovers(r.tag).empty());
}

// An image too big for the memory the farm may use is a message and exit 1, not an abort (exit 134).
TEST_F(FailureTest, AnImageTooBigForMemoryIsAnErrorNotACrash) {
  const std::string script = write("huge.lua", "scene { builtin = \"cornell\" }\nimage { width = 16384, height = 16384 }\n"
                                               "renderers { count = 1, lighting = lightop \"direct\" {} }\n");
  const std::string cmd = "ulimit -v 2000000; exec " LIGHTFARM_BINARY " run " + script + " --output " + path("huge.png") +
                          " 2> " + path("huge.err");
  const int rc = std::system(("bash -c '" + cmd + "'").c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 1);
  EXPECT_EQ(read_file(path("huge.err")),
            "lightfarm: error: out of memory for a 16384x16384 image; nothing was rendered\n");
  EXPECT_FALSE(fs::exists(path("huge.png")));
}

// A director SIGKILLed while writing leaves its temporary image; the next farm writing there removes it (and
// never one whose writer still runs).
TEST_F(FailureTest, ADeadWritersPartialImageIsRemovedByTheNextFarm) {
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string stale = path(".out.partial-" + std::to_string(dead) + ".png");
  const std::string live = path(".out.partial-" + std::to_string(::getpid()) + ".png");
  write(".out.partial-" + std::to_string(dead) + ".png", "half an image");
  write(".out.partial-" + std::to_string(::getpid()) + ".png", "being written");
  render(small(kCornell, {"width=16", "height=16", "spp=1"}), "out.png");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));
}

}  // namespace
}  // namespace lf::test
