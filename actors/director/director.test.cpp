// The director as a sequencer, with no process started: a launcher that runs each actor's real runtime on a thread
// of this test (the kinds' own code, over TCP on loopback) drives whole frames through every stage, and frames that
// fail at each stage end with the message and exit status a user would see.
#include "actors/director/director.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

#include "actors/launchers/launcher.hpp"
#include "actors/kinds/actor_kinds.hpp"
#include "actors/runtime/runtime.hpp"
#include "farm/builders.hpp"
#include "render/images/image.hpp"

namespace lf {
namespace {

namespace fs = std::filesystem;

// Starts `lightfarm actor --kind K --name N --director EP` as Runtime(args).run(make_actor(K)) on a thread. A pid is
// a handle; an actor's exit is its thread's end; a kill is Runtime::stop (its run ends at its next turn, 143).
class ThreadLauncher final : public Launcher {
 public:
  std::set<std::string> refuse_kinds;  // start() fails for these, as for a program that is not there
  std::set<std::string> fail_kinds;    // these exit with status 3 before they say HELLO
  std::set<std::string> late_kinds;    // these start 300 ms late (after a failing farm has sent its BYEs)
  std::vector<std::string> started;    // NAME (KIND), in order
  std::vector<pid_t> killed;
  int still_running_after_stop = 0;  // threads that ended only when stopped after the grace

