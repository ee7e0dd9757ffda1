#include "actors/director/director.hpp"

#include <sys/prctl.h>
#include <unistd.h>

#include <array>
#include <deque>
#include <mutex>
#include <cmath>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <thread>

#include "actors/director/actor_configs.hpp"
#include "actors/director/exchange_service.hpp"
#include "actors/director/launcher.hpp"
#include "actors/director/local_launcher.hpp"
#include "actors/director/monitor.hpp"
#include "actors/director/report.hpp"
#include "actors/director/ring_service.hpp"
#include "farm/light_path_check.hpp"
#include "render/light_checks.hpp"
#include "render/lightop_registry.hpp"
#include "actors/director/supervisor.hpp"
#include "actors/director/tile_service.hpp"
#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/runtime.hpp"
#include "farm/builders.hpp"
#include "core/log.hpp"
#include "core/private_dir.hpp"
#include "render/camera.hpp"
#include "render/image.hpp"
#include "render/partition.hpp"
#include "render/scene.hpp"
#include "render/scene_file.hpp"
#include "transport/security.hpp"
#include "transport/socket.hpp"

namespace lf {
namespace {

using wire::MsgType;
using wire::Phase;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Thrown inside the director to end the farm: a message and the exit status.
struct FarmFailure {
  std::string message;
  int status = 1;
};

void check(const Status& st) {
  if (!st) throw FarmFailure{st.error().message};
}

std::vector<std::string> renderers_of(const FarmSpec& spec) {
  std::vector<std::string> names;
  for (const auto& a : spec.actors)
    if (a.is_renderer()) names.push_back(a.name);
  return names;
}

class Director final : public ControlOut, public Outbox {
 public:
  Director(const FarmSpec& spec, const RunOptions& options)
      : spec_(spec),
        options_(options),
        supervisor_(spec, launchers_, *this,
                    Supervisor::Events{[this](ActorRecord& a, wire::Message& m) { return dispatch(a, m); },
                                       [this](ActorRecord& a, const std::string& why) { return lost(a, why); },
                                       [this](const ActorRecord& a) { return needs_restart(a); },
                                       [this](ActorRecord& a) { return configure_actor(a); },
                                       [this](ActorRecord& a) { return rejoin(a); },
                                       [this](const ActorRecord& a, const std::string& what, uint64_t done,
                                              uint64_t total) { show_progress(a, what, done, total); }}),
        tiles_(spec.image, renderers_of(spec), options.progress_on_terminal, options.quiet),
        ring_(spec, exchange_, options.quiet, options.progress_on_terminal) {
    for (Service* s : all_services_)
      for (wire::Op op : s->ops()) services_[op] = s;
  }

  int run() {
    install_stop_signals();
    install_suspend_signal();
    // Orphans of actors (a daemonised grandchild) become ours, so that kill_orphans() can end them.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
    start_ = Clock::now();
    int status = 0;
    if (!options_.monitor.empty()) {
      auto m = Monitor::start(options_.monitor);
      if (!m) {
        log_error(m.error().message);
        return 2;
      }
      monitor_ = std::move(*m);
      set_log_observer([this](const std::string& level, const std::string& text) { keep_log_line(level, text); });
      log_info("monitor: " + monitor_->url());
      publish_monitor(true);
    }
    struct StopObserving {
      bool on;
      ~StopObserving() {
        if (on) set_log_observer({});
      }
    } stop_observing{monitor_ != nullptr};
    struct Join {
      std::thread& t;
      ~Join() {
        if (t.joinable()) t.join();
      }
    } join_image_io{image_io_};
    try {
      // Timed: the director's own scene load (an OBJ's parse, its checks, a radiosity plan) shows in the table.
      stage(Stage::prepare, [&] { prepare(); });
      stage(Stage::launch, [&] {
        std::function<std::string(const ActorSpec&)> keys_of;
        if (!actor_keys_.empty()) keys_of = [&](const ActorSpec& a) { return farm_keys_for(a.name); };
        check(supervisor_.launch(control_endpoint_, local_address_, keys_of));
      });
      stage(Stage::hello, [&] { wait_all(30.0, [](const ActorRecord& a) { return a.said_hello; }); });
      stage(Stage::configure, [&] {
        configure();
        wait_all(60.0, [](const ActorRecord& a) { return a.ready == Phase::configure; });
      });
      stage(Stage::setup, [&] { run_phase(Phase::setup); });
      stage(Stage::render, [&] {
        render_start_ = Clock::now();
        run_phase(Phase::render);
        tiles_.finish_progress();
        render_seconds_ = tiles_.render_seconds();
        if (!tiles_.finished()) throw FarmFailure{"the renderers stopped before every tile was done"};
      });
      stage(Stage::finish, [&] { finish(); });
    } catch (const FarmFailure& f) {
      if (tiles_.drawing_progress()) std::fprintf(stderr, "\n");
      if (image_written_) {
        // The image is whole and in place: the farm's work is done, only the actors' goodbyes were cut short (a
        // signal, or an actor or its host that did not end cleanly).
        log_warn(f.message + " after the image was written");
      } else {
        log_error(f.message);
        status = f.status;
      }
    } catch (const std::bad_alloc&) {
      if (tiles_.drawing_progress()) std::fprintf(stderr, "\n");
      log_error("out of memory (the image is " + std::to_string(spec_.image.width) + "x" +
                std::to_string(spec_.image.height) + "); stopping the farm");
      status = 1;
    }
    if (hosts_connected_.valid()) hosts_connected_.wait();  // a farm that failed before launch: hosts still connecting
    // No actor outlives the farm, whatever happened above.
    supervisor_.send_bye_to_all();
    // Host agents leave by themselves once their actors have exited (a Slurm step killed from outside would be
    // cancelled with them); one still there after the grace is stopped like an actor.
    launchers_.stop_all(std::chrono::milliseconds(status == 0 ? 3000 : 300));
    kill_orphans();
    // An actor removes its IPC folder when it exits; one that was killed cannot. Every actor here is reaped by now.
    sweep_stale_private_dirs("actor");
    if (status == 0) status = report();
    if (monitor_) hold_monitor(status);
    return status;
  }

