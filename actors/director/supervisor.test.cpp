// The supervisor driven message by message, with a fake launcher: what starts, what HELLO must say, and what each
// death means in each stage.
#include "actors/director/supervisor.hpp"

#include <gtest/gtest.h>

#include <set>
#include <signal.h>

#include <deque>

#include "actors/runtime/hello.hpp"
#include "farm/builders.hpp"
#include "radiosity/config.hpp"

namespace lf {
namespace {

using wire::MsgType;

class FakeLauncher final : public Launcher {
 public:
  std::string name() const override { return "fake"; }
  Result<Shipped> ship(const std::string&, const std::string& hash) override { return Shipped{"/cache/" + hash, 0}; }
  Result<pid_t> start(const LaunchRequest& r) override {
    started.push_back(r);
    return next_pid++;
  }
  std::optional<ExitReport> reap_one() override {
    if (exits.empty()) return std::nullopt;
    auto e = exits.front();
    exits.pop_front();
    return e;
  }
  void kill(pid_t pid, int signal) override { killed.emplace_back(pid, signal); }
  void stop_all(std::chrono::milliseconds) override {}

  pid_t next_pid = 100;
  std::vector<LaunchRequest> started;
  std::deque<ExitReport> exits;
  std::vector<std::pair<pid_t, int>> killed;
};

struct Recorder final : Outbox {
  void send(const std::string& actor, wire::Message m) override { sent.emplace_back(actor, std::move(m)); }
  std::vector<std::pair<std::string, wire::Message>> sent;
};

// The events as lines: "request renderer-1 tile", "lost direct.0: why", "peer_down direct.0 to direct",
// "hello again X", "configured again X", "progress X: photons 1 of 4".
std::vector<std::string> described(std::vector<SupervisorEvent> events) {
  std::vector<std::string> lines;
  for (const auto& e : events) {
    using Kind = SupervisorEvent::Kind;
    switch (e.kind) {
      case Kind::request: lines.push_back("request " + e.actor + " " + e.message.header.op); break;
      case Kind::lost: lines.push_back("lost " + e.actor + ": " + e.why); break;
      case Kind::peer_down: lines.push_back("peer_down " + e.actor + " to " + e.to); break;
      case Kind::hello_again: lines.push_back("hello again " + e.actor); break;
      case Kind::configured_again: lines.push_back("configured again " + e.actor); break;
      case Kind::progress:
        lines.push_back("progress " + e.actor + ": " + e.what + " " + std::to_string(e.done) + " of " + std::to_string(e.total));
        break;
    }
  }
  return lines;
}

int status_exited(int code) { return code << 8; }          // as waitpid reports exit(code)
int status_killed(int signal) { return signal & 0x7f; }     // as waitpid reports a death by signal

struct SupervisorTest : ::testing::Test {
  FarmSpec spec;
  Launchers launchers;
  FakeLauncher* fake = nullptr;
  Recorder out;
  std::vector<std::string> seen;  // every event so far, described
  std::unique_ptr<Supervisor> sup;

  // Two renderers asking a pool of two `direct` replicas.
  void SetUp() override {
    PoolSpec pool;
    pool.op = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct", .loc = {"farm.lua", 3}});
    auto mux = replicate(spec, pool);
    ASSERT_TRUE(mux.ok());
    add_renderers(spec, 2, *mux, RendererParams{}, {}, {"farm.lua", 5});
    spec.heartbeat_timeout = 1.0;
    auto f = std::make_unique<FakeLauncher>();
    fake = f.get();
    launchers.set("local", std::move(f));
    sup = std::make_unique<Supervisor>(spec, launchers, out);
    ASSERT_TRUE(sup->launch("tcp://127.0.0.1:5555").ok());
  }

