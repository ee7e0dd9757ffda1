// Farms across hosts (issue 11): the hosts are network namespaces on this machine running Debian's OpenSSH server
// (tests/rig/hosts.sh), the actors start over real ssh. Images equal the one-machine run bit for bit; bad hosts
// stop the farm at launch naming the host and ssh's words; nothing is left running here or on any host.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>

#include "render/images/image.hpp"
#include "actors/launchers/host_launcher.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kRig = kSource + "/tests/rig/hosts.sh";

// The rig of the running test, torn down on Ctrl-C too.
std::string g_rig_dir;
void tear_down_on_signal(int sig) {
  if (!g_rig_dir.empty() && ::fork() == 0) {
    ::execl("/bin/bash", "bash", kRig.c_str(), "down", g_rig_dir.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::wait(nullptr);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

int sh(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

class HostsTest : public FarmFixture {
 protected:
  std::map<std::string, std::string> address;  // h1 -> 10.213.x.11
  std::string rig;

  void SetUp() override {
    FarmFixture::SetUp();
    rig = path("rig");
    g_rig_dir = rig;
    ::signal(SIGINT, tear_down_on_signal);
    ::signal(SIGTERM, tear_down_on_signal);
    const int rc = sh(kRig + " up " + rig + " 3 > " + path("rig.log") + " 2>&1");
    if (rc == 77) {
      // CI runs on a machine made for the rig (.ci/run says so): there, a rig that cannot be made is a failure.
      if (std::getenv("LIGHTFARM_REQUIRE_RIG")) FAIL() << "LIGHTFARM_REQUIRE_RIG is set: " << read_file(path("rig.log"));
      GTEST_SKIP() << read_file(path("rig.log"));
    }
    ASSERT_EQ(rc, 0) << read_file(path("rig.log"));
    std::ifstream hosts(rig + "/hosts");
    std::string name, addr;
    while (hosts >> name >> addr) address[name] = addr;
    ASSERT_EQ(address.size(), 3u);
  }
  void TearDown() override {
    if (!rig.empty()) sh(kRig + " down " + rig);
    g_rig_dir.clear();
    FarmFixture::TearDown();
  }

  // host "h1" { ... } declarations for every rig host, as Lua locals h1, h2, h3.
  std::string host_lines(const std::string& extra = "") const {
    std::string lua;
    for (const auto& [name, addr] : address)
      lua += "local " + name + " = host \"" + name + "\" { launcher = \"ssh\", address = \"" + addr +
             "\", ssh_config = \"" + rig + "/ssh_config\"" + extra + " }\n";
    return lua;
  }

  // Nothing of the farm is left here, and nothing but sshd runs on any host.
  void expect_nothing_left(const RunResult& r) {
    expect_no_leftovers(r);
    // A host's sshd session ends when the local ssh master does; on a loaded machine (the full suite) that was seen
    // to take over 5 s after the master left this host's process table.
    std::string remote;
    EXPECT_TRUE(Farm::eventually([&] { return (remote = running_on_hosts("")).empty(); }, 10.0))
        << "left running on the hosts:\n" << remote;
  }

  // What runs on the hosts (`rig pids`: "hN PID COMMAND" lines), through `filter` (a shell pipeline, or empty).
  std::string running_on_hosts(const std::string& filter) {
    sh(kRig + " pids " + rig + filter + " > " + path("pids") + " 2>&1");
    return read_file(path("pids"));
  }

  // The pool network (2 renderers, 3 `direct` replicas) twice: local.lua all here, spread.lua with the replicas on
  // h1..h3 and the renderers on `renderer_hosts`. Returns the two scripts' paths.
  std::pair<std::string, std::string> pool_scripts(const std::string& head, const std::string& renderer_hosts) {
    const std::string pool = "local direct = multiplexer { lightop \"direct\" { light_samples = 2 }, replicas = 3";
    return {write("local.lua", head + pool + " }\nrenderers { count = 2, lighting = direct }\n"),
            write("spread.lua", head + host_lines() + pool + ",\n                             host = { h1, h2, h3 } }\n"
                                "renderers { count = 2, lighting = direct, host = " + renderer_hosts + " }\n")};
  }

  // Every renderer and replica of a three-host pool farm says (in --stats-json) it got its scene from its host's agent.
  static void expect_scenes_from_agents(const std::string& stats) {
    for (const char* actor : {"renderer-0", "renderer-1", "renderer-2", "direct.0", "direct.1", "direct.2"}) {
      const size_t at = stats.find(std::string("\"name\": \"") + actor + "\"");
      ASSERT_NE(at, std::string::npos) << actor;
      const size_t next = stats.find("\"name\": \"", at + 1);
      EXPECT_NE(stats.substr(at, next - at).find("\"scene_from_agent\": true"), std::string::npos)
          << actor << " did not get its scene from its host's agent";
    }
  }

  Image render(const std::string& script, const std::vector<std::string>& sets, const std::string& out) {
    std::vector<std::string> args{"run", script, "--quiet", "--output", path(out)};
    for (const auto& s : sets) args.insert(args.end(), {"--set", s});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << r.err;
    expect_nothing_left(r);
    auto img = read_image(path(out));
    EXPECT_TRUE(img.ok()) << out;
    return img.ok() ? *img : Image{};
  }
};

bool same_pixels(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.width > 0 &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(RGB)) == 0;
}

TEST_F(HostsTest, ThePoolNetworkOverThreeSshHostsGivesTheLocalPixels) {
  const auto [local, spread] = pool_scripts("scene { builtin = \"cornell\" }\n"
                                           "image { width = 96, height = 96, spp = 4 }\n",
                                           "{ h2, h3 }");
  const Image a = render(local, {}, "local.exr");
  const Image b = render(spread, {}, "spread.exr");
  EXPECT_TRUE(same_pixels(a, b));
}

TEST_F(HostsTest, TheCausticsNetworkWithItsPhotonPoolAcrossHostsGivesTheLocalPixels) {
  const std::string script = kSource + "/examples/cornell_glass.lua";
  const std::vector<std::string> small{"width=64", "height=64", "spp=2", "photons=40000", "prepass=1000"};
  const Image a = render(script, small, "glass-local.exr");
  // The same network, its photon-map replicas on h1 and h2, a cache on h3, the rest here.
  std::string text = host_lines() + read_file(script);
  auto place = [&](const std::string& what, const std::string& with) {
    const auto at = text.find(what);
    ASSERT_NE(at, std::string::npos) << what;
    text.replace(at, what.size(), with);
  };
  place("replicas = param(\"photon_replicas\", 2)", "replicas = param(\"photon_replicas\", 2), host = { h1, h2 }");
  place("name = \"bounce1\",", "name = \"bounce1\", host = h3,");
  const std::string spread = write("glass.lua", text);
  const Image b = render(spread, small, "glass-spread.exr");
  EXPECT_TRUE(same_pixels(a, b));
}

TEST_F(HostsTest, BadHostsStopTheFarmAtLaunchNamingTheHostAndSshsWords) {
  const std::string wrong_key = rig + "/wrong_id";
  ASSERT_EQ(sh("ssh-keygen -q -t ed25519 -N '' -f " + wrong_key), 0);
  ASSERT_EQ(sh("sed 's#IdentityFile .*/id$#IdentityFile " + wrong_key + "#' " + rig + "/ssh_config > " + rig +
               "/ssh_config_wrong"),
            0);
  const std::string subnet = address["h1"].substr(0, address["h1"].rfind('.'));
  struct Case {
    std::string name, host, says;
  };
  for (const Case& c : std::vector<Case>{
           {"unreachable", "address = \"" + subnet + ".99\", ssh_config = \"" + rig + "/ssh_config\"",
            "host 'far' (" + subnet + ".99): ssh failed: ssh: connect to host " + subnet + ".99 port 22:"},
           {"wrong key", "address = \"" + address["h1"] + "\", ssh_config = \"" + rig + "/ssh_config_wrong\"",
            "host 'far' (" + address["h1"] + "): ssh failed: root@" + address["h1"] + ": Permission denied (publickey)"},
           {"no binary", "address = \"" + address["h1"] + "\", ssh_config = \"" + rig + "/ssh_config\", lightfarm = \"/no/lightfarm\"",
            "host 'far' (" + address["h1"] + "): no lightfarm executable at '/no/lightfarm' there"}}) {
    auto script = write("bad.lua", "scene { builtin = \"cornell\" }\nimage { width = 16, height = 16, spp = 1 }\n"
                                   "local far = host \"far\" { launcher = \"ssh\", " + c.host + " }\n"
                                   "renderers { count = 1, lighting = lightop \"direct\" { host = far } }\n");
    auto r = run_lightfarm({"run", script, "--output", path("bad.png")});
    EXPECT_EQ(r.status, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.name << ":\n" << r.err;
    EXPECT_NE(r.err.find("lightfarm: error: cannot start the farm: host 'far'"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("bad.png")));
    expect_nothing_left(r);
  }
}

}  // namespace
}  // namespace lf::test

namespace lf::test {
namespace {

// A host known to the user's ssh config by name is reached by that name (ssh_name), so its Host block applies: here
// only the names carry the key, and the addresses alone are refused.
TEST_F(HostsTest, AHostIsReachedByItsSshName) {
  ASSERT_EQ(sh("sed 's/^Host \\(h[0-9]\\) .*/Host \\1/' " + rig + "/ssh_config > " + rig + "/ssh_config_names"), 0);
  auto script = [&](bool named) {
    std::string lua = "scene { builtin = \"cornell\" }\nimage { width = 32, height = 32, spp = 1 }\n";
    lua += "local h1 = host \"h1\" { launcher = \"ssh\", address = \"" + address.at("h1") + "\", ssh_config = \"" + rig +
           "/ssh_config_names\"" + (named ? ", ssh_name = \"h1\"" : "") + " }\n";
    lua += "renderers { count = 1, lighting = lightop \"direct\" { host = h1 } }\n";
    return write(named ? "named.lua" : "unnamed.lua", lua);
  };
  auto named = run_lightfarm({"run", script(true), "--output", path("named.exr"), "--quiet"});
  EXPECT_EQ(named.status, 0) << named.err;
  expect_nothing_left(named);
  auto unnamed = run_lightfarm({"run", script(false), "--output", path("unnamed.exr"), "--quiet"});
  EXPECT_EQ(unnamed.status, 1) << unnamed.err;
  EXPECT_NE(unnamed.err.find("host 'h1' (" + address.at("h1") + "): ssh failed"), std::string::npos) << unnamed.err;
  expect_nothing_left(unnamed);
}

// A whole host lost mid-frame — its network cut, or everything on it SIGKILLed at once: the heartbeats (or the
// exits) tell, its renderer's tiles and its replica's packets are redone elsewhere, and the image is the
// fault-free one. The pool's multiplexer and the other actors live on h1 and here.
// The frame is long enough (2048 spp, some 10 s) that the cut lands well before its end even on a quiet, fast
// machine: at 512 spp a 2.7 s frame once finished before the kill reached the host, and nothing was lost. With the
// link still cut, the host's launcher stops itself and its actors (the director's pings stopped arriving).
TEST_F(HostsTest, AHostLostMidFrameChangesNoPixel) {
  const auto [local, spread] = pool_scripts("scene { builtin = \"cornell\" }\n"
                                           "image { width = 96, height = 96, spp = 2048, tile = 16 }\n"
                                           "farm { heartbeat_timeout = 2 }\n",
                                           "{ h2, \"local\" }");
  const Image expected = render(local, {}, "local.exr");
  for (const std::string how : {"cut", "kill"}) {
    SCOPED_TRACE(how);
    Farm farm({"run", spread, "--output", path(how + ".exr")});
    // Mid-frame: once the first tiles are in.
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60.0))
        << farm.err_so_far();
    ASSERT_EQ(sh(kRig + " " + how + " " + rig + " 2"), 0);
    auto r = farm.wait(120);
    if (how == "cut") {
      // Still cut off, the host stops what the farm started there once the director has been silent too long:
      // nothing of lightfarm's waits on h2 for the link to return.
      std::string left;
      EXPECT_TRUE(Farm::eventually([&] { return (left = running_on_hosts(" | grep '^h2 ' | grep lightfarm")).empty(); },
                                   kHostSilenceSeconds + 10))
          << "left on h2 with its link cut:\n" << left;
      sh(kRig + " mend " + rig + " 2");
    }
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.err.find("renderer 'renderer-0'"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("replica 'direct.1'"), std::string::npos) << r.err;
    auto img = read_image(path(how + ".exr"));
    ASSERT_TRUE(img.ok()) << r.err;
    EXPECT_TRUE(same_pixels(expected, *img));
    expect_nothing_left(r);
  }
}

// The director SIGKILLed mid-frame with actors on three hosts: the lifelines end the remote actors, ssh's master
// connections expire (ControlPersist), and the next farm sweeps the folders the dead director could not remove.
TEST_F(HostsTest, AKilledDirectorLeavesNothingOnAnyHost) {
  const auto [local, spread] = pool_scripts("scene { builtin = \"cornell\" }\n"
                                           "image { width = 96, height = 96, spp = 1024, tile = 16 }\n"
                                           "farm { heartbeat_timeout = 2 }\n",
                                           "{ h2, h3 }");
  Farm farm({"run", spread, "--output", path("killed.exr")});
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60.0))
      << farm.err_so_far();
  const std::string control_dirs = "/tmp/lightfarm-ssh-" + std::to_string(farm.pid()) + "-";
  auto left_dirs = [&] {
    size_t n = 0;
    for (const auto& e : fs::directory_iterator("/tmp")) n += e.path().string().rfind(control_dirs, 0) == 0;
    return n;
  };
  EXPECT_EQ(left_dirs(), 3u);  // one per host
  ::kill(farm.pid(), SIGKILL);
  auto r = farm.wait(10);
  EXPECT_EQ(r.status, 128 + SIGKILL);
  // Remote actors go within their lifeline's 2 s; the masters after ControlPersist (5 s) once their sessions end.
  auto left = wait_no_leftovers(r.tag, 15.0);
  EXPECT_TRUE(left.empty()) << left.size() << " processes of the farm left here, e.g. "
                            << read_file("/proc/" + std::to_string(left.empty() ? 0 : left[0]) + "/cmdline");
  expect_nothing_left(r);
  EXPECT_FALSE(fs::exists(path("killed.exr")));
  // The next farm here starts by sweeping the dead director's control folder.
  render(local, {}, "after.exr");
  EXPECT_EQ(left_dirs(), 0u);
}

}  // namespace
}  // namespace lf::test