  // ControlOut and Outbox: everything leaves through the control socket.
  void tell(const std::string& actor, wire::MsgType type, Value body) override {
    send(actor, wire::make(type, "director", std::move(body)));
  }
  void send(const std::string& actor, wire::Message m) override {
    m.header.sender = "director";
    if (!control_.send_to(actor, m)) log_debug("could not send to '" + actor + "'");
  }
  void reply(const std::string& actor, uint64_t id, Value body) override {
    send(actor, wire::make_reply("director", id, std::move(body)));
  }
  void refuse(const std::string& actor, uint64_t id, ErrorCode code, const std::string& message) override {
    send(actor, wire::make_error_reply("director", id, code, message));
  }

 private:
  template <class Fn>
  void stage(Stage s, Fn&& fn, bool timed = true) {
    const auto t = Clock::now();
    supervisor_.set_stage(s);
    if (monitor_) publish_monitor(true);  // a watching page sees each stage as it begins
    fn();
    if (timed) stage_seconds_.emplace_back(std::string(stage_name(s)), seconds_since(t));
  }

  void prepare() {
    // An output that cannot be written is a bad command line or script (exit 2), found before anything starts.
    if (auto st = check_output_path(spec_.image.output); !st) throw FarmFailure{st.error().message, 2};
    // Remote hosts are connected to (ssh's key exchange, the check for lightfarm there) while the scene loads here:
    // on a real scene the two take similar time. Joined before launch, and before anything else touches launchers_.
    if (spec_.has_remote_hosts())
      hosts_connected_ = std::async(std::launch::async, [this] { return launchers_.prepare(spec_.hosts_in_use()); });
    // The director reads the scene once itself, so a broken scene stops the farm before anything launches.
    if (!spec_.scene.file.empty())
      if (auto catalogue = Scene::catalogue_obj(spec_.scene.file))
        for (const auto& warning : catalogue->warnings) log_warn(warning);
    const auto load_start = Clock::now();
    auto scene = Scene::load(spec_.scene);
    if (!scene) throw FarmFailure{spec_.scene.loc.str() + ": " + scene.error().message};
    if (const double took = seconds_since(load_start); took >= 1.0 && !options_.quiet)
      log_info("scene: read " + spec_.scene.file + " (" + std::to_string(scene->triangle_count()) + " triangles) in " +
               seconds_text(std::round(took * 10) / 10));
    // Light counted twice or left out by the network, for this scene's materials: a script error, before launch.
    const LightPathReport paths = check_light_paths(spec_, scene_lobes(*scene));
    for (const auto& warning : paths.warnings) log_warn(warning);
    if (!paths.errors.empty()) throw FarmFailure{paths.error_text(), 2};
    // A scene from a file travels to the hosts in its binary form; actors never parse the OBJ themselves. It is
    // shipped, and each host's agent started, before the checks below: an agent builds its BVH while this process
    // checks the lights. Lost Empire on one host: an actor's start 0.41 -> 0.24 s (6 replicas, scene_share_bench),
    // launch to first tile 1.70 -> 1.32 s (8 replicas and 3 renderers, medians of 5 interleaved runs).
    if (!spec_.scene.file.empty()) {
      scene_bytes_ = scene_to_bytes(*scene);
      scene_hash_ = content_hash(scene_bytes_);
    }
    if (hosts_connected_.valid())
      if (auto st = hosts_connected_.get(); !st) throw FarmFailure{"cannot start the farm: " + st.error().message};
    ship_scene();
    start_host_agents();
    // Lights whose flux mostly meets nothing: a quad wound away from the room, a light outside the geometry.
    std::vector<std::string> point_labels;
    for (const Value& l : spec_.scene.lights)
      if (l.find("point"))
        point_labels.push_back(l.find("at") && l.find("at")->is_string() ? l.find("at")->as_string() + ": light"
                                                                         : "a script's point light");
    auto escapes = light_escapes(*scene, point_labels);
    for (auto& e : escapes)
      if (e.light.rfind("material '", 0) == 0 && !spec_.scene.file.empty()) e.light = spec_.scene.file + ": " + e.light;
    for (const auto& warning : escaping_light_warnings(escapes)) log_warn(warning);
    if (spec_.partition_parts > 0) split_scene(*scene);
    if (ring_.active()) {
      check(ring_.prepare(*scene));
      if (!ring_.ply_path().empty()) {
        const auto dir = std::filesystem::path(ring_.ply_path()).parent_path();
        if (::access(dir.c_str(), W_OK) != 0)
          throw FarmFailure{"radiosity: cannot write '" + ring_.ply_path() + "': folder '" + dir.string() +
                            "' does not exist or is not writable"};
      }
    }
    // A farm on one machine talks over loopback; one that spans hosts listens where they all reach it.
    if (spec_.has_remote_hosts()) {
      auto address = director_address();
      if (!address) throw FarmFailure{address.error().message};
      local_address_ = *address;
    }
    if (spec_.security == "curve") make_keys();
    auto endpoint = control_.bind("tcp://" + (local_address_.empty() ? std::string("127.0.0.1") : local_address_) + ":*");
    if (!endpoint) throw FarmFailure{endpoint.error().message};
    control_endpoint_ = *endpoint;
    control_.set_linger_ms(0);
  }

  // Where the remote hosts reach this machine: farm { director_address }, or the source address of the route to
  // the first remote host.
  Result<std::string> director_address() const {
    if (!spec_.director_address.empty()) return spec_.director_address;
    for (const auto& a : spec_.actors) {
      const HostSpec* h = spec_.host_of(a);
      if (!h || !h->remote()) continue;
      auto source = wire::local_address_towards(h->address);
      if (!source) return make_error("host '" + h->name + "': " + source.error().message + " (set farm { director_address })");
      return source;
    }
    return std::string("127.0.0.1");
  }