  Status say(const std::string& peer, wire::Message m) {
    Result<wire::Message> r(std::move(m));
    return sup->on_message(peer, r);
  }
  void hello_all() {
    for (auto& [name, a] : sup->actors())
      ASSERT_TRUE(say(name, wire::make(MsgType::hello, name, my_hello(a.spec->kind, "tcp://x:1").to_value())).ok());
  }
  pid_t pid(const std::string& name) { return sup->at(name).pid; }
  // The events so far whose line starts with `kind`.
  std::vector<std::string> events(const std::string& kind) {
    for (auto& line : described(sup->take_events())) seen.push_back(line);
    std::vector<std::string> of_kind;
    for (const auto& line : seen)
      if (line.rfind(kind + " ", 0) == 0) of_kind.push_back(line);
    return of_kind;
  }
};

TEST_F(SupervisorTest, LaunchesEveryActorPointedAtTheDirector) {
  ASSERT_EQ(fake->started.size(), spec.actors.size());
  for (size_t i = 0; i < spec.actors.size(); ++i) {
    const auto& argv = fake->started[i].argv;
    EXPECT_EQ(argv[1], "actor");
    EXPECT_EQ(std::vector<std::string>(argv.end() - 6, argv.end()),
              (std::vector<std::string>{"--kind", spec.actors[i].kind, "--name", spec.actors[i].name, "--director",
                                        "tcp://127.0.0.1:5555"}));
    EXPECT_TRUE(fake->started[i].self);
  }
}

// A farm of thousands waits on HELLOs and READYs after every message; who is late is named only for the message
// that needs it, ten by name and the rest counted.
TEST(SupervisorLate, NamesTenLateActorsAndCountsTheRest) {
  FarmSpec spec;
  const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  add_renderers(spec, 24, direct, RendererParams{}, {}, {});
  Launchers launchers;
  launchers.set("local", std::make_unique<FakeLauncher>());
  Recorder out;
  Supervisor sup(spec, launchers, out);
  ASSERT_TRUE(sup.launch("tcp://127.0.0.1:5555").ok());
  const auto said_hello = [](const ActorRecord& a) { return a.said_hello; };
  EXPECT_FALSE(sup.all(said_hello));
  EXPECT_EQ(sup.late(said_hello),
            "'direct', 'renderer-0', 'renderer-1', 'renderer-10', 'renderer-11', 'renderer-12', 'renderer-13', "
            "'renderer-14', 'renderer-15', 'renderer-16' and 15 more");
}

TEST_F(SupervisorTest, HelloMustNameTheKindAndFloatFormat) {
  auto wrong = say("direct.0", wire::make(MsgType::hello, "direct.0", my_hello("pathtrace", "tcp://x:1").to_value()));
  ASSERT_FALSE(wrong.ok());
  EXPECT_EQ(wrong.error().message, "actor 'direct.0' says it is a 'pathtrace', expected 'direct'");
  Hello h = my_hello("direct", "tcp://x:1");
  h.float_format = "f64be";
  auto floats = say("direct.0", wire::make(MsgType::hello, "direct.0", h.to_value()));
  EXPECT_EQ(floats.error().message, "actor 'direct.0' is incompatible: float format 'f64be', expected 'f32le'");
  EXPECT_EQ(floats.error().code, ErrorCode::incompatible);
  Result<wire::Message> version(make_error("incompatible peer: protocol version 2, expected 1", ErrorCode::incompatible));
  EXPECT_EQ(sup->on_message("direct.0", version).error().message,
            "actor 'direct.0' is an incompatible peer: protocol version 2, expected 1; refusing it");
  // A stranger is ignored; the farm goes on.
  EXPECT_TRUE(say("mallory", wire::make(MsgType::hello, "mallory", my_hello("direct", "tcp://x:1").to_value())).ok());
  hello_all();
  EXPECT_TRUE(sup->all([](const ActorRecord& a) { return a.said_hello; }));
  EXPECT_EQ(sup->at("direct.1").endpoint, "tcp://x:1");
}

TEST_F(SupervisorTest, ReadyRequestsAndErrorsAreRouted) {
  hello_all();
  ASSERT_TRUE(say("renderer-0", wire::make_ready("renderer-0", wire::Phase::configure)).ok());
  EXPECT_EQ(sup->at("renderer-0").ready, wire::Phase::configure);
  const auto configured = [](const ActorRecord& a) { return a.ready == wire::Phase::configure; };
  EXPECT_FALSE(sup->all(configured));
  EXPECT_EQ(sup->late(configured), "'direct', 'direct.0', 'direct.1', 'renderer-1'");
  ASSERT_TRUE(say("renderer-1", wire::make_request("renderer-1", wire::Op::tile, Value::Map{}, 4)).ok());
  EXPECT_EQ(events("request"), std::vector<std::string>{"request renderer-1 tile"});
  ASSERT_TRUE(say("direct.0", wire::make(MsgType::progress, "direct.0",
                                         Value::Map{{"what", "photons"}, {"done", 1}, {"total", 4}})).ok());
  ASSERT_TRUE(say("direct.0", wire::make(MsgType::progress, "direct.0",
                                         Value::Map{{"what", "photons"}, {"done", 5}, {"total", 4}})).ok());
  EXPECT_EQ(events("progress"), std::vector<std::string>{"progress direct.0: photons 1 of 4"}) << "5 of 4 is dropped";
  auto failed = say("direct.1", wire::make_error_reply("direct.1", 0, ErrorCode::actor_failed, "no scene"));
  EXPECT_EQ(failed.error().message, "actor 'direct.1' failed: no scene");
}

TEST_F(SupervisorTest, ADeathDuringStartUpStopsTheFarmUnlessAnotherTakesOver) {
  sup->set_stage(Stage::hello);
  // A replica before its pool is configured: left out of the pool's CONFIG, so nobody is told.
  ASSERT_TRUE(sup->on_exit(ExitReport{pid("direct.0"), status_exited(3)}).ok());
  EXPECT_TRUE(sup->at("direct.0").lost);
  EXPECT_TRUE(events("peer_down").empty());
  // The multiplexer has nobody to take over.
  auto st = sup->on_exit(ExitReport{pid("direct"), status_exited(3)});
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message,
            "actor 'direct' (pid " + std::to_string(pid("direct")) + ") exited with status 3 during start-up");
}

// all() looks first where it last found an actor not done; the answer is still over every actor, whichever comes
// first, and an exit is found by its pid (an unknown pid is nobody's).
TEST_F(SupervisorTest, AllAsksEveryActorWhereverItLastStopped) {
  std::set<std::string> done;
  auto all_done = [&] { return sup->all([&](const ActorRecord& a) { return done.count(a.name()) > 0; }); };
  std::vector<std::string> names;
  for (const auto& [name, a] : sup->actors())
    if (a.spec->has_process()) names.push_back(name);
  ASSERT_GE(names.size(), 3u);
  done.insert(names.begin(), names.end());
  done.erase(names[1]);
  EXPECT_FALSE(all_done());  // stops at names[1]
  done.insert(names[1]);
  done.erase(names[0]);
  EXPECT_FALSE(all_done()) << "the actor before the last stop is still asked";
  done.insert(names[0]);
  EXPECT_TRUE(all_done());
  EXPECT_TRUE(sup->on_exit(ExitReport{987654, status_exited(1)}).ok()) << "no actor has that pid";
  EXPECT_FALSE(sup->may_still_speak(987654));
  EXPECT_TRUE(sup->may_still_speak(pid(names[0])));
}

TEST_F(SupervisorTest, ALostReplicaGoesToItsPoolAndTheLastOneStopsTheFarm) {
  hello_all();
  sup->actors().at("direct").configured = true;
  sup->set_stage(Stage::render);
  ASSERT_TRUE(sup->on_exit(ExitReport{pid("direct.0"), status_killed(SIGKILL)}).ok());
  // The services hear of the loss first, then whoever dispatches to the pool (its multiplexer).
  EXPECT_EQ(described(sup->take_events()),
            (std::vector<std::string>{"lost direct.0: was killed by signal 9 (Killed)", "peer_down direct.0 to direct"}));
  auto last = sup->on_exit(ExitReport{pid("direct.1"), status_exited(1)});
  ASSERT_FALSE(last.ok());
  EXPECT_EQ(last.error().message,
            "lost the last replica of 'direct': direct.0 was killed by signal 9 (Killed), direct.1 exited with status 1");
  // The multiplexer itself is no replica: its death is fatal.
  EXPECT_FALSE(sup->on_exit(ExitReport{pid("direct"), status_exited(1)}).ok());
}

TEST_F(SupervisorTest, LostRenderersAreRecoveredUntilNoneIsLeft) {
  hello_all();
  sup->set_stage(Stage::setup);
  ASSERT_TRUE(sup->on_exit(ExitReport{pid("renderer-1"), status_killed(SIGKILL)}).ok());
  EXPECT_EQ(events("lost").size(), 1u);
  auto all = sup->on_exit(ExitReport{pid("renderer-0"), status_killed(SIGKILL)});
  ASSERT_FALSE(all.ok());
  EXPECT_EQ(all.error().message,
            "every renderer was lost: renderer-0 was killed by signal 9 (Killed), renderer-1 was killed by signal 9 "
            "(Killed)");
}

TEST_F(SupervisorTest, SilentActorsAreKilledWhenRecoverableAndStopTheFarmOtherwise) {
  hello_all();
  sup->set_stage(Stage::render);
  const auto later = Clock::now() + std::chrono::seconds(2);
  // Everyone is silent: the renderers and replicas are killed first (in name order the multiplexer `direct` comes
  // first, and it cannot be recovered).
  auto st = sup->check_heartbeats(later);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message, "actor 'direct' has been silent for 1 s (missed heartbeats)");
  ASSERT_TRUE(say("direct", wire::make(MsgType::heartbeat, "direct")).ok());
  sup->actors().at("direct").last_seen = later;
  // Every actor is looked at a twentieth of the timeout apart (50 ms here), not at every turn of the loop.
  ASSERT_TRUE(sup->check_heartbeats(later + std::chrono::milliseconds(10)).ok());
  EXPECT_TRUE(fake->killed.empty());
  ASSERT_TRUE(sup->check_heartbeats(later + std::chrono::milliseconds(60)).ok());
  EXPECT_EQ(fake->killed.size(), 4u);  // direct.0, direct.1, renderer-0, renderer-1
  for (const auto& [p, sig] : fake->killed) EXPECT_EQ(sig, SIGKILL);
  // Its death then reads as a hang, not as the SIGKILL we sent.
  ASSERT_TRUE(sup->on_exit(ExitReport{pid("renderer-0"), status_killed(SIGKILL)}).ok());
  EXPECT_EQ(events("lost").back(), "lost renderer-0: stopped answering (no heartbeat for 1 s); it was killed");
}