  ~ThreadLauncher() override {
    for (auto& [pid, r] : running_)
      if (r->thread.joinable()) r->thread.join();
  }
  std::string name() const override { return "threads"; }
  Result<Shipped> ship(const std::string&, const std::string&) override { return make_error("no scene files here"); }
  Result<pid_t> start(const LaunchRequest& request) override {
    std::map<std::string, std::string> opt;
    for (size_t i = 2; i + 1 < request.argv.size(); i += 2) opt[request.argv[i].substr(2)] = request.argv[i + 1];
    ActorArgs args{opt["kind"], opt["name"], opt["director"]};
    if (refuse_kinds.count(args.kind)) return make_error("no such program");
    started.push_back(args.name + " (" + args.kind + ")");
    auto run = std::make_shared<Running>();
    const bool fail = fail_kinds.count(args.kind) > 0, late = late_kinds.count(args.kind) > 0;
    run->thread = std::thread([args, run, fail, late] {
      if (late) std::this_thread::sleep_for(std::chrono::milliseconds(300));
      if (!fail) {
        auto actor = make_actor(args.kind);
        Runtime rt(args);
        {
          std::lock_guard<std::mutex> lock(run->mutex);
          if (run->stop_asked) rt.stop();
          run->runtime = &rt;
        }
        run->status = rt.run(*actor);
        std::lock_guard<std::mutex> lock(run->mutex);
        run->runtime = nullptr;
      } else {
        run->status = 3;
      }
      run->done = true;
    });
    running_[++next_pid_] = run;
    return next_pid_;
  }
  std::optional<ExitReport> reap_one() override {
    for (auto it = running_.begin(); it != running_.end(); ++it)
      if (it->second->done) {
        it->second->thread.join();
        const ExitReport exit{it->first, it->second->status << 8};
        running_.erase(it);
        return exit;
      }
    return std::nullopt;
  }
  bool all_ended() const { return running_.empty(); }
  void kill(pid_t pid, int) override {
    killed.push_back(pid);
    if (auto it = running_.find(pid); it != running_.end()) it->second->stop();
  }
  void stop_all(std::chrono::milliseconds grace) override {
    const auto until = std::chrono::steady_clock::now() + grace;
    while (std::chrono::steady_clock::now() < until) {
      while (reap_one()) {
      }
      if (running_.empty()) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    // As a launcher sends SIGTERM after the grace: the rest are stopped, and end.
    still_running_after_stop = static_cast<int>(running_.size());
    for (auto& [pid, run] : running_) kill(pid, SIGTERM);
    while (reap_one() || !running_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }

 private:
  struct Running {
    std::thread thread;
    std::atomic<bool> done{false};
    int status = 0;
    std::mutex mutex;              // guards runtime, which lives on the thread's stack
    Runtime* runtime = nullptr;    // while it runs
    bool stop_asked = false;
    void stop() {
      std::lock_guard<std::mutex> lock(mutex);
      stop_asked = true;
      if (runtime) runtime->stop();
    }
  };
  std::map<pid_t, std::shared_ptr<Running>> running_;
  pid_t next_pid_ = 1000;
};

struct DirectorTest : ::testing::Test {
  fs::path dir = fs::temp_directory_path() / ("director-test-" + std::to_string(::getpid()));
  FarmSpec spec;
  Launchers launchers;
  ThreadLauncher* threads = nullptr;
  RunOptions options;

  // The built-in Cornell box, 32 x 32 at 2 spp, two renderers asking one `direct`.
  void SetUp() override {
    fs::create_directories(dir);
    spec.scene.builtin = "cornell";
    spec.image.width = spec.image.height = 32;
    spec.image.spp = 2;
    spec.image.tile = 8;
    spec.image.output = (dir / "frame.exr").string();
    spec.security = "none";
    spec.heartbeat_timeout = 5;
    const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
    add_renderers(spec, 2, direct, RendererParams{}, {}, {});
    auto fake = std::make_unique<ThreadLauncher>();
    threads = fake.get();
    launchers.set("local", std::move(fake));
    options.quiet = true;
    options.stats_json = (dir / "stats.json").string();
  }
  void TearDown() override { fs::remove_all(dir); }

  int run(std::string& err) {
    testing::internal::CaptureStderr();
    const int status = run_farm(spec, options, launchers);
    err = testing::internal::GetCapturedStderr();
    return status;
  }
};

TEST_F(DirectorTest, AFrameRunsThroughEveryStageAndEveryActorEnds) {
  std::string err;
  ASSERT_EQ(run(err), 0) << err;
  EXPECT_EQ(threads->started, (std::vector<std::string>{"direct (direct)", "renderer-0 (renderer)", "renderer-1 (renderer)"}));
  EXPECT_TRUE(threads->killed.empty());
  EXPECT_EQ(threads->still_running_after_stop, 0);  // every actor ended on its own, after BYE
  auto image = read_image(spec.image.output);
  ASSERT_TRUE(image.ok()) << image.error().message;
  ASSERT_EQ(image->width, 32);
  double sum = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) sum += image->at(x, y)[0] + image->at(x, y)[1] + image->at(x, y)[2];
  EXPECT_GT(sum / (32 * 32 * 3), 0.01);  // lit: the direct light reached the camera through the network
  // The report times every stage.
  std::ifstream in(options.stats_json);
  const std::string json((std::istreambuf_iterator<char>(in)), {});
  const std::string phases = json.substr(json.find("\"phases_seconds\""));
  for (const char* stage : {"prepare", "launch", "hello", "configure", "setup", "render", "finish"})
    EXPECT_NE(phases.find("\"" + std::string(stage) + "\": "), std::string::npos) << stage << " in " << json;
}

TEST_F(DirectorTest, TheSameFrameComesOutWhicheverRendererTookWhichTile) {
  std::string err;
  ASSERT_EQ(run(err), 0) << err;
  auto one = read_image(spec.image.output);
  ASSERT_TRUE(one.ok());
  // Four renderers now: tiles land in another order on other actors; the pixels are seeded per pixel and sample.
  FarmSpec four = spec;
  four.actors.resize(1);
  add_renderers(four, 4, 0, RendererParams{}, {}, {});
  four.image.output = (dir / "four.exr").string();
  spec = four;
  Launchers again;
  auto fake = std::make_unique<ThreadLauncher>();
  again.set("local", std::move(fake));
  testing::internal::CaptureStderr();
  const int status = run_farm(spec, options, again);
  err = testing::internal::GetCapturedStderr();
  ASSERT_EQ(status, 0) << err;
  auto other = read_image(spec.image.output);
  ASSERT_TRUE(other.ok());
  EXPECT_EQ(one->pixels, other->pixels);
}

TEST_F(DirectorTest, AnOutputThatCannotBeWrittenStopsTheFarmBeforeAnythingStarts) {
  spec.image.output = (dir / "no-such-folder" / "frame.exr").string();
  std::string err;
  EXPECT_EQ(run(err), 2);
  EXPECT_NE(err.find("no-such-folder"), std::string::npos) << err;
  EXPECT_TRUE(threads->started.empty());
}

TEST_F(DirectorTest, AnActorThatCannotStartIsNamedAndTheOthersEnd) {
  threads->refuse_kinds = {"direct"};
  std::string err;
  EXPECT_EQ(run(err), 1);
  EXPECT_NE(err.find("cannot start actor 'direct': no such program"), std::string::npos) << err;
  EXPECT_TRUE(threads->all_ended());
  EXPECT_FALSE(fs::exists(spec.image.output));
}

TEST_F(DirectorTest, AnActorThatExitsBeforeHelloIsNamedWithItsStatus) {
  threads->fail_kinds = {"direct"};
  threads->late_kinds = {"renderer"};  // they say HELLO to a farm that has already failed
  std::string err;
  EXPECT_EQ(run(err), 1);
  EXPECT_NE(err.find("actor 'direct' (pid 1001) exited with status 3 during start-up"), std::string::npos) << err;
  EXPECT_TRUE(threads->all_ended());  // those that said HELLO after the BYEs went are stopped
  EXPECT_EQ(threads->still_running_after_stop, 2);
  EXPECT_FALSE(fs::exists(spec.image.output));
}

}  // namespace
}  // namespace lf