  // Every host that runs an actor gets the scene once (its cache may have it already); hosts connect in parallel.
  void ship_scene() {
    if (scene_bytes_.empty()) return;
    const auto hosts = spec_.hosts_in_use();
    if (auto st = launchers_.prepare(hosts); !st) throw FarmFailure{"cannot start the farm: " + st.error().message};
    for (const HostSpec* h : hosts) {
      auto launcher = launchers_.for_host(*h);
      if (!launcher) throw FarmFailure{launcher.error().message};
      auto shipped = (*launcher)->ship(scene_bytes_, scene_hash_);
      if (!shipped) throw FarmFailure{"cannot start the farm: " + shipped.error().message};
      scene_paths_[h->name] = shipped->path;
      scene_sent_[h->name] = shipped->bytes_sent;
    }
  }

  // A host with two or more scene-loading actors gets a host agent: the scene's BVH is built once there and shared
  // by the actors it forks (actors/runtime/host_agent.hpp). An agent that cannot start is only a warning: the
  // actors then load the scene themselves.
  void start_host_agents() {
    if (scene_bytes_.empty() || !spec_.host_agents) return;
    std::map<std::string, int> loaders;
    for (const auto& a : spec_.actors)
      if (const HostSpec* h = spec_.host_of(a); h && a.loads_scene()) ++loaders[h->name];
    std::map<std::string, std::string> sockets;
    std::random_device random;
    for (const HostSpec* h : spec_.hosts_in_use()) {
      if (loaders[h->name] < 2) continue;
      char tag[17];
      std::snprintf(tag, sizeof tag, "%08x%08x", random(), random());
      const std::string socket = "lightfarm-agent-" + scene_hash_ + "-" + tag;
      LaunchRequest how;
      how.argv = {"lightfarm", "host-agent", "--scene", scene_paths_.at(h->name), "--hash", scene_hash_, "--socket", socket,
                  "--actors", std::to_string(loaders[h->name])};
      how.hold_stdin = true;
      auto pid = launchers_.start(*h, how);
      if (!pid) {
        log_warn("host '" + h->name + "': no host agent (" + pid.error().message + "); its actors load the scene themselves");
        continue;
      }
      sockets[h->name] = socket;
    }
    supervisor_.set_host_agents(std::move(sockets));
  }

  // CURVE: a keypair for the director and one for each actor; the director lets in only the actors' keys.
  void make_keys() {
    director_keys_ = wire::make_curve_keypair();
    if (director_keys_.public_key.empty()) throw FarmFailure{"cannot make CURVE keys (ZeroMQ built without CURVE?)"};
    std::set<std::string> allowed;
    for (const auto& a : spec_.actors)
      if (a.has_process()) allowed.insert((actor_keys_[a.name] = wire::make_curve_keypair()).public_key);
    authenticator_ = std::make_unique<wire::Authenticator>(allowed);
    control_.make_curve_server(director_keys_.secret_key);
    authenticator_->watch(control_);
  }

  std::string farm_keys_for(const std::string& actor) const {
    wire::FarmKeys k;
    k.own = actor_keys_.at(actor);
    k.director = director_keys_.public_key;
    for (const auto& [name, keys] : actor_keys_) k.allowed.push_back(keys.public_key);
    return k.to_line();
  }

  void configure() {
    for (auto& [name, a] : supervisor_.actors())
      if (!a.lost && a.spec->has_process()) check(configure_actor(a));
  }

  // Where `receiver` reaches its input `input`: inputs on the same host over their IPC socket, without CURVE (the
  // 0700 folder keeps other users out, and a process of the same user could read the keys anyway); only an actor
  // that offers such a socket itself is known to connect to one. Otherwise TCP, with the input's public key.
  std::pair<std::string, std::string> endpoint_for(const ActorRecord& receiver, const ActorRecord& input) const {
    if (input.spec->host == receiver.spec->host && !receiver.local_endpoint.empty() && !input.local_endpoint.empty())
      return {input.local_endpoint, ""};
    return {input.endpoint, actor_keys_.empty() ? "" : actor_keys_.at(input.name()).public_key};
  }

  // partition { parts = N }: the split the geometry actors hold, weighted by probe rays from the farm's camera
  // (render/partition.hpp), made once here so that every actor agrees on it.
  void split_scene(const Scene& scene) {
    const auto start = Clock::now();
    RayTracer whole(scene);
    const int width = std::min(spec_.image.width, 160);
    const int height = std::max(1, spec_.image.height * width / std::max(1, spec_.image.width));
    const Camera probe(spec_.camera, width, height);
    parts_ = partition_by_probes(scene, whole, probe, width, height, spec_.partition_parts);
    if (static_cast<int>(parts_.size()) < spec_.partition_parts)
      throw FarmFailure{spec_.partition_loc.str() + ": partition: the scene has " +
                        std::to_string(scene.triangle_count()) + " triangles, fewer than the " +
                        std::to_string(spec_.partition_parts) + " parts asked for"};
    if (!options_.quiet) {
      std::string shares;
      for (const ScenePart& p : parts_)
        shares += (shares.empty() ? "" : ", ") + std::to_string(p.triangles.size());
      log_info("partition: " + std::to_string(parts_.size()) + " parts of " + shares + " triangles (split in " +
               seconds_text(std::round(seconds_since(start) * 100) / 100) + ")");
    }
  }

  // partition { colocate = true }: the part actor `name` holds itself (farm/builders), once the scene is split.
  int64_t colocated_part(const std::string& name) const {
    return parts_.empty() ? -1 : lf::colocated_part(spec_, spec_.find(name));
  }

