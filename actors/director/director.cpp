#include "actors/director/director.hpp"

#include <sys/prctl.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "actors/codecs/control_codec.hpp"
#include "actors/director/actor_configs.hpp"
#include "actors/director/control_channel.hpp"
#include "actors/director/control_loop.hpp"
#include "actors/director/deployment.hpp"
#include "actors/director/exchange_service.hpp"
#include "actors/director/farm_failure.hpp"
#include "actors/director/frame_loop.hpp"
#include "actors/launchers/local_launcher.hpp"
#include "actors/director/monitor_feed.hpp"
#include "actors/director/progress.hpp"
#include "actors/director/report.hpp"
#include "actors/director/ring_service.hpp"
#include "actors/director/service_router.hpp"
#include "actors/director/supervisor.hpp"
#include "actors/director/tile_service.hpp"
#include "actors/runtime/process.hpp"
#include "core/log.hpp"
#include "core/private_dir.hpp"
#include "render/images/image.hpp"

namespace lf {
namespace {

using wire::MsgType, wire::Phase;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class Director {
 public:
  Director(const FarmSpec& spec, const RunOptions& options, Launchers& launchers)
      : spec_(spec),
        options_(options),
        launchers_(launchers),
        supervisor_(spec_, launchers_, control_, [this](const std::string& a) { return services_.needs_restart(a); }),
        tiles_(spec.image, spec.renderer_names(), options.progress_on_terminal, options.quiet),
        frames_(spec_, tiles_, exchange_, control_, options_),
        ring_(spec_, exchange_, options.quiet, options.progress_on_terminal),
        loop_(spec_, control_, supervisor_, launchers_, [this](SupervisorEvent& e) { route(e); }),
        step_progress_(options.quiet) {}

  int run() {
    install_stop_signals();
    install_suspend_signal();
    // Orphans of actors (a daemonised grandchild) become ours, so that kill_orphans() can end them.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    if (!options_.monitor.empty()) {
      auto feed = MonitorFeed::start(options_.monitor, spec_, supervisor_, tiles_, ring_, timeline_, frames_);
      if (!feed) return log_error(feed.error().message), 2;
      monitor_ = std::move(*feed);
    }
    int status = 0;
    try {
      run_stages();
    } catch (const FarmFailure& f) {
      if (tiles_.drawing_progress()) std::fprintf(stderr, "\n");
      tiles_.save_checkpoint();  // what is done stays done for the next run
      // With the image whole and in place, the farm's work is done: only the actors' goodbyes were cut short.
      if (timeline_.image_written) log_warn(f.message + " after the image was written");
      else log_error(f.message), status = f.status;
    } catch (const std::bad_alloc&) {
      if (tiles_.drawing_progress()) std::fprintf(stderr, "\n");
      log_error("out of memory (the image is " + std::to_string(spec_.image.width) + "x" +
                std::to_string(spec_.image.height) + "); stopping the farm");
      status = 1;
    }
    // No actor outlives the farm, whatever happened above. Host agents leave once their actors have exited (a Slurm
    // step killed from outside is cancelled with them); one left after the grace (none if no actor began) is stopped.
    supervisor_.send_bye_to_all();
    launchers_.stop_all(std::chrono::milliseconds(frames_.nothing_left() ? 0 : status == 0 ? 3000 : 300));
    kill_orphans();
    // An actor removes its IPC folder when it exits; one that was killed cannot. Every actor here is reaped by now.
    sweep_stale_private_dirs("actor");
    if (status == 0) status = report();
    if (monitor_) monitor_->hold(options_.monitor_hold, options_.quiet, status);
    return status;
  }

 private:
  void run_stages() {
    stage(Stage::prepare, [&] { prepare(); });  // timed: the director's own scene load shows in the table
    if (frames_.nothing_left()) return;         // a job whose every frame is done already
    stage(Stage::launch, [&] {
      std::function<std::string(const ActorSpec&)> keys_of;
      if (deployment_.curve()) keys_of = [&](const ActorSpec& a) { return deployment_.keys_line_for(a.name); };
      check(supervisor_.launch(control_endpoint_, deployment_.local_address, keys_of));
    });
    stage(Stage::hello, [&] { wait_all(30.0, [](const ActorRecord& a) { return a.said_hello; }); });
    stage(Stage::configure, [&] {
      for (auto& [name, a] : supervisor_.actors())
        if (!a.lost && a.spec->has_process()) configure_actor(a);
      wait_all(60.0, [](const ActorRecord& a) { return a.ready == Phase::configure; });
    });
    stage(Stage::setup, [&] { run_phase(Phase::setup); });
    stage(Stage::render, [&] {
      render_start_ = Clock::now();
      frames_.run({[&](Phase phase, Value::Map body) { run_phase(phase, std::move(body)); },
                   [&](const std::function<bool()>& done) { render_until(done); }, [&] { end_render(); }});
      timeline_.image_written = true;
    });
    stage(Stage::finish, [&] { finish(); });
  }

