// The host launcher's line protocol, and a HostSession whose transport is this machine's own `lightfarm
// host-launcher` (no ssh): actors start through it, report their exits with their status, are killed on request,
// and nothing they started outlives the session.
#include "actors/launchers/host_launcher.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <fstream>
#include <thread>

namespace lf {
namespace {

TEST(HostLineTest, FieldsWithTabsNewlinesAndBackslashesSurviveTheTrip) {
  const std::vector<std::string> fields{"start", "7", "/a dir", "key\tline\n", "", "back\\slash", "x"};
  const std::string line = host_line(fields);
  EXPECT_EQ(line.back(), '\n');
  EXPECT_EQ(line.find('\n'), line.size() - 1) << "one line";
  EXPECT_EQ(split_host_line(line.substr(0, line.size() - 1)), fields);
}

ExitReport wait_exit(HostSession& s, double seconds = 10) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    if (auto r = s.reap_one()) return *r;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ADD_FAILURE() << "no exit within " << seconds << " s";
  return {};
}

bool alive(pid_t pid) { return ::kill(pid, 0) == 0; }

// A start request for a program of this machine (not lightfarm itself), with `stdin_text` on its stdin.
LaunchRequest program(std::vector<std::string> argv, std::string stdin_text = "") {
  LaunchRequest r;
  r.self = false;
  r.argv = std::move(argv);
  r.stdin_text = std::move(stdin_text);
  return r;
}

TEST(HostSessionTest, ActorsStartThroughOneSessionAndTheirExitsComeBack) {
  HostSession session("here", {LIGHTFARM_BINARY, "host-launcher"});
  const LaunchRequest quick = program({"sh", "-c", "read k; test \"$k\" = secret && exit 3"}, "secret\n");
  auto a = session.start(quick);
  ASSERT_TRUE(a.ok()) << a.error().message;
  EXPECT_GE(*a, pid_t{1} << 30) << "a handle, not a pid of this machine";
  const ExitReport r = wait_exit(session);
  EXPECT_EQ(r.pid, *a);
  ASSERT_TRUE(WIFEXITED(r.status));
  EXPECT_EQ(WEXITSTATUS(r.status), 3) << "its stdin text arrived and its status came back";

  auto m = session.start(program({"/no/such/program"}));
  ASSERT_TRUE(m.ok());
  const ExitReport mr = wait_exit(session);
  EXPECT_EQ(mr.pid, *m);
  EXPECT_TRUE(WIFEXITED(mr.status) && WEXITSTATUS(mr.status) == 127);

  // A long one, killed: SIGTERM arrives as its exit; SIGKILL counts at once.
  const LaunchRequest sleeper = program({"sleep", "60"});
  auto s1 = session.start(sleeper), s2 = session.start(sleeper);
  ASSERT_TRUE(s1.ok() && s2.ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  session.kill(*s1, SIGTERM);
  const ExitReport t = wait_exit(session);
  EXPECT_EQ(t.pid, *s1);
  EXPECT_TRUE(WIFSIGNALED(t.status) && WTERMSIG(t.status) == SIGTERM) << t.describe();
  session.kill(*s2, SIGKILL);
  auto k = session.reap_one();
  ASSERT_TRUE(k.has_value()) << "SIGKILL is an exit at once";
  EXPECT_EQ(k->pid, *s2);
  EXPECT_TRUE(WIFSIGNALED(k->status) && WTERMSIG(k->status) == SIGKILL);
}

TEST(HostSessionTest, AHostLauncherThatIsNotThereEndsItsActorsAtOnce) {
  // A host whose lightfarm has no host launcher (another build): the session ends at once, and each actor asked for
  // comes back as an exit instead of hanging the farm's start-up.
  HostSession session("old", {"sh", "-c", "echo 'lightfarm: error: unknown command host-launcher' >&2; exit 2"});
  const LaunchRequest r = program({"true"});
  auto a = session.start(r);
  ASSERT_TRUE(a.ok());
  const ExitReport e = wait_exit(session);
  EXPECT_EQ(e.pid, *a);
  EXPECT_FALSE(WIFEXITED(e.status) && WEXITSTATUS(e.status) == 0) << e.describe();
  EXPECT_FALSE(session.running());
}

TEST(HostSessionTest, AnEndedSessionIsNoSignalToTheDirector) {
  // The transport is gone before the director writes to it (a cut host's ssh gives up): the write fails quietly
  // instead of raising SIGPIPE, which would end the director.
  HostSession session("cut", {"sh", "-c", "exec 0<&-; sleep 0.3"});
  const LaunchRequest r = program({"true"});
  auto a = session.start(r);
  ASSERT_TRUE(a.ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // its stdin is closed now; it still runs
  session.kill(*a, SIGTERM);  // a write into a pipe nobody reads
  auto b = session.start(r);  // the failed write closed the session's side: no more starts on it
  EXPECT_FALSE(b.ok()) << "a start on a session whose host end is gone";
  const ExitReport e = wait_exit(session);  // the session's end reports the actor
  EXPECT_EQ(e.pid, *a);
}

TEST(HostSessionTest, EndingTheSessionStopsWhatIsStillRunning) {
  const std::string marker = ::testing::TempDir() + "/host-session-" + std::to_string(::getpid());
  {
    HostSession session("here", {LIGHTFARM_BINARY, "host-launcher"});
    const LaunchRequest sleeper = program({"sh", "-c", "echo $$ > " + marker + "; exec sleep 60"});
    ASSERT_TRUE(session.start(sleeper).ok());
    for (int i = 0; i < 200 && !std::ifstream(marker).good(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    session.stop_all(std::chrono::milliseconds(0));
    EXPECT_FALSE(session.running());
  }
  std::ifstream in(marker);
  pid_t pid = 0;
  ASSERT_TRUE(in >> pid);
  EXPECT_FALSE(alive(pid)) << "the actor outlived its session";
  std::remove(marker.c_str());
}

}  // namespace
}  // namespace lf