  Status configure_actor(ActorRecord& a) {
    auto endpoint_of = [&](int i) { return supervisor_.at(spec_.actors[static_cast<size_t>(i)].name).endpoint; };
    std::function<std::string(int)> key_of;
    if (!actor_keys_.empty())
      key_of = [&](int i) { return actor_keys_.at(spec_.actors[static_cast<size_t>(i)].name).public_key; };
    ActorConfig config = config_for(spec_, a.index, endpoint_of, key_of);
    for (auto& in : config.inputs) {
      if (!in.is_pool()) {
        std::tie(in.endpoint, in.key) = endpoint_for(a, supervisor_.at(in.name));
        continue;
      }
      // A replica lost before this client was configured is left out (it may never have said where it listens).
      std::vector<InputSpec> live;
      for (auto& r : in.replicas) {
        const ActorRecord& replica = supervisor_.at(r.name);
        if (replica.lost) continue;
        r.part = colocated_part(r.name);
        std::tie(r.endpoint, r.key) = endpoint_for(a, replica);
        live.push_back(std::move(r));
      }
      in.replicas = std::move(live);
    }
    if (!scene_bytes_.empty()) {
      config.scene.cache = scene_paths_.at(a.spec->host);
      config.scene.hash = scene_hash_;
    }
    if (!parts_.empty()) {
      if (a.spec->is_geometry()) {
        config.part_triangles = parts_.at(static_cast<size_t>(a.spec->params.at("part").as_int())).triangles;
      } else if (a.spec->loads_scene()) {
        if (config.pool) {
          config.local_part = colocated_part(a.name());
          if (config.local_part >= 0) config.part_triangles = parts_.at(static_cast<size_t>(config.local_part)).triangles;
        }
        // A renderer traces its camera rays through the parts, and a LightOp its rays (those of its ops that can:
        // direct, pathtrace).
        for (const auto& g : spec_.actors) {
          if (!g.is_geometry()) continue;
          const auto [endpoint, key] = endpoint_for(a, supervisor_.at(g.name));
          config.geometry.push_back({g.name, endpoint, 4, key});
        }
        for (const ScenePart& p : parts_)
          config.part_boxes.insert(config.part_boxes.end(),
                                   {p.bounds.lo.x, p.bounds.lo.y, p.bounds.lo.z, p.bounds.hi.x, p.bounds.hi.y, p.bounds.hi.z});
      }
    }
    // Replicas that share their setup send each other their parts directly: a photon map's tens of MB then cross
    // one link (IPC on one host) once, instead of going to the director and out again, decoded and re-encoded.
    if (config.pool && config.pool->count > 1)
      if (const LightOpKind* kind = find_lightop_kind(a.spec->kind); kind && kind->shares_setup_for(a.spec->params)) {
        const auto& replicas = spec_.actors[static_cast<size_t>(spec_.pool_of(a.index))].inputs;
        for (int r : replicas) {
          const ActorRecord& sibling = supervisor_.at(spec_.actors[static_cast<size_t>(r)].name);
          if (sibling.name() == a.name()) continue;
          const auto [endpoint, key] = endpoint_for(a, sibling);
          config.pool->peers.push_back({sibling.name(), endpoint, 4, key});
        }
      }
    // A replica lost before its pool was configured is left out of the pool (it never said where it listens).
    std::vector<InputSpec> inputs;
    for (auto& in : config.inputs)
      if (!supervisor_.at(in.name).lost) inputs.push_back(std::move(in));
    config.inputs = std::move(inputs);
    send(a.name(), wire::make(MsgType::config, "director", config.to_value()));
    a.configured = true;
    return Ok{};
  }

  // A long setup step (photons, a cache's pre-pass) as it goes: a line at each quarter, per actor and step, once
  // the step has taken a second (short ones say nothing).
  void show_progress(const ActorRecord& a, const std::string& what, uint64_t done, uint64_t total) {
    if (monitor_)
      monitor_progress_[a.name() + "\n" + what] =
          Value::Map{{"actor", a.name()}, {"what", what}, {"done", static_cast<int64_t>(done)},
                     {"total", static_cast<int64_t>(total)}};
    if (options_.quiet) return;
    const int quarter = static_cast<int>(4 * done / total);
    auto [step, fresh] = progress_shown_.try_emplace(a.name() + "\n" + what, StepShown{Clock::now(), 0});
    if (quarter <= step->second.quarter || seconds_since(step->second.first) < 1.0) return;
    step->second.quarter = quarter;
    if (tiles_.drawing_progress()) std::fprintf(stderr, "\n");
    log_info(a.name() + ": " + what + " " + std::to_string(25 * quarter) + "% (" + std::to_string(done) + " of " +
             std::to_string(total) + ")");
  }
  struct StepShown {
    Clock::time_point first;  // the step's first report
    int quarter = 0;          // the last quarter shown
  };
  std::map<std::string, StepShown> progress_shown_;

  bool needs_restart(const ActorRecord& a) const {
    for (const Service* s : all_services_)
      if (s->needs_restart(a.name())) return true;
    return false;
  }

  // A restarted actor is configured: every configured actor that has it as an input learns where it listens now,
  // the services take it back (the ring rolls back once all its restarted nodes are here), and it joins the phase
  // under way.
  Status rejoin(ActorRecord& moved) {
    for (auto& [name, a] : supervisor_.actors()) {
      if (a.lost || !a.configured || a.exited || &a == &moved) continue;
      for (int input : a.spec->inputs) {
        if (input != moved.index) continue;
        const auto [endpoint, key] = endpoint_for(a, moved);
        send(name, wire::make(MsgType::peer_moved, "director",
                              Value::Map{{"name", moved.name()}, {"endpoint", endpoint}, {"key", key}}));
      }
    }
    for (Service* s : all_services_)
      if (auto st = s->on_rejoined(moved.name(), *this); !st) return st;
    if (supervisor_.stage() >= Stage::setup) send(moved.name(), wire::make_phase("director", Phase::setup));
    if (supervisor_.stage() >= Stage::render) send(moved.name(), wire::make_phase("director", Phase::render));
    return Ok{};
  }

