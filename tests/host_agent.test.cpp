// Host agents (issue 11): a host with two or more scene-loading actors of a shipped scene loads it and builds its
// BVH once, in an agent that forks those actors. The image does not change, every actor says it got its scene
// from the agent, and killing an actor — its stand-in (the `lightfarm actor` process the director launched) or the
// forked process itself — is the same loss, recovered the same way, with nothing left running.
#include <gtest/gtest.h>
#include <signal.h>

#include <regex>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kBox = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/cornell_box_mcguire/CornellBox-Original.obj";

class HostAgentTest : public FarmFixture {
 protected:
  void SetUp() override {
    FarmFixture::SetUp();
    if (!fs::exists(kBox)) GTEST_SKIP() << "no " << kBox << " here";
  }
  // Two renderers and a pool of `replicas` `direct`s on this machine, over the McGuire box (a shipped scene).
  std::string pool_script(int replicas, int spp, double slowdown) {
    std::string slow = "{";
    for (int i = 0; i < replicas; ++i) slow += (i ? ", " : "") + std::to_string(slowdown);
    slow += "}";
    return write("agent.lua", "scene { file = \"" + kBox + "\" }\n"
                              "camera { eye = {0, 1, 3.5}, at = {0, 1, 0}, fov = 40 }\n"
                              "image { width = 96, height = 96, spp = " + std::to_string(spp) + ", tile = 16 }\n"
                              "farm { host_agents = param(\"agents\", true), heartbeat_timeout = 2 }\n"
                              "local direct = multiplexer { lightop \"direct\" { light_samples = 2 }, replicas = " +
                              std::to_string(replicas) + ", slowdown = " + slow + " }\n"
                              "renderers { count = 2, lighting = direct, batch = 1024 }\n");
  }
  // Per actor in a --stats-json text: whether it said it got its scene from the host agent.
  static std::map<std::string, bool> from_agent(const std::string& stats) {
    std::map<std::string, bool> out;
    const std::regex actor("\"name\": \"([^\"]+)\"");
    for (auto it = std::sregex_iterator(stats.begin(), stats.end(), actor); it != std::sregex_iterator(); ++it) {
      const size_t at = static_cast<size_t>(it->position());
      const size_t end = stats.find("\"name\": \"", at + 1);
      const std::string block = stats.substr(at, end == std::string::npos ? std::string::npos : end - at);
      if (block.find("\"scene_from_agent\": true") != std::string::npos) out[(*it)[1]] = true;
      else if (block.find("\"scene_from_agent\": false") != std::string::npos) out[(*it)[1]] = false;
    }
    return out;
  }
};

TEST_F(HostAgentTest, ActorsForkedFromTheAgentRenderTheSamePixels) {
  const std::string script = pool_script(2, 4, 1);
  auto with = run_lightfarm({"run", script, "--output", path("with.exr"), "--stats-json", path("with.json")});
  ASSERT_EQ(with.status, 0) << with.err;
  expect_no_leftovers(with);
  auto without = run_lightfarm({"run", script, "--set", "agents=false", "--output", path("without.exr"),
                                "--stats-json", path("without.json")});
  ASSERT_EQ(without.status, 0) << without.err;
  expect_no_leftovers(without);
  auto a = read_image(path("with.exr")), b = read_image(path("without.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->pixels == b->pixels) << "a host agent changes no pixel";
  const auto forked = from_agent(read_file(path("with.json"))), own = from_agent(read_file(path("without.json")));
  for (const char* actor : {"renderer-0", "renderer-1", "direct.0", "direct.1"}) {
    ASSERT_TRUE(forked.count(actor)) << actor << " sent no scene_from_agent";
    EXPECT_TRUE(forked.at(actor)) << actor << " loaded its own scene though the host has an agent";
    ASSERT_TRUE(own.count(actor));
    EXPECT_FALSE(own.at(actor)) << actor << " says it came from an agent with host_agents = false";
  }
  EXPECT_FALSE(forked.count("direct")) << "the pool has no process (its renderers dispatch to the replicas)";
}

TEST_F(HostAgentTest, KillingAForkedActorOrItsStandInIsOneLossAndChangesNoPixel) {
  const std::string reference_script = pool_script(3, 64, 1);
  auto ref = run_lightfarm({"run", reference_script, "--output", path("reference.exr")});
  ASSERT_EQ(ref.status, 0) << ref.err;
  const auto reference = read_image(path("reference.exr"));
  ASSERT_TRUE(reference.ok());
  const std::string script = pool_script(3, 64, 6);
  // The stand-in is the process with the actor's command line; the forked actor carries its name in comm.
  for (const std::string victim : {"stand-in", "forked"}) {
    SCOPED_TRACE(victim);
    Farm farm({"run", script, "--output", path(victim + ".exr")});
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 20%") != std::string::npos; }, 60))
        << farm.err_so_far();
    std::vector<pid_t> pids;
    if (victim == "stand-in") {
      pids = actor_pids(farm.tag(), "direct.1");
    } else {
      for (pid_t pid : leftover_processes(farm.tag()))
        if (read_file("/proc/" + std::to_string(pid) + "/comm") == "direct.1\n") pids.push_back(pid);
    }
    ASSERT_EQ(pids.size(), 1u) << "no single " << victim << " process for direct.1";
    EXPECT_EQ(farm.err_so_far().find("render 100%"), std::string::npos) << "the frame ended before the kill";
    ::kill(pids[0], SIGKILL);
    auto r = farm.wait(120);
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("replica 'direct.1' was killed by signal 9 (Killed)"), std::string::npos) << r.err;
    auto img = read_image(path(victim + ".exr"));
    ASSERT_TRUE(img.ok()) << r.err;
    EXPECT_TRUE(img->pixels == reference->pixels) << "the image changed after losing direct.1's " << victim;
    expect_no_leftovers(r);
  }
}

}  // namespace
}  // namespace lf::test