TEST_F(SupervisorTest, InTheFinishStageACleanExitIsAnActorFinishing) {
  hello_all();
  sup->set_stage(Stage::finish);
  ASSERT_TRUE(sup->on_exit(ExitReport{pid("renderer-0"), status_exited(0)}).ok());
  EXPECT_TRUE(sup->at("renderer-0").said_bye);
  EXPECT_FALSE(sup->on_exit(ExitReport{pid("renderer-1"), status_exited(2)}).ok());
}

TEST(SupervisorNested, AnEmptiedInnerPoolIsALostReplicaOfTheOuterOne) {
  FarmSpec spec;
  PoolSpec inner;
  inner.op = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  auto in = replicate(spec, inner);
  PoolSpec outer;
  outer.op = *in;
  auto top = replicate(spec, outer);
  add_renderers(spec, 1, *top, RendererParams{}, {}, {});
  Launchers launchers;
  auto f = std::make_unique<FakeLauncher>();
  FakeLauncher* fake = f.get();
  launchers.set("local", std::move(f));
  Recorder out;
  Supervisor sup(spec, launchers, out);
  ASSERT_TRUE(sup.launch("tcp://d").ok());
  sup.set_stage(Stage::render);
  ASSERT_TRUE(sup.on_exit(ExitReport{sup.at("direct.0.0").pid, status_killed(SIGKILL)}).ok());
  ASSERT_TRUE(sup.on_exit(ExitReport{sup.at("direct.0.1").pid, status_killed(SIGKILL)}).ok());
  ASSERT_EQ(fake->killed.size(), 1u);
  EXPECT_EQ(fake->killed[0].first, sup.at("direct.0").pid);
  const auto events = described(sup.take_events());
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back(),
            "lost direct.0: lost every replica (direct.0.0 was killed by signal 9 (Killed), direct.0.1 was killed by "
            "signal 9 (Killed))");
  EXPECT_TRUE(sup.at("direct.0").lost);
}