  // PHASE to everyone, then wait for every READY of it (no timeout: setup and render take what they take).
  void run_phase(Phase phase) {
    supervisor_.broadcast(wire::make_phase("director", phase));
    for (Service* s : all_services_) check(s->on_phase(phase, *this));
    if (phase != Phase::render) {
      wait_all(0, [phase](const ActorRecord& a) { return a.ready == phase; });
      // A READY sent before a rollback counts for nothing: the services say when the phase's work is really in.
      auto complete = [&] {
        for (const Service* s : all_services_)
          if (!s->phase_complete(phase)) return false;
        return true;
      };
      while (!complete() || !supervisor_.all([phase](const ActorRecord& a) { return a.ready == phase; })) pump(100);
      return;
    }
    // Rendering takes what it takes; once every renderer is done, the others have had PHASE render for the whole
    // frame and must have said READY render (docs/PROTOCOL.md). One that never does would hang the farm.
    // A frame that makes no progress for a long while says, every so often, what it is waiting on: who holds which
    // tiles and what each actor has in flight (from its heartbeats). It changes nothing; a stall is then diagnosable.
    auto last_report = Clock::now();
    while (!supervisor_.all([](const ActorRecord& a) { return !a.spec->is_renderer() || a.ready == Phase::render; })) {
      pump(100);
      if (tiles_.seconds_since_progress() < kStallReportSeconds || seconds_since(last_report) < kStallReportSeconds)
        continue;
      last_report = Clock::now();
      std::string in_flight;
      for (const auto& [name, a] : supervisor_.actors()) {
        auto figure = [&a = a](const char* key) {
          const Value* v = a.live.find(key);
          return v && v->is_number() ? v->as_int() : int64_t{0};
        };
        if (a.lost || (figure("in_flight") == 0 && figure("queue") == 0)) continue;
        in_flight += (in_flight.empty() ? "" : ", ") + name + " " + std::to_string(figure("in_flight")) + " out / " +
                     std::to_string(figure("queue")) + " queued";
      }
      log_warn("no tile has landed for " + seconds_text(std::round(tiles_.seconds_since_progress())) + " (" +
               std::to_string(tiles_.tiles_done()) + " of " + std::to_string(tiles_.tiles_total()) + " done): " +
               tiles_.holders() + "; requests " + (in_flight.empty() ? std::string("none in flight") : in_flight));
    }
    const auto deadline = Clock::now() + std::chrono::seconds(kReadyRenderGraceSeconds);
    while (true) {
      std::string late;
      if (supervisor_.all([](const ActorRecord& a) { return a.ready == Phase::render; }, &late)) return;
      if (Clock::now() > deadline)
        throw FarmFailure{"every tile is done, but " + late + " never answered PHASE render with READY render (every "
                          "actor must; docs/PROTOCOL.md, \"Life of an actor\")"};
      pump(100);
    }
  }
  static constexpr int kReadyRenderGraceSeconds = 5;
  static constexpr double kStallReportSeconds = 30;
  Clock::time_point last_awake_ = Clock::now();  // the last time notice_outside_stop() ran
  bool image_written_ = false;

  // Stopped from outside (SIGSTOP, a debugger) and continued: for longer than the heartbeat timeout, the actors took
  // this director for dead and are going; say so rather than blame the first of them whose exit arrives.
  // `slept_through`: a wait just returned far later than its timeout. The SIGCONT handler may run on any of this
  // process's threads, and on another one it can set its flag a moment after this thread has looked; a wait that
  // overran by more than the heartbeat timeout says the same without that race.
  void notice_outside_stop(bool slept_through = false) {
    if (take_resumed() || slept_through) {
      const double away = seconds_since(last_awake_);
      if (away > spec_.heartbeat_timeout)
        throw FarmFailure{"this director was stopped for " + seconds_text(std::round(away)) +
                          ", longer than heartbeat_timeout (" + seconds_text(spec_.heartbeat_timeout) +
                          "): its actors took it for dead"};
      supervisor_.forgive_silence(Clock::now());
    }
    last_awake_ = Clock::now();
  }

  // Ctrl-Z: stop this machine's actors, then this process; on `fg`, continue them and forgive the time spent
  // stopped (heartbeats, and the actors' own clocks through their SIGCONT). Remote actors cannot be stopped: a
  // pause longer than heartbeat_timeout loses them (pools recover; docs/lua-api.md).
  void suspend_farm() {
    const auto stopped_at = Clock::now();
    launchers_.pause_all(true);
    // SIGSTOP, not SIGTSTP re-raised: the kernel discards a default-action SIGTSTP in an orphaned process group
    // (a farm started from a script or a service), which would leave the actors stopped and the director running.
    ::raise(SIGSTOP);  // stops here until SIGCONT
    launchers_.pause_all(false);
    take_resumed();  // that SIGCONT was this pause's
    const double paused = seconds_since(stopped_at);
    if (paused > spec_.heartbeat_timeout && launchers_.any_remote())
      log_warn("the farm was suspended for " + seconds_text(std::round(paused)) +
               "; actors on other hosts cannot be, and may have taken the director for dead");
    supervisor_.forgive_silence(Clock::now());
  }

  void finish() {
    const Display display{static_cast<float>(spec_.image.exposure), spec_.image.tonemap};
    if (auto st = write_image(tiles_.film(), spec_.image.output, display); !st) throw FarmFailure{st.error().message};
    image_written_ = true;
    if (all_black(tiles_.film()))
      log_warn(spec_.image.output + ": every pixel is 0, nothing the camera sees is lit: it may look at the back of the "
               "scene's surfaces from outside or past them (`lightfarm scene FILE.obj` suggests a camera that frames "
               "the scene), or the lights may face away from what it sees");
    supervisor_.broadcast(wire::make_phase("director", Phase::finish));
    // Wait for every actor's STATS and BYE, and for its process to end.
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (Clock::now() < deadline) {
      if (supervisor_.all([](const ActorRecord& a) { return a.said_bye && a.exited; })) return;
      pump(50);
    }
    log_warn("some actors did not stop within 10 s; stopping them");
  }