namespace lf::test {
namespace {

// A room lit by a ceiling panel, as OBJ + MTL: a scene only the director reads.
const char* kRoomObj = R"(mtllib room.mtl
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -1 2 -1
v 1 2 -1
v 1 2 1
v -1 2 1
v -0.3 1.99 -0.3
v 0.3 1.99 -0.3
v 0.3 1.99 0.3
v -0.3 1.99 0.3
usemtl white
f 1 2 3 4
f 8 7 6 5
f 5 6 2 1
usemtl red
f 4 8 5 1
usemtl green
f 2 6 7 3
usemtl light
f 12 11 10 9
)";
const char* kRoomMtl = "newmtl white\nKd 0.7 0.7 0.7\nnewmtl red\nKd 0.7 0.1 0.1\nnewmtl green\nKd 0.1 0.7 0.1\n"
                       "newmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n";

// The number after "key": in a JSON text.
double json_number(const std::string& text, const std::string& key) {
  auto pos = text.find("\"" + key + "\"");
  return pos == std::string::npos ? -1 : std::strtod(text.c_str() + text.find(':', pos) + 1, nullptr);
}

// The stats JSON's scene.bytes_shipped for `host` (a small parser for a flat map).
int64_t shipped_to(const std::string& stats, const std::string& host) {
  const auto at = stats.find("\"bytes_shipped\"");
  if (at == std::string::npos) return -1;
  const auto key = stats.find("\"" + host + "\"", at);
  return key == std::string::npos ? -1 : std::strtoll(stats.c_str() + stats.find(':', key) + 1, nullptr, 10);
}

TEST_F(HostsTest, TheSceneTravelsOncePerHostAndIsThenReusedFromItsCache) {
  write("room.obj", kRoomObj);
  write("room.mtl", kRoomMtl);
  const std::string body = "scene { file = \"room.obj\" }\n"
                           "camera { eye = {0, 1, 3.5}, at = {0, 1, 0}, fov = 45 }\n"
                           "image { width = 48, height = 48, spp = 4 }\n";
  auto local = write("local.lua", body + "renderers { count = 2, lighting = multiplexer { lightop \"direct\" {}, replicas = 3 } }\n");
  // A renderer and a replica on each host: two scene-loading actors, so each host's agent (reached over ssh, like
  // the actors) loads the scene once and forks both.
  auto spread = write("spread.lua", body + host_lines() +
                                        "local d = multiplexer { lightop \"direct\" {}, replicas = 3, host = { h1, h2, h3 } }\n"
                                        "renderers { count = 3, lighting = d, host = { h1, h2, h3 } }\n");
  const Image expected = render(local, {}, "local.exr");
  int64_t size = 0;
  for (int run = 1; run <= 2; ++run) {
    SCOPED_TRACE("run " + std::to_string(run));
    auto r = run_lightfarm({"run", spread, "--quiet", "--output", path("spread.exr"), "--stats-json", path("stats.json")},
                           {"LIGHTFARM_CACHE=" + path("director-cache")});
    ASSERT_EQ(r.status, 0) << r.err;
    expect_nothing_left(r);
    const std::string stats = read_file(path("stats.json"));
    size = static_cast<int64_t>(json_number(stats, "bytes"));
    ASSERT_GT(size, 0) << stats;
    for (const char* h : {"h1", "h2", "h3"}) EXPECT_EQ(shipped_to(stats, h), run == 1 ? size : 0) << h << stats;
    EXPECT_EQ(shipped_to(stats, "local"), -1) << "no actor runs on this machine: nothing to ship here\n" << stats;
    expect_scenes_from_agents(stats);
    auto img = read_image(path("spread.exr"));
    ASSERT_TRUE(img.ok());
    EXPECT_TRUE(same_pixels(expected, *img));
  }
  // Each host keeps its own copy, named by the content hash, and the image its actors made of it and share; no
  // temporary is left.
  for (int i = 1; i <= 3; ++i) {
    std::vector<std::string> names;
    for (const auto& f : fs::directory_iterator(rig + "/cache-h" + std::to_string(i) + "/scenes")) {
      names.push_back(f.path().filename().string());
      if (f.path().extension() == ".lfscene") {
        EXPECT_EQ(static_cast<int64_t>(fs::file_size(f.path())), size);
      }
    }
    std::sort(names.begin(), names.end());
    ASSERT_EQ(names.size(), 3u) << "host h" << i;
    const std::string stem = names[0];
    EXPECT_EQ(fs::path(stem).extension(), ".lfscene");
    EXPECT_EQ(names[1], stem + ".image");
    EXPECT_EQ(names[2], stem + ".lock");
  }
}

// A partitioned scene whose parts live on three ssh hosts (partition { host = ... }): the path tracer here sends its
// rays to geometry actors on other hosts, over CURVE, and gets the unpartitioned farm's pixels.
TEST_F(HostsTest, AScenesPartsOnThreeHostsGiveTheLocalPixels) {
  write("room.obj", kRoomObj);
  write("room.mtl", kRoomMtl);
  const std::string body = "scene { file = \"room.obj\" }\n"
                           "camera { eye = {0, 1, 3.5}, at = {0, 1, 0}, fov = 45 }\n"
                           "image { width = 48, height = 48, spp = 2 }\n";
  const std::string lighting = "renderers { count = 2, lighting = lightop \"pathtrace\" { max_depth = 4 } }\n";
  auto local = write("whole.lua", body + lighting);
  auto spread = write("parts.lua", body + host_lines() + "partition { parts = 3, host = { h1, h2, h3 } }\n" + lighting);
  const Image a = render(local, {}, "whole.exr");
  auto r = run_lightfarm({"run", spread, "--quiet", "--output", path("parts.exr"), "--stats-json", path("stats.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  expect_nothing_left(r);
  // Only the geometry actors run on the hosts: the scene went to each of them.
  const std::string stats = read_file(path("stats.json"));
  for (const char* h : {"h1", "h2", "h3"}) EXPECT_GT(shipped_to(stats, h), 0) << h << stats;
  auto b = read_image(path("parts.exr"));
  ASSERT_TRUE(b.ok());
  EXPECT_TRUE(same_pixels(a, *b));
}


}  // namespace
}  // namespace lf::test

namespace lf::test {
namespace {

// A real Slurm cluster over the same hosts (tests/rig/slurm.sh): the farm runs inside `salloc`, finds its nodes
// with slurm_hosts() and starts every actor as a job step.
class SlurmTest : public HostsTest {
 protected:
  void SetUp() override {
    HostsTest::SetUp();
    if (IsSkipped() || HasFatalFailure()) return;
    const int rc = sh(std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/slurm.sh up " + rig + " > " + path("slurm.log") + " 2>&1");
    if (rc == 77) {
      if (std::getenv("LIGHTFARM_REQUIRE_RIG")) FAIL() << "LIGHTFARM_REQUIRE_RIG is set: " << read_file(path("slurm.log"));
      GTEST_SKIP() << read_file(path("slurm.log"));
    }
    ASSERT_EQ(rc, 0) << read_file(path("slurm.log"));
    slurm_up = true;
  }
  void TearDown() override {
    if (slurm_up) sh(std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/slurm.sh down " + rig);
    HostsTest::TearDown();
  }

  // `salloc -N nodes lightfarm args...`, tagged like any farm of the harness.
  RunResult run_in_allocation(int nodes, const std::vector<std::string>& args) {
    RunResult r;
    r.tag = unique_tag();
    std::string cmd = "cd " + path("") + " && LIGHTFARM_TEST_TAG=" + r.tag + " LIGHTFARM_CACHE=" + path("cache") +
                      " SLURM_CONF=" + rig + "/slurm.conf salloc --quiet -N " + std::to_string(nodes) + " " +
                      LIGHTFARM_BINARY;
    for (const auto& a : args) cmd += " '" + a + "'";
    r.status = sh(cmd + " > " + path("salloc.out") + " 2> " + path("salloc.err"));
    r.out = read_file(path("salloc.out"));
    r.err = read_file(path("salloc.err"));
    return r;
  }
  // examples/slurm/walkthrough.sbatch as a job array of `tasks` (sbatch --wait), submitted from the test's folder
  // with `env` set and `args` after the batch script's name; lightfarm is found on the PATH, as a user's would be.
  RunResult submit_walkthrough(int tasks, const std::string& env, const std::vector<std::string>& args) {
    RunResult r;
    r.tag = unique_tag();
    const std::string bin = std::string(LIGHTFARM_BINARY).substr(0, std::string(LIGHTFARM_BINARY).rfind('/'));
    std::string cmd = "cd " + path("") + " && PATH=" + bin + ":$PATH LIGHTFARM_TEST_TAG=" + r.tag + " " + env +
                      " SLURM_CONF=" + rig + "/slurm.conf sbatch --quiet --wait --array=0-" + std::to_string(tasks - 1) +
                      " " + LIGHTFARM_SOURCE_DIR + "/examples/slurm/walkthrough.sbatch";
    for (const auto& a : args) cmd += " '" + a + "'";
    r.status = sh(cmd + " > " + path("sbatch.out") + " 2> " + path("sbatch.err"));
    r.out = read_file(path("sbatch.out"));
    r.err = read_file(path("sbatch.err"));
    return r;
  }
  // The array tasks' logs (lightfarm-walk-JOB_TASK.log in the submit folder), by task, of the newest job.
  std::map<int, std::string> task_logs() {
    std::map<int, std::pair<long, std::string>> newest;  // task -> (job id, log)
    for (const auto& e : fs::directory_iterator(path(""))) {
      long job = 0;
      int task = 0;
      if (std::sscanf(e.path().filename().c_str(), "lightfarm-walk-%ld_%d.log", &job, &task) != 2) continue;
      if (job >= newest[task].first) newest[task] = {job, read_file(e.path().string())};
    }
    std::map<int, std::string> logs;
    for (auto& [task, log] : newest) logs[task] = log.second;
    return logs;
  }
  bool slurm_up = false;
};

TEST_F(SlurmTest, ThePoolNetworkAcrossAnAllocationGivesTheLocalPixels) {
  const std::string body = "scene { builtin = \"cornell\" }\nimage { width = 96, height = 96, spp = 4 }\n";
  auto local = write("local.lua", body + "renderers { count = 2, lighting = multiplexer { lightop \"direct\" {}, replicas = 3 } }\n");
  auto slurm = write("slurm.lua", body + "local nodes = slurm_hosts()\n"
                                       "local d = multiplexer { lightop \"direct\" {}, replicas = 3, host = nodes }\n"
                                       "renderers { count = 2, lighting = d, host = nodes }\n");
  const Image expected = render(local, {}, "local.exr");
  auto r = run_in_allocation(3, {"run", slurm, "--quiet", "--output", path("slurm.exr")});
  ASSERT_EQ(r.status, 0) << r.err;
  expect_nothing_left(r);
  auto img = read_image(path("slurm.exr"));
  ASSERT_TRUE(img.ok()) << r.err;
  EXPECT_TRUE(same_pixels(expected, *img));
  // Outside an allocation, slurm_hosts() says so at its line.
  auto outside = run_lightfarm({"run", slurm, "--output", path("outside.exr")});
  EXPECT_EQ(outside.status, 2);
  EXPECT_NE(outside.err.find("slurm.lua:3: slurm_hosts(): not inside a Slurm allocation"), std::string::npos)
      << outside.err;
}

// A scene from a file under Slurm: shipped to each node, where a host agent (a job step of its own) loads it once
// and forks that node's renderer and replica; the image is the local one.
TEST_F(SlurmTest, AShippedSceneIsLoadedOncePerNodeByItsAgent) {
  write("room.obj", kRoomObj);
  write("room.mtl", kRoomMtl);
  const std::string body = "scene { file = \"room.obj\" }\ncamera { eye = {0, 1, 3.5}, at = {0, 1, 0}, fov = 45 }\n"
                           "image { width = 48, height = 48, spp = 4 }\nfarm { light_paths = \"partial\" }\n";
  auto local = write("local.lua", body + "renderers { count = 2, lighting = multiplexer { lightop \"direct\" {}, replicas = 3 } }\n");
  auto slurm = write("slurm.lua", body + "local nodes = slurm_hosts()\n"
                                       "local d = multiplexer { lightop \"direct\" {}, replicas = 3, host = nodes }\n"
                                       "renderers { count = 3, lighting = d, host = nodes }\n");
  const Image expected = render(local, {}, "local.exr");
  auto r = run_in_allocation(3, {"run", slurm, "--quiet", "--output", path("slurm.exr"), "--stats-json", path("stats.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "") << "a clean farm says nothing with --quiet";
  expect_nothing_left(r);
  auto img = read_image(path("slurm.exr"));
  ASSERT_TRUE(img.ok()) << r.err;
  EXPECT_TRUE(same_pixels(expected, *img));
  const std::string stats = read_file(path("stats.json"));
  expect_scenes_from_agents(stats);
}

// The walkthrough's batch script as a job array: each task renders its share of a job's frames with a farm on its
// node, all record into one job folder (the nodes share this machine's file system, as a cluster's share NFS), and
// a task that starts mid-job holds the carried cache and learned lights the uninterrupted job would (restored from
// the folder or replayed). Together they give that job's frames bit for bit; submitted again after frames were
// lost, the array renders only those.
TEST_F(SlurmTest, TheWalkthroughArraysTasksTogetherGiveTheUninterruptedJobsFrames) {
  const std::string script = write("turn.lua", R"(
scene  { builtin = "cornell_glass" }
image  { width = 32, height = 32, spp = 2, output = param("out", "turn.####.exr") }
local function view(f)
  local a = (f - 1) * 0.08
  return { eye = {278 + 1073 * math.sin(a), 273, 273 - 1073 * math.cos(a)}, at = {278, 273, 273}, fov = 39.3 }
end
frames { first = 1, last = param("frames", 6), camera = view }
farm { light_paths = "partial" }
local direct   = lightop "direct" { light_sampling = "learned" }
local indirect = lightop "irradiance" { input = lightop "pathtrace" { name = "paths" }, name = "indirect" }
renderers { count = 1, lighting = lightop "combine" { inputs = { direct, indirect } } }
)");
  const auto whole = run_lightfarm({"run", script, "--quiet", "--checkpoint-every", "0", "--set", "out=" + path("ref.####.exr")});
  ASSERT_EQ(whole.status, 0) << whole.err;
  auto frame = [&](const std::string& name, int n) {
    char file[64];
    std::snprintf(file, sizeof file, "%s.%04d.exr", name.c_str(), n);
    return path(file);
  };
  auto same_frames = [&] {
    for (int n = 1; n <= 6; ++n) {
      auto a = read_image(frame("ref", n)), b = read_image(frame("walk", n));
      EXPECT_TRUE(a.ok() && b.ok() && same_pixels(*a, *b)) << "frame " << n << " differs from the uninterrupted job's";
    }
  };
  const std::vector<std::string> args{"--set", "out=" + path("walk.####.exr"), "--checkpoint-every", "0"};
  auto r = submit_walkthrough(3, "SCRIPT=turn.lua FRAMES=6", args);
  ASSERT_EQ(r.status, 0) << r.err;
  expect_nothing_left(r);
  same_frames();
  auto logs = task_logs();
  ASSERT_EQ(logs.size(), 3u);
  for (int task = 0; task < 3; ++task) {
    EXPECT_NE(logs[task].find("wrote 2 frames"), std::string::npos) << "task " << task << ":\n" << logs[task];
    // A task after the first starts mid-job: it caught up with the frames before its own.
    if (task > 0) {
      EXPECT_TRUE(logs[task].find("restored the setups carried over the views") != std::string::npos ||
                  logs[task].find("replaying the views") != std::string::npos)
          << "task " << task << ":\n" << logs[task];
    }
  }
  // Frames lost (deleted, or one overwritten): the array again renders only those, to the same pixels.
  fs::remove(frame("walk", 2));
  fs::copy_file(frame("ref", 1), frame("walk", 5), fs::copy_options::overwrite_existing);
  r = submit_walkthrough(3, "SCRIPT=turn.lua FRAMES=6", args);
  ASSERT_EQ(r.status, 0) << r.err;
  expect_nothing_left(r);
  same_frames();
  logs = task_logs();
  ASSERT_EQ(logs.size(), 3u);
  EXPECT_NE(logs[0].find("wrote 1 frame"), std::string::npos) << logs[0];
  EXPECT_NE(logs[1].find("nothing to render"), std::string::npos) << logs[1];
  EXPECT_NE(logs[2].find("wrote 1 frame"), std::string::npos) << logs[2];
}

}  // namespace
}  // namespace lf::test