// A ring node that dies during setup is started again with the same command (at most kMaxRestarts times); the
// services hear of the loss, and of the new process's HELLO and READY configure. Once the ring no longer needs it
// (the solution is in), a loss is just a loss.
TEST(SupervisorRing, ALostRingNodeIsRestartedUntilItsBudgetIsSpent) {
  FarmSpec spec;
  Value::Map params{{"rings", 1}, {"ring_length", 2}};
  const auto config = radiosity::read_ring_config(ParamTable(params, "radiosity"));
  ASSERT_TRUE(expand_ring(spec, config, params, "radiosity", {}, {}).ok());
  Launchers launchers;
  auto f = std::make_unique<FakeLauncher>();
  FakeLauncher* fake = f.get();
  launchers.set("local", std::move(f));
  Recorder out;
  std::vector<std::string> events;
  bool needed = true;
  Supervisor sup(spec, launchers, out, [&](const std::string&) { return needed; });
  ASSERT_TRUE(sup.launch("tcp://d").ok());
  const size_t launched = fake->started.size();
  const int node_index = sup.at("radiosity.0.1").index;
  sup.set_stage(Stage::setup);
  auto say = [&](const std::string& peer, wire::Message m) {
    Result<wire::Message> r(std::move(m));
    return sup.on_message(peer, r);
  };
  for (int round = 1; round <= Supervisor::kMaxRestarts; ++round) {
    sup.actors().at("radiosity.0.1").configured = true;  // as the director's CONFIG (first, or after hello again)
    const pid_t old = sup.at("radiosity.0.1").pid;
    ASSERT_TRUE(sup.on_exit(ExitReport{old, status_killed(SIGKILL)}).ok());
    ASSERT_EQ(fake->started.size(), launched + static_cast<size_t>(round));
    EXPECT_EQ(fake->started.back().argv, fake->started[static_cast<size_t>(node_index)].argv);  // the same command
    const ActorRecord& node = sup.at("radiosity.0.1");
    EXPECT_NE(node.pid, old);
    EXPECT_FALSE(node.lost || node.exited || node.said_hello);
    EXPECT_EQ(node.restarts, round);
    ASSERT_TRUE(say("radiosity.0.1", wire::make(MsgType::hello, "radiosity.0.1",
                                                my_hello("radiosity_node", "tcp://x:2").to_value())).ok());
    ASSERT_TRUE(say("radiosity.0.1", wire::make_ready("radiosity.0.1", wire::Phase::configure)).ok());
    for (auto& line : described(sup.take_events())) events.push_back(line);
  }
  EXPECT_EQ(events.size(), 3u * Supervisor::kMaxRestarts);
  EXPECT_EQ(events[0], "lost radiosity.0.1: was killed by signal 9 (Killed)");
  EXPECT_EQ(events[1], "hello again radiosity.0.1");
  EXPECT_EQ(events[2], "configured again radiosity.0.1");
  auto spent = sup.on_exit(ExitReport{sup.at("radiosity.0.1").pid, status_exited(1)});
  ASSERT_FALSE(spent.ok());
  EXPECT_EQ(spent.error().message,
            "ring node 'radiosity.0.1' exited with status 1 during setup, after 3 restarts; stopping the farm");

  // Not yet configured (a loss in the hello stage): started again, and it joins like the others.
  sup.set_stage(Stage::hello);
  ASSERT_TRUE(sup.on_exit(ExitReport{sup.at("radiosity.0.0").pid, status_killed(SIGKILL)}).ok());
  EXPECT_EQ(fake->started.size(), launched + Supervisor::kMaxRestarts + 1);
  EXPECT_FALSE(sup.at("radiosity.0.0").rejoining);
  EXPECT_TRUE(sup.take_events().empty());

  needed = false;
  sup.set_stage(Stage::render);
  ASSERT_TRUE(sup.on_exit(ExitReport{sup.at("radiosity.0.0").pid, status_killed(SIGKILL)}).ok());
  EXPECT_TRUE(sup.at("radiosity.0.0").lost);
  EXPECT_EQ(fake->started.size(), launched + Supervisor::kMaxRestarts + 1);
}

}  // namespace
}  // namespace lf