  // Processes control messages and exits until every actor satisfies `done`.
  template <class Pred>
  void wait_all(double timeout_seconds, Pred done) {
    const auto start = Clock::now();
    while (true) {
      std::string late;
      if (supervisor_.all(done, &late)) return;
      if (timeout_seconds > 0 && seconds_since(start) > timeout_seconds)
        throw FarmFailure{"timed out after " + seconds_text(timeout_seconds) + " waiting for " + late + " in phase " +
                          std::string(stage_name(supervisor_.stage()))};
      pump(100);
    }
  }

  void pump(long timeout_ms) {
    // The image writer's load runs beside the render, once the first tile is in. For .exr and .png it is a few
    // milliseconds (OpenEXR, libpng); for other formats it is OpenImageIO's (0.4-0.6 CPU-s: 154k symbol lookups in
    // 261 libraries), which, started with the actors, took a core from their start-up and from setup (photon
    // shooting 1 -> 2 replicas: 1.27x instead of 1.95x), and the first tile waited. Not at idle priority: on a host
    // busy with other work it would never run, and the image would wait for it. Not after the last tile: that adds
    // its time to every frame. Only once this process has made its own threads (ZeroMQ's, the ZAP handler, hosts
    // connecting): dlopen holds the loader's lock, which creating a thread needs.
    if (!image_io_started_ && tiles_.tiles_done() > 0) {
      image_io_started_ = true;
      image_io_ = std::thread(preload_image_writer, spec_.image.output);
    }
    if (stop_requested())
      throw FarmFailure{"interrupted by signal " + std::to_string(stop_signal()) + "; stopping the farm",
                        128 + stop_signal()};
    if (take_suspend_request()) suspend_farm();
    notice_outside_stop();
    wire::Poller poller;
    poller.add(control_);
    const long wait_ms = std::min<long>(timeout_ms, static_cast<long>(spec_.heartbeat_timeout * 250));
    const auto waiting_since = Clock::now();
    poller.wait(wait_ms);
    // The stop may have come during the wait: before reading what it left behind.
    notice_outside_stop(seconds_since(waiting_since) > wait_ms / 1000.0 + spec_.heartbeat_timeout);
    while (auto in = control_.receive()) check(supervisor_.on_message(in->peer, in->message));
    while (auto exit = launchers_.reap_one()) {
      // A stop that landed after the check above (while messages were read) would otherwise make the actors that
      // left during it look like the fault: judge this director's own absence first.
      notice_outside_stop();
      // Its last words (an ERROR with the reason, or BYE) may still be in flight: read them before judging. (Not for
      // an actor that has said BYE: at the end of every farm that waited 50 ms per actor, 0.6 s for 12.)
      wire::Poller last;
      last.add(control_);
      for (int i = 0; i < 5 && supervisor_.may_still_speak(exit->pid) && !last.wait(10)[0]; ++i) {
      }
      while (auto in = control_.receive()) check(supervisor_.on_message(in->peer, in->message));
      check(supervisor_.on_exit(*exit));
    }
    check(supervisor_.check_heartbeats(Clock::now()));
    supervisor_.send_heartbeats(Clock::now());
    if (monitor_) {
      if (tiles_.tiles_done() != tiles_seen_) {  // when tiles landed, for the page's latency
        tiles_seen_ = tiles_.tiles_done();
        tile_landed_ms_ = std::chrono::duration_cast<std::chrono::milliseconds>(
                              std::chrono::system_clock::now().time_since_epoch()).count();
        if (oldest_unshown_ms_ == 0) oldest_unshown_ms_ = tile_landed_ms_;
      }
      publish_monitor(false);
    }
  }

  // --- The live monitor: the state it shows, built here on the director's thread and handed over as a copy.

  void keep_log_line(const std::string& level, const std::string& text) {
    std::string kind = level.empty() ? "info" : level.substr(0, level.find(':'));
    // Losses and recoveries, as the supervisor words them, stand out on the page.
    auto says = [&](const char* words) { return text.find(words) != std::string::npos; };
    if (says("restarting") || says("rejoined") || says("recovered")) kind = "recovery";
    else if (says(" lost") || says("was killed") || says("sends its work to the others") || says("heartbeat")) kind = "loss";
    std::lock_guard<std::mutex> lock(log_mutex_);
    log_lines_.push_back(Value::Map{{"kind", kind}, {"text", text}, {"seconds", seconds_since(start_)}});
    if (log_lines_.size() > 300) log_lines_.pop_front();
  }

  std::string actor_state(const ActorRecord& a) const {
    if (!a.spec->has_process()) return "pool";  // dispatched by its clients: nothing runs under its name
    if (a.lost) return "lost";
    if (a.rejoining) return "restarting";
    if (a.exited || a.said_bye) return "done";
    if (!a.said_hello) return "launching";
    const Stage st = supervisor_.stage();
    if (st <= Stage::configure) return a.ready == Phase::configure ? "ready" : "configuring";
    if (st == Stage::setup) return a.ready == Phase::setup ? "ready" : "setup";
    if (st == Stage::render) return "rendering";
    return "finishing";
  }