  template <class Fn>
  void stage(Stage s, Fn&& fn) {
    const auto t = Clock::now();
    const double cpu = process_cpu_seconds();
    supervisor_.set_stage(s);
    if (monitor_) monitor_->update(true);  // a watching page sees each stage as it begins
    fn();
    timeline_.stage_seconds.emplace_back(std::string(stage_name(s)), seconds_since(t));
    timeline_.stage_cpu_seconds.push_back(process_cpu_seconds() - cpu);
    // As it passes (LIGHTFARM_DEBUG): a farm that fails later never writes its stats file.
    log_debug("stage " + timeline_.stage_seconds.back().first + ": " + seconds_text(timeline_.stage_seconds.back().second) +
              ", director CPU " + seconds_text(timeline_.stage_cpu_seconds.back()));
  }

  void prepare() {
    // An output that cannot be written is a bad command line or script (exit 2), found before anything starts.
    if (auto st = check_output_path(spec_.image.output); !st) throw FarmFailure{st.error().message, 2};
    Deployer deployer(spec_, launchers_, options_.quiet);  // remote hosts connect while the scene loads here
    const Scene scene = load_checked_scene(spec_, options_.quiet);
    deployer.ship(scene);  // host agents build their BVH while this process checks the lights
    warn_about_escaping_light(spec_, scene);
    deployment_ = deployer.finish(scene);
    supervisor_.set_host_agents(deployment_.agent_sockets);
    frames_.prepare(deployment_.scene_hash);  // sets spec_.camera, every actor's CONFIG, to the first frame's
    if (ring_.active()) check(ring_.prepare(scene));
    auto endpoint = control_.open(deployment_, heartbeat_interval(spec_.heartbeat_timeout));
    if (!endpoint) throw FarmFailure{endpoint.error().message};
    control_endpoint_ = *endpoint;
  }

  void configure_actor(ActorRecord& a) {
    const ActorConfig config = ConfigBuilder(spec_, deployment_).build(a, supervisor_.actors());
    control_.send(a.name(), wire::make(MsgType::config, "director", config.to_value()));
    a.configured = true;
  }

  // All the supervisor says goes on from here: requests and losses to the services, PEER_DOWN to a lost replica's
  // dispatchers, a restarted actor's CONFIG and return, progress to the terminal and the monitor.
  void route(SupervisorEvent& e) {
    using Kind = SupervisorEvent::Kind;
    switch (e.kind) {
      case Kind::request: return check(services_.request(e.actor, e.message, control_));
      case Kind::lost: return check(services_.lost(e.actor, e.why, control_));
      case Kind::peer_down: return control_.tell(e.to, MsgType::peer_down, control::encode_peer_down(e.actor));
      case Kind::hello_again: return configure_actor(supervisor_.actors().at(e.actor));
      case Kind::configured_again: return check(rejoin(supervisor_.actors().at(e.actor)));
      case Kind::progress:
        if (monitor_) monitor_->on_progress(e.actor, e.what, e.done, e.total);
        return step_progress_.report(e.actor, e.what, e.done, e.total, tiles_.drawing_progress());
    }
  }

  // A restarted actor is configured: every configured actor that has it as an input learns where it listens now,
  // the services take it back (the ring rolls back once all its restarted nodes are here), and it joins the phase
  // under way.
  Status rejoin(ActorRecord& moved) {
    for (auto& [to, body] : ConfigBuilder(spec_, deployment_).peer_moved(moved, supervisor_.actors()))
      control_.tell(to, MsgType::peer_moved, std::move(body));
    if (auto st = services_.rejoined(moved.name(), control_); !st) return st;
    if (supervisor_.stage() >= Stage::setup) control_.send(moved.name(), wire::make_phase("director", Phase::setup));
    if (supervisor_.stage() >= Stage::render) control_.send(moved.name(), wire::make_phase("director", Phase::render));
    return Ok{};
  }

  // PHASE to everyone, then wait for every READY of it. Setup (and a job's frame) takes what it takes. Render is
  // awaited apart (render_until, end_render): a job's next frame may begin while it goes on.
  void run_phase(Phase phase, Value::Map body = {}) {
    supervisor_.broadcast(wire::make_phase("director", phase, std::move(body)));
    check(services_.phase(phase, control_));
    // READY frame only says the view is taken (docs/PROTOCOL.md): an actor silent for a minute never will say it.
    if (phase == Phase::frame) return wait_all(60.0, [](const ActorRecord& a) { return a.ready == Phase::frame; });
    // A READY sent before a rollback counts for nothing: the services say when the phase's work is really in.
    while (phase != Phase::render &&
           (!services_.phase_complete(phase) || !supervisor_.all([phase](const ActorRecord& a) { return a.ready == phase; })))
      pump(100);
  }

  // Every renderer said READY render (every tile is done); every actor, which had PHASE render, must say it too.
  void end_render() {
    const auto said = [](const ActorRecord& a) { return a.ready == Phase::render; };
    render_until([&] { return supervisor_.all([&](const ActorRecord& a) { return !a.spec->is_renderer() || said(a); }); });
    for (const auto deadline = Clock::now() + std::chrono::seconds(kReadyRenderGraceSeconds); !supervisor_.all(said); pump(100))
      if (Clock::now() > deadline)
        throw FarmFailure{"every tile is done, but " + supervisor_.late(said) + " never answered PHASE render with "
                          "READY render (every actor must; docs/PROTOCOL.md, \"Life of an actor\")"};
  }

