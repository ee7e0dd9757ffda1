// CURVE on every link (issue 11): a local process that knows an actor's name and the director's endpoint (both on
// the actor's command line, for anyone running `ps`) cannot take the actor's place, and a stranger's shade request
// to an actor's data socket is never answered; both are refused and logged, and the farm's image is right. With
// farm { security = "none" } the impostor does get CONFIG: what CURVE prevents.
#include <gtest/gtest.h>

#include <signal.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kStranger = kSource + "/tests/actors/stranger.py";
const std::string kTint = kSource + "/examples/plugin-python/tint.py";

// The value after `option` on pid's command line.
std::string option_of(pid_t pid, const std::string& option) {
  std::string cmd = read_file("/proc/" + std::to_string(pid) + "/cmdline");
  std::vector<std::string> args;
  for (size_t start = 0; start < cmd.size();) {
    const size_t end = cmd.find('\0', start);
    args.push_back(cmd.substr(start, end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  for (size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == option) return args[i + 1];
  return {};
}

// TCP ports pid listens on (from /proc: its socket inodes, matched in /proc/net/tcp).
std::vector<int> listening_ports(pid_t pid) {
  std::set<std::string> inodes;
  std::error_code ec;
  for (const auto& fd : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
    const std::string target = fs::read_symlink(fd.path(), ec).string();
    if (target.rfind("socket:[", 0) == 0) inodes.insert(target.substr(8, target.size() - 9));
  }
  std::vector<int> ports;
  std::istringstream tcp(read_file("/proc/net/tcp"));
  std::string line;
  std::getline(tcp, line);  // header
  while (std::getline(tcp, line)) {
    std::istringstream f(line);
    std::string slot, local, remote, state, queues, timer, retr, uid, timeout, inode;
    f >> slot >> local >> remote >> state >> queues >> timer >> retr >> uid >> timeout >> inode;
    if (state == "0A" && inodes.count(inode)) ports.push_back(std::stoi(local.substr(local.find(':') + 1), nullptr, 16));
  }
  return ports;
}

std::string run_stranger(const std::string& args, const std::string& out) {
  std::system((kStranger + " " + args + " > " + out + " 2>&1").c_str());
  return read_file(out);
}

using SecurityTest = FarmFixture;

TEST_F(SecurityTest, AnImpostorWithTheActorsNameIsRefusedUnlessSecurityIsOff) {
  // tint starts 2 s late: the window in which an impostor would have to win the race.
  const std::string script = write("late.lua",
      "scene { builtin = \"cornell\" }\n"
      "image { width = 48, height = 48, spp = 2, tile = 16 }\n"
      "farm { security = param(\"security\", \"curve\") }\n"
      "local t = lightop.exec { cmd = {\"/bin/sh\", \"-c\", \"sleep 2; exec \\\"$0\\\" \\\"$@\\\"\", \"" + kTint + "\"},\n"
      "                         name = \"tint\", input = lightop \"direct\" {} }\n"
      "renderers { count = 1, lighting = t }\n");
  for (const std::string security : {"curve", "none"}) {
    SCOPED_TRACE(security);
    Farm farm({"run", script, "--output", path(security + ".exr"), "--set", "security=" + security});
    std::vector<pid_t> late;
    ASSERT_TRUE(Farm::eventually([&] { return !(late = actor_pids(farm.tag(), "tint")).empty(); }, 10.0));
    const std::string director = option_of(late[0], "--director");
    ASSERT_FALSE(director.empty());
    const std::string said = run_stranger("impostor " + director + " tint", path("impostor.txt"));
    if (security == "curve") {
      EXPECT_NE(said.find("NO CONFIG"), std::string::npos) << said;
      auto r = farm.wait();
      EXPECT_EQ(r.status, 0) << r.err;
      // The impostor's attempt and its client's reconnects within a second are one line, naming the endpoint.
      EXPECT_TRUE(std::regex_search(r.err, std::regex("refused [0-9]+ connections? that did not present a key of this "
                                                      "farm \\(latest: a connection to tcp://[0-9.:]+ that "
                                                      "(spoke without CURVE|left the handshake unfinished \\(no "
                                                      "CURVE, or it timed out or closed half way\\)), sender "
                                                      "unknown\\)")))
          << r.err;
      EXPECT_TRUE(read_image(path("curve.exr")).ok());
      expect_no_leftovers(r);
    } else {
      // Without CURVE the impostor is taken for tint and gets its CONFIG; the real tint is shut out.
      EXPECT_NE(said.find("GOT CONFIG"), std::string::npos) << said;
      ::kill(farm.pid(), SIGINT);
      auto r = farm.wait();
      EXPECT_EQ(r.status, 128 + SIGINT) << r.err;
      expect_no_leftovers(r);
    }
  }
  // The image with an impostor knocking equals one without.
  auto quiet = run_lightfarm({"run", script, "--output", path("quiet.exr")});
  ASSERT_EQ(quiet.status, 0) << quiet.err;
  auto a = read_image(path("curve.exr")), b = read_image(path("quiet.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->pixels, b->pixels);
}

TEST_F(SecurityTest, AStrangersShadeRequestIsNeverAnswered) {
  Farm farm({"run", kSource + "/examples/cornell.lua", "--set", "width=128", "--set", "height=128", "--set", "spp=512",
             "--set", "renderers=1", "--output", path("c.exr")});
  std::vector<pid_t> direct;
  std::vector<int> ports;
  ASSERT_TRUE(Farm::eventually(
      [&] {
        direct = actor_pids(farm.tag(), "direct");
        if (direct.empty()) return false;
        ports = listening_ports(direct[0]);
        return !ports.empty();
      },
      10.0));
  for (int port : ports) {
    const std::string said = run_stranger("shade tcp://127.0.0.1:" + std::to_string(port), path("stranger.txt"));
    EXPECT_NE(said.find("NO REPLY"), std::string::npos) << "port " << port << ": " << said;
  }
  auto r = farm.wait();
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("direct: warning: refused"), std::string::npos) << r.err;
  EXPECT_TRUE(read_image(path("c.exr")).ok());
  expect_no_leftovers(r);
}

}  // namespace
}  // namespace lf::test