  Value monitor_state() {
    const double now = seconds_since(start_);
    Value::Array actors, parts;  // parts: a partitioned scene's geometry actors
    for (const ActorSpec& g : spec_.actors)
      if (g.is_geometry()) parts.push_back(g.name);
    for (const ActorSpec& spec : spec_.actors) {
      const ActorRecord& a = supervisor_.at(spec.name);
      Value::Array inputs;
      for (int i : spec.inputs) inputs.push_back(spec_.actors[static_cast<size_t>(i)].name);
      if (spec.is_renderer() && spec.inputs.empty() && spec_.lighting >= 0)
        inputs.push_back(spec_.actors[static_cast<size_t>(spec_.lighting)].name);
      Value::Map m{{"name", spec.name}, {"kind", spec.kind}, {"host", spec.host}, {"state", actor_state(a)},
                   {"inputs", std::move(inputs)}, {"restarts", static_cast<int64_t>(a.restarts)}};
      if (!parts.empty() && traces_through_parts(spec)) m["rays_from"] = parts;
      if (const pid_t pid = supervisor_.host_pid(a); pid > 0) m["pid"] = static_cast<int64_t>(pid);
      if (!a.loss.empty()) m["loss"] = a.loss;
      if (a.live.is_map()) {
        m["live"] = a.live;
        // Rates over the time since the figures before these (heartbeats come about once a second).
        // Plain references, not a structured binding: clang 14 cannot capture one in the lambda below.
        auto& entry = live_before_[spec.name];
        Value& before = std::get<0>(entry);
        Clock::time_point& before_at = std::get<1>(entry);
        Value& rates = std::get<2>(entry);
        if (a.live_at != before_at) {
          if (before.is_map() && before_at != Clock::time_point{}) {
            const double dt = std::chrono::duration<double>(a.live_at - before_at).count();
            auto delta = [&](const char* k) {
              const Value *x = a.live.find(k), *y = before.find(k);
              const double xv = x && x->is_number() ? (x->is_int() ? static_cast<double>(x->as_int()) : x->as_double()) : 0;
              const double yv = y && y->is_number() ? (y->is_int() ? static_cast<double>(y->as_int()) : y->as_double()) : 0;
              return dt > 0 ? (xv - yv) / dt : 0.0;
            };
            rates = Value::Map{{"requests_per_second", delta("requests")},
                               {"points_per_second", delta("points")},
                               {"busy_share", std::min(1.0, delta("busy_seconds"))}};
          }
          before = a.live;
          before_at = a.live_at;
        }
        if (rates.is_map() && !a.stats.is_map() && !a.lost) m["rates"] = rates;  // a finished actor does nothing
      }
      if (a.stats.is_map()) {
        // Its final figures: the counters end at what the end-of-run table prints, not at the last heartbeat.
        m["stats"] = a.stats;
        Value::Map final_live;
        for (const char* k : {"requests", "points", "tiles", "busy_seconds", "bytes_in", "bytes_out"})
          if (const Value* v = a.stats.find(k)) final_live[k] = *v;
        final_live["queue"] = int64_t{0};
        m["live"] = std::move(final_live);
      }
      actors.push_back(std::move(m));
    }
    Value::Array stages;
    for (const auto& [name, secs] : stage_seconds_) stages.push_back(Value::Map{{"name", name}, {"seconds", secs}});
    if (!image_written_)
      stages.push_back(Value::Map{{"name", std::string(stage_name(supervisor_.stage())) + " (now)"},
                                  {"seconds", now - stage_started_seconds()}});
    Value::Array progress;
    for (const auto& [key, p] : monitor_progress_) progress.push_back(p);
    Value::Array log;
    {
      std::lock_guard<std::mutex> lock(log_mutex_);
      for (const Value& l : log_lines_) log.push_back(l);
    }
    Value::Map farm{{"script", spec_.script},
                    {"output", spec_.image.output},
                    {"width", static_cast<int64_t>(spec_.image.width)},
                    {"height", static_cast<int64_t>(spec_.image.height)},
                    {"stage", image_written_ ? std::string("done") : std::string(stage_name(supervisor_.stage()))},
                    {"elapsed_seconds", now},
                    {"tiles_done", static_cast<int64_t>(tiles_.tiles_done())},
                    {"tiles_total", static_cast<int64_t>(tiles_.tiles_total())}};
    Value::Map state{{"farm", std::move(farm)}, {"actors", std::move(actors)}, {"stages", std::move(stages)},
                     {"progress", std::move(progress)}, {"log", std::move(log)}};
    if (ring_.active()) {
      // The last 200 iterations' unshot power (older ones thinned out): what a progressive solution shows.
      const auto& unshot = ring_.unshot_fraction();
      Value::Array tail;
      const size_t step = std::max<size_t>(1, unshot.size() / 200);
      for (size_t i = 0; i < unshot.size(); i += step) tail.push_back(unshot[i]);
      if (!unshot.empty() && (unshot.size() - 1) % step != 0) tail.push_back(unshot.back());
      state["radiosity"] = Value::Map{{"iterations", static_cast<int64_t>(unshot.size())},
                                      {"unshot_fraction", std::move(tail)}};
    }
    return state;
  }

  double stage_started_seconds() const {
    double sum = 0;
    for (const auto& [name, secs] : stage_seconds_) sum += secs;
    return sum;
  }

  // Once a second (and at every call with `now`): the state, and the preview when tiles have landed, as one update,
  // so that a watching page wakes, lays out and paints once a second. A headless Chromium watching on the farm's
  // machine took 0.082 of a core with the state twice a second and the preview apart, 0.063 so (bench/monitor_bench).
  void publish_monitor(bool now) {
    const auto t = Clock::now();
    if (!now && t - monitor_published_ < std::chrono::milliseconds(1000)) return;
    monitor_published_ = t;
    const size_t done = tiles_.tiles_done();
    if (done != preview_tiles_) {
      preview_tiles_ = done;
      publish_preview(/*notify=*/false);  // the state below tells the readers about both
    }
    monitor_->publish_state(monitor_state());
  }

  // The film so far as the output will look (exposure, tone map, sRGB), at most 400 pixels wide (a page that
  // decodes and draws it once a second costs its machine CPU by the pixel).
  void publish_preview(bool notify = true) {
    const Image& film = tiles_.film();
    const int step = std::max(1, (film.width + 399) / 400);
    const int w = std::max(1, film.width / step), h = std::max(1, film.height / step);
    const Display display{static_cast<float>(spec_.image.exposure), spec_.image.tonemap};
    std::string rgb(static_cast<size_t>(w) * h * 3, '\0');
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const RGB& p = film.at(x * step, y * step);
        for (int c = 0; c < 3; ++c)
          rgb[(static_cast<size_t>(y) * w + x) * 3 + c] = static_cast<char>(static_cast<unsigned char>(
              std::lround(255.0f * display_srgb(p[c], display))));
      }
    monitor_->publish_preview(w, h, std::move(rgb), tiles_.tiles_done(), oldest_unshown_ms_ ? oldest_unshown_ms_ : tile_landed_ms_,
                              tile_landed_ms_, notify);
    oldest_unshown_ms_ = 0;
  }