  void render_until(const std::function<bool()>& done) {
    for (auto last_report = Clock::now(); !done();) {
      pump(100);
      // A frame that makes no progress for a long while says, every so often, what it is waiting on: who holds
      // which tiles and what each actor has in flight. It changes nothing; a stall is then diagnosable.
      if (tiles_.seconds_since_progress() < kStallReportSeconds || seconds_since(last_report) < kStallReportSeconds)
        continue;
      last_report = Clock::now();
      log_warn(tiles_.stall_report(supervisor_.in_flight()));
    }
  }
  static constexpr int kReadyRenderGraceSeconds = 5;
  static constexpr double kStallReportSeconds = 30;

  void finish() {
    supervisor_.broadcast(wire::make_phase("director", Phase::finish));
    // Wait for every actor's STATS and BYE, and for its process to end.
    for (const auto deadline = Clock::now() + std::chrono::seconds(10); Clock::now() < deadline; pump(50))
      if (supervisor_.all([](const ActorRecord& a) { return a.said_bye && a.exited; })) return;
    log_warn("some actors did not stop within 10 s; stopping them");
  }

  // Processes control messages and exits until every actor satisfies `done`.
  template <class Pred>
  void wait_all(double timeout_seconds, Pred done) {
    for (const auto start = Clock::now(); !supervisor_.all(done); pump(100))
      if (timeout_seconds > 0 && seconds_since(start) > timeout_seconds)
        throw FarmFailure{"timed out after " + seconds_text(timeout_seconds) + " waiting for " + supervisor_.late(done) +
                          " in phase " + std::string(stage_name(supervisor_.stage()))};
  }

  void pump(long timeout_ms) {
    // OpenImageIO's load (formats other than .exr and .png: 0.4-0.6 CPU-s) runs beside the render once a tile is in:
    // not with the actors' start-up, which it slowed, nor after the last tile, adding to every frame. dlopen holds the
    // loader's lock, which creating a thread needs: by now this process has its threads (ZeroMQ's, ZAP, hosts).
    if (!image_io_.joinable() && tiles_.tiles_done() > 0) image_io_ = std::jthread(preload_image_writer, spec_.image.output);
    loop_.turn(timeout_ms);
    if (monitor_) monitor_->update(false);
  }

  // The tables, and the stats file if asked for; 1 when that file cannot be written (the image is there, but what
  // was asked for is not).
  int report() {
    RunFigures f;
    f.stage_seconds = timeline_.stage_seconds;
    f.stage_cpu_seconds = timeline_.stage_cpu_seconds;
    f.total_seconds = timeline_.seconds();
    f.render_seconds = tiles_.render_seconds();
    frames_.add_figures(f);
    f.first_tile_seconds = std::chrono::duration<double>(render_start_ - timeline_.start).count() + tiles_.first_tile_seconds();
    if (ring_.active()) f.radiosity = ring_.report();
    f.scene = deployment_.scene_figures();
    if (!options_.quiet) print_report(spec_, supervisor_, f);
    if (!options_.stats_json.empty())
      if (auto st = write_stats_json(spec_, supervisor_, f, options_.stats_json); !st) return log_error(st.error().message), 1;
    return 0;
  }

  FarmSpec spec_;  // the script's, with the first frame's camera once prepared
  RunOptions options_;
  FarmTimeline timeline_;
  Launchers& launchers_;
  std::jthread image_io_;    // loads the image writer beside the render (pump)
  Deployment deployment_;    // declared before the control socket, whose CURVE handshakes its authenticator serves
  ControlChannel control_;
  std::string control_endpoint_;
  Supervisor supervisor_;
  TileService tiles_;
  FrameLoop frames_;
  ExchangeService exchange_;
  RingService ring_;
  ServiceRouter services_{&tiles_, &exchange_, &ring_, &frames_.carried_setups()};
  ControlLoop loop_;
  StepProgress step_progress_;
  Clock::time_point render_start_;
  std::unique_ptr<MonitorFeed> monitor_;  // declared last: it goes first, before what its state reads
};

}  // namespace

int run_farm(const FarmSpec& spec, const RunOptions& options, Launchers& launchers) {
  // Folders an earlier director or actor here could not remove (it was SIGKILLed) go before this farm starts.
  sweep_stale_private_dirs("ssh");
  sweep_stale_private_dirs("actor");
  try {
    return Director(spec, options, launchers).run();
  } catch (const std::bad_alloc&) {
    // The film is allocated before any actor starts: nothing to stop yet.
    log_error("out of memory for a " + std::to_string(spec.image.width) + "x" + std::to_string(spec.image.height) +
              " image; nothing was rendered");
    return 1;
  }
}

int run_farm(const FarmSpec& spec, const RunOptions& options) {
  Launchers launchers;
  return run_farm(spec, options, launchers);
}

}  // namespace lf