  // After the frame: the final figures, kept up for `monitor_hold` seconds (Ctrl-C ends the wait).
  void hold_monitor(int status) {
    publish_monitor(true);
    publish_preview();
    if (options_.monitor_hold <= 0) return;
    if (!options_.quiet)
      log_info("monitor: holding " + monitor_->url() + " for " + seconds_text(options_.monitor_hold) +
               (status == 0 ? "" : " (the farm failed)"));
    const auto until = Clock::now() + std::chrono::duration<double>(options_.monitor_hold);
    while (Clock::now() < until && !stop_requested()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      monitor_->publish_state(monitor_state());
    }
  }

  Status dispatch(ActorRecord& a, wire::Message& m) {
    const wire::Op op = wire::op_of(m.header);
    auto it = services_.find(op);
    if (it == services_.end()) {
      std::string served;
      for (const auto& [o, s] : services_) served += (served.empty() ? "'" : ", '") + std::string(wire::op_name(o)) + "'";
      refuse(a.name(), m.header.id, ErrorCode::unknown_op,
             "unknown operation '" + m.header.op + "' (the director serves " + served + ")");
      return Ok{};
    }
    return it->second->on_request(a.name(), op, m.header.id, std::move(m.body), *this);
  }

  Status lost(ActorRecord& a, const std::string& why) {
    for (Service* s : all_services_)
      if (auto st = s->on_lost(a.name(), why, *this); !st) return st;
    return Ok{};
  }

  // The tables, and the stats file if asked for; 1 when that file cannot be written (the image is there, but
  // what was asked for is not).
  int report() {
    RunFigures f;
    f.stage_seconds = stage_seconds_;
    f.total_seconds = seconds_since(start_);
    f.render_seconds = render_seconds_;
    f.first_tile_seconds = std::chrono::duration<double>(render_start_ - start_).count() + tiles_.first_tile_seconds();
    if (ring_.active()) f.radiosity = ring_.report();
    if (!scene_bytes_.empty()) {
      Value::Map sent;
      for (const auto& [host, bytes] : scene_sent_) sent[host] = static_cast<int64_t>(bytes);
      f.scene = Value::Map{{"hash", scene_hash_}, {"bytes", static_cast<int64_t>(scene_bytes_.size())},
                           {"bytes_shipped", std::move(sent)}};
    }
    if (!options_.quiet) print_report(spec_, supervisor_, f);
    if (!options_.stats_json.empty())
      if (auto st = write_stats_json(spec_, supervisor_, f, options_.stats_json); !st) {
        log_error(st.error().message);
        return 1;
      }
    return 0;
  }

  const FarmSpec& spec_;
  RunOptions options_;
  Launchers launchers_;
  std::thread image_io_;  // loads the image writer beside the render (pump)
  bool image_io_started_ = false;
  std::future<Status> hosts_connected_;  // remote hosts connecting during prepare
  // CURVE (farm { security = "curve" }): declared before the control socket, whose handshakes it serves.
  std::unique_ptr<wire::Authenticator> authenticator_;
  wire::CurveKeys director_keys_;
  std::map<std::string, wire::CurveKeys> actor_keys_;
  std::string scene_bytes_, scene_hash_;           // a scene from a file, as shipped
  std::vector<ScenePart> parts_;                   // partition { parts = N }: what each geometry actor holds
  std::map<std::string, std::string> scene_paths_;  // host -> the scene's path in its cache
  std::map<std::string, uint64_t> scene_sent_;      // host -> bytes that crossed to it
  wire::Socket control_{wire::Socket::Kind::router};
  std::string control_endpoint_;
  std::string local_address_;  // set when the farm spans hosts: where this machine's actors and the director listen
  Supervisor supervisor_;
  TileService tiles_;
  ExchangeService exchange_;
  RingService ring_;
  const std::array<Service*, 3> all_services_{&tiles_, &exchange_, &ring_};
  std::map<wire::Op, Service*> services_;  // by the operation each serves
  std::vector<std::pair<std::string, double>> stage_seconds_;
  Clock::time_point start_, render_start_;
  double render_seconds_ = 0;
  // The live monitor, when asked for (declared last: it goes first, before what its state reads).
  std::map<std::string, Value> monitor_progress_;  // actor + step -> {actor, what, done, total}
  std::map<std::string, std::tuple<Value, Clock::time_point, Value>> live_before_;  // figures, when, rates
  std::mutex log_mutex_;
  std::deque<Value> log_lines_;
  Clock::time_point monitor_published_{};
  size_t preview_tiles_ = SIZE_MAX, tiles_seen_ = 0;
  int64_t tile_landed_ms_ = 0;     // Unix time of the latest tile's arrival
  int64_t oldest_unshown_ms_ = 0;  // of the first tile that landed since the last preview (0: none)
  std::unique_ptr<Monitor> monitor_;
};

}  // namespace

int run_farm(const FarmSpec& spec, const RunOptions& options) {
  // Folders an earlier director or actor here could not remove (it was SIGKILLed) go before this farm starts.
  sweep_stale_private_dirs("ssh");
  sweep_stale_private_dirs("actor");
  try {
    return Director(spec, options).run();
  } catch (const std::bad_alloc&) {
    // The film is allocated before any actor starts: nothing to stop yet.
    log_error("out of memory for a " + std::to_string(spec.image.width) + "x" + std::to_string(spec.image.height) +
              " image; nothing was rendered");
    return 1;
  }
}

}  // namespace lf
