#include "actors/director.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <algorithm>
#include <map>
#include <thread>

#include "actors/launcher.hpp"
#include "actors/render_master.hpp"
#include "actors/ring_coordinator.hpp"
#include "actors/runtime.hpp"
#include "core/log.hpp"
#include "render/image.hpp"
#include "render/scene.hpp"
#include "transport/socket.hpp"

namespace lf {
namespace {

using Clock = std::chrono::steady_clock;
using wire::MsgType;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct ActorState {
  const ActorSpec* spec = nullptr;
  pid_t pid = 0;
  std::string endpoint;
  std::string phase_done;  // last READY
  bool said_hello = false;
  bool said_bye = false;
  bool exited = false;
  bool lost = false;         // died or hung during setup/render, and the farm went on without it
  bool killed_hung = false;  // we SIGKILLed it for missing heartbeats
  std::string loss;          // why it was lost
  Clock::time_point last_seen;
  Value stats;
};

struct FarmFailure {
  std::string message;
  int status = 1;
};

class Progress {
 public:
  Progress(bool tty, bool quiet, size_t total, uint64_t samples_per_tile)
      : tty_(tty && !quiet), quiet_(quiet), total_(total), per_tile_(samples_per_tile) {}
  void update(size_t done, double elapsed, bool force = false) {
    if (tty_) {
      if (!force && seconds_since(last_) < 0.1) return;
      last_ = Clock::now();
      const int width = 30;
      int filled = total_ ? static_cast<int>(width * done / total_) : width;
      double rate = elapsed > 0 ? done * per_tile_ / elapsed : 0;
      double eta = done > 0 ? elapsed * (static_cast<double>(total_) - done) / done : 0;
      std::fprintf(stderr, "\r[%s%s] %zu/%zu tiles  %.2f M samples/s  ETA %.0f s   ",
                   std::string(static_cast<size_t>(filled), '#').c_str(),
                   std::string(static_cast<size_t>(width - filled), '.').c_str(), done, total_, rate / 1e6, eta);
      if (done == total_) std::fprintf(stderr, "\n");
    } else if (!quiet_) {
      // Plain lines at every tenth, for logs and CI.
      size_t tenth = total_ ? 10 * done / total_ : 10;
      if (tenth > last_tenth_ || (force && done == total_ && last_tenth_ < 10)) {
        last_tenth_ = tenth;
        log_info("render " + std::to_string(tenth * 10) + "% (" + std::to_string(done) + "/" + std::to_string(total_) +
                 " tiles)");
      }
    }
  }

 private:
  bool tty_;
  bool quiet_;
  size_t total_;
  uint64_t per_tile_;
  Clock::time_point last_ = Clock::now() - std::chrono::seconds(1);
  size_t last_tenth_ = 0;
};

class Director {
 public:
  Director(const FarmSpec& spec, const RunOptions& options)
      : spec_(spec), options_(options), ring_(spec, options.quiet, options.progress_on_terminal) {}

  int run() {
    install_stop_signals();
    const auto start = Clock::now();
    int status = 0;
    start_ = start;
    // Loading OpenImageIO takes ~0.2 s; do it while the actors start instead of after the last tile.
    std::thread image_io(preload_image_io);
    struct Join {
      std::thread& t;
      ~Join() { t.join(); }
    } join_image_io{image_io};
    try {
      prepare();
      phase("launch", [&] { launch(); });
      phase("hello", [&] { wait_all("hello", 30.0, [](const ActorState& a) { return a.said_hello; }); });
      phase("configure", [&] {
        configure();
        wait_all("configure", 60.0, [](const ActorState& a) { return a.phase_done == "configure"; });
      });
      phase("setup", [&] {
        broadcast_phase("setup");
        wait_all("setup", 0, [](const ActorState& a) { return a.phase_done == "setup"; });
      });
      phase("render", [&] { render(); });
      phase("finish", [&] { finish(); });
    } catch (const FarmFailure& f) {
      if (progress_active_) std::fprintf(stderr, "\n");
      log_error(f.message);
      status = f.status;
    }
    // No actor outlives the farm, whatever happened above.
    send_bye_to_all();
    launcher_.stop_all(std::chrono::milliseconds(status == 0 ? 3000 : 300));
    total_seconds_ = seconds_since(start);
    if (status == 0) report();
    return status;
  }

 private:
  template <class Fn>
  void phase(const char* name, Fn&& fn) {
    const auto t = Clock::now();
    current_phase_ = name;
    fn();
    phases_.emplace_back(name, seconds_since(t));
  }

  void prepare() {
    if (auto st = check_output_path(spec_.image.output); !st) throw FarmFailure{st.error().message};
    // The director reads the scene once itself, so a broken scene stops the farm before anything launches.
    auto scene = Scene::load(spec_.scene);
    if (!scene) throw FarmFailure{spec_.scene.loc.str() + ": " + scene.error().message};
    if (ring_.active()) {
      if (auto st = ring_.prepare(*scene); !st) throw FarmFailure{st.error().message};
      if (!ring_.ply_path().empty()) {
        const auto dir = std::filesystem::path(ring_.ply_path()).parent_path();
        if (::access(dir.c_str(), W_OK) != 0)
          throw FarmFailure{"radiosity: cannot write '" + ring_.ply_path() + "': folder '" + dir.string() +
                            "' does not exist or is not writable"};
      }
    }
    auto endpoint = control_.bind("tcp://127.0.0.1:*");
    if (!endpoint) throw FarmFailure{endpoint.error().message};
    control_endpoint_ = *endpoint;
    control_.set_linger_ms(0);
    for (const auto& a : spec_.actors) {
      ActorState s;
      s.spec = &a;
      actors_.emplace(a.name, s);
    }
    master_ = std::make_unique<RenderMaster>(spec_.image.width, spec_.image.height, spec_.image.tile);
  }

  void launch() {
    for (const auto& a : spec_.actors) {
      std::vector<std::string> argv{"lightfarm", "actor"};
      LocalLauncher::Options how;
      if (const Value* cmd = a.runtime.count("cmd") ? &a.runtime.at("cmd") : nullptr) {
        // An external actor: its own command, then the arguments every actor gets.
        argv.clear();
        for (const auto& part : cmd->as_array()) argv.push_back(part.as_string());
        how.self = false;
        how.cwd = a.runtime.count("cwd") ? a.runtime.at("cwd").as_string() : std::string();
      }
      argv.insert(argv.end(), {"--kind", a.kind, "--name", a.name, "--director", control_endpoint_});
      auto pid = launcher_.launch(argv, how);
      if (!pid) throw FarmFailure{a.loc.str() + ": cannot start actor '" + a.name + "': " + pid.error().message};
      actors_[a.name].pid = *pid;
      actors_[a.name].last_seen = Clock::now();
    }
  }

  void configure() {
    for (auto& [name, a] : actors_) {
      Value::Array inputs;
      const int64_t window = a.spec->is_renderer() ? a.spec->params.at("window").as_int() : 4;
      for (int in : a.spec->inputs) {
        const auto& peer = actors_.at(spec_.actors[static_cast<size_t>(in)].name);
        inputs.push_back(Value::Map{{"name", peer.spec->name}, {"endpoint", peer.endpoint}, {"window", window}});
      }
      Value::Map config{{"params", a.spec->params},
                        {"scene", spec_.scene.to_value()},
                        {"camera", spec_.camera.to_value()},
                        {"image", spec_.image.to_value()},
                        {"inputs", std::move(inputs)},
                        {"runtime", a.spec->runtime},
                        {"heartbeat_timeout", spec_.heartbeat_timeout},
                        {"request_timeout", spec_.request_timeout}};
      if (const int pool = spec_.pool_of(index_of(a)); pool >= 0) {
        const auto& replicas = spec_.actors[static_cast<size_t>(pool)].inputs;
        const auto at = std::find(replicas.begin(), replicas.end(), index_of(a)) - replicas.begin();
        config["pool"] = Value::Map{{"name", spec_.actors[static_cast<size_t>(pool)].name},
                                    {"index", static_cast<int64_t>(at)},
                                    {"count", static_cast<int64_t>(replicas.size())}};
      }
      send(name, wire::make(MsgType::config, "director", {}, std::move(config)));
    }
  }

  void broadcast_phase(const std::string& phase) {
    for (auto& [name, a] : actors_) send(name, wire::make(MsgType::phase, "director", phase, Value::Map{{"phase", phase}}));
  }

  void render() {
    const uint64_t per_tile = static_cast<uint64_t>(spec_.image.tile) * spec_.image.tile * spec_.image.spp;
    progress_ = std::make_unique<Progress>(options_.progress_on_terminal, options_.quiet, master_->total(), per_tile);
    progress_active_ = options_.progress_on_terminal && !options_.quiet;
    render_start_ = Clock::now();
    broadcast_phase("render");
    wait_all("render", 0, [](const ActorState& a) { return a.phase_done == "render"; });
    progress_->update(master_->done(), seconds_since(render_start_), true);
    progress_active_ = false;
    render_seconds_ = seconds_since(render_start_);
    if (!master_->finished()) throw FarmFailure{"the renderers stopped before every tile was done"};
  }

  void finish() {
    if (auto st = write_image(master_->film(), spec_.image.output); !st) throw FarmFailure{st.error().message};
    broadcast_phase("finish");
    // Wait for every actor's STATS and BYE, and for its process to end.
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (Clock::now() < deadline) {
      bool all = true;
      for (auto& [n, a] : actors_) all = all && (a.lost || (a.said_bye && a.exited));
      if (all) return;
      pump(50);
    }
    log_warn("some actors did not stop within 10 s; stopping them");
  }

  void send(const std::string& name, wire::Message m) {
    m.header.sender = "director";
    if (!control_.send_to(name, m)) log_debug("could not send to '" + name + "'");
  }

  void send_bye_to_all() {
    for (auto& [name, a] : actors_)
      if (a.said_hello && !a.said_bye && !a.exited && !a.lost) send(name, wire::make(MsgType::bye, "director"));
  }

  // Processes control messages and child exits until every actor satisfies `done`.
  template <class Pred>
  void wait_all(const char* what, double timeout_seconds, Pred done) {
    const auto start = Clock::now();
    while (true) {
      bool all = true;
      for (auto& [n, a] : actors_) all = all && (a.lost || done(a));
      if (all) return;
      if (timeout_seconds > 0 && seconds_since(start) > timeout_seconds) {
        std::string late;
        for (auto& [n, a] : actors_)
          if (!a.lost && !done(a)) late += (late.empty() ? "'" : ", '") + n + "'";
        throw FarmFailure{"timed out after " + seconds_text(timeout_seconds) + " waiting for " + late + " in phase " + what};
      }
      pump(100);
    }
  }

  void pump(long timeout_ms) {
    if (stop_requested()) throw FarmFailure{"interrupted by signal " + std::to_string(stop_signal()) + "; stopping the farm", 128 + stop_signal()};
    wire::Poller poller;
    poller.add(control_);
    poller.wait(std::min<long>(timeout_ms, static_cast<long>(spec_.heartbeat_timeout * 250)));
    while (auto in = control_.receive()) handle(*in);
    while (auto exit = launcher_.reap_one()) {
      // Its last words (an ERROR with the reason, or BYE) may still be in flight: read them before judging.
      wire::Poller last;
      last.add(control_);
      for (int i = 0; i < 5 && !last.wait(10)[0]; ++i) {
      }
      while (auto in = control_.receive()) handle(*in);
      on_exit(*exit);
    }
    check_heartbeats();
    send_heartbeats();
  }

  void on_exit(const ExitReport& r) {
    for (auto& [name, a] : actors_) {
      if (a.pid != r.pid) continue;
      a.exited = true;
      if (a.lost) return;  // already accounted for (we killed it)
      // In the finish phase a clean exit is an actor finishing, even if its BYE is still on the way.
      if (current_phase_ == "finish" && (a.said_bye || (WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0))) {
        a.said_bye = true;
        return;
      }
      const std::string why = a.killed_hung ? "stopped answering (no heartbeat for " + seconds_text(spec_.heartbeat_timeout) +
                                                  "); it was killed"
                                            : r.describe();
      if (recoverable(a)) return on_lost(a, why);
      std::string when = current_phase_ == "launch" || current_phase_ == "hello" || current_phase_ == "configure"
                             ? "during start-up"
                             : "during " + current_phase_;
      throw FarmFailure{"actor '" + name + "' (pid " + std::to_string(r.pid) + ") " + why + " " + when};
    }
  }

  int index_of(const ActorState& a) const { return static_cast<int>(a.spec - spec_.actors.data()); }

  // Renderers and pool replicas may be lost during setup and render: their work goes to the others.
  bool recoverable(const ActorState& a) const {
    if (current_phase_ != "setup" && current_phase_ != "render") return false;
    return a.spec->is_renderer() || spec_.pool_of(index_of(a)) >= 0;
  }

  void on_lost(ActorState& a, const std::string& why) {
    a.lost = true;
    a.loss = why;
    const std::string& name = a.spec->name;
    if (a.spec->is_renderer()) {
      std::string all;
      bool any_left = false;
      for (auto& [n, other] : actors_) {
        if (!other.spec->is_renderer()) continue;
        any_left = any_left || !other.lost;
        all += (all.empty() ? "" : ", ") + n + " " + other.loss;
      }
      if (!any_left) throw FarmFailure{"every renderer was lost: " + all};
      const size_t tiles = master_ ? master_->release(name) : 0;
      log_warn("renderer '" + name + "' " + why + "; its " + std::to_string(tiles) + " tiles go to the others");
      serve_waiting_tile_requests();
      return;
    }
    ActorState& pool = actors_.at(spec_.actors[static_cast<size_t>(spec_.pool_of(index_of(a)))].name);
    std::string replicas;
    bool any_left = false;
    for (int r : pool.spec->inputs) {
      const ActorState& rep = actors_.at(spec_.actors[static_cast<size_t>(r)].name);
      any_left = any_left || !rep.lost;
      replicas += (replicas.empty() ? "" : "; ") + rep.spec->name + " " + (rep.lost ? rep.loss : "alive");
    }
    if (!any_left) {
      if (recoverable(pool) && !pool.exited) {
        // A nested pool with no replica left is itself a lost replica of the pool above.
        ::kill(pool.pid, SIGKILL);
        return on_lost(pool, "lost every replica (" + replicas + ")");
      }
      throw FarmFailure{"lost the last replica of '" + pool.spec->name + "': " + replicas};
    }
    if (gathers_.count(spec_.pool_of(index_of(a))))
      throw FarmFailure{"replica '" + name + "' " + why + " while '" + pool.spec->name +
                        "' was sharing its setup; its share cannot be redone"};
    log_warn("replica '" + name + "' " + why + "; '" + pool.spec->name + "' sends its work to the others");
    send(pool.spec->name, wire::make(MsgType::peer_down, "director", {}, Value::Map{{"name", name}}));
  }

  void check_heartbeats() {
    if (current_phase_ == "launch" || current_phase_ == "hello") return;  // the hello timeout covers start-up
    for (auto& [name, a] : actors_) {
      if (a.exited || a.said_bye || a.lost || a.killed_hung) continue;
      if (seconds_since(a.last_seen) <= spec_.heartbeat_timeout) continue;
      if (recoverable(a)) {
        // A hung process (e.g. SIGSTOPped) counts as dead; SIGKILL makes sure it can never answer late.
        a.killed_hung = true;
        ::kill(a.pid, SIGKILL);
        continue;
      }
      throw FarmFailure{"actor '" + name + "' has been silent for " + seconds_text(spec_.heartbeat_timeout) +
                        " (missed heartbeats)"};
    }
  }

  void send_heartbeats() {
    if (seconds_since(last_heartbeat_) < std::min(1.0, spec_.heartbeat_timeout / 4)) return;
    last_heartbeat_ = Clock::now();
    for (auto& [name, a] : actors_)
      if (a.said_hello && !a.exited && !a.lost) send(name, wire::make(MsgType::heartbeat, "director"));
  }

  void handle(wire::Incoming& in) {
    auto it = actors_.find(in.peer);
    if (!in.message) {
      const std::string& why = in.message.error().message;
      if (it != actors_.end() && why.rfind("incompatible peer", 0) == 0)
        throw FarmFailure{"actor '" + in.peer + "' is an " + why + "; refusing it"};
      log_warn("dropped a bad control message from '" + in.peer + "': " + why);
      return;
    }
    if (it == actors_.end()) {
      log_warn("ignored a message from '" + in.peer + "', which is not part of this farm");
      return;
    }
    ActorState& a = it->second;
    if (a.lost) return;  // whatever a lost actor still says is not counted
    a.last_seen = Clock::now();
    wire::Message& m = *in.message;
    switch (m.header.type) {
      case MsgType::hello: on_hello(a, m); break;
      case MsgType::ready:
        a.phase_done = m.header.op;
        break;
      case MsgType::error: {
        const Value* text = m.body.find("message");
        throw FarmFailure{"actor '" + in.peer + "' failed: " + (text && text->is_string() ? text->as_string() : "?")};
      }
      case MsgType::stats: a.stats = m.body; break;
      case MsgType::bye: a.said_bye = true; break;
      case MsgType::heartbeat: break;
      case MsgType::request: on_request(a, m); break;
      default: log_warn("ignored a " + std::string(wire::type_name(m.header.type)) + " from '" + in.peer + "'");
    }
  }

  void on_hello(ActorState& a, const wire::Message& m) {
    const Value* kind = m.body.find("kind");
    const Value* endpoint = m.body.find("endpoint");
    const Value* floats = m.body.find("float_format");
    const std::string& name = a.spec->name;
    if (!floats || !floats->is_string() || floats->as_string() != wire::kFloatFormat)
      throw FarmFailure{"actor '" + name + "' is incompatible: float format '" +
                        (floats && floats->is_string() ? floats->as_string() : "?") + "', expected '" +
                        std::string(wire::kFloatFormat) + "'"};
    if (!kind || !kind->is_string() || kind->as_string() != a.spec->kind)
      throw FarmFailure{"actor '" + name + "' says it is a '" + (kind && kind->is_string() ? kind->as_string() : "?") +
                        "', expected '" + a.spec->kind + "'"};
    if (!endpoint || !endpoint->is_string() || endpoint->as_string().empty())
      throw FarmFailure{"actor '" + name + "' sent no data endpoint in its HELLO"};
    a.endpoint = endpoint->as_string();
    a.said_hello = true;
  }

  void on_request(ActorState& a, const wire::Message& m) {
    const std::string& name = a.spec->name;
    if (m.header.op == "tile") {
      // With no tile free but some still out with others, the answer waits: a lost renderer's tiles may come back.
      waiting_tile_requests_.emplace_back(name, m.header.id);
      serve_waiting_tile_requests();
    } else if (m.header.op == "tile_done") {
      const Value* id = m.body.find("id");
      const Value* pixels = m.body.find("pixels");
      std::vector<float> rgb;
      if (!id || !id->is_int() || !pixels || !pixels->is_bytes() || !bytes_to_floats(pixels->as_bytes(), rgb)) {
        send(name, wire::make_error_reply("director", m.header.id, "bad_request", "tile_done needs id and pixels"));
        return;
      }
      auto outcome = master_->complete(name, static_cast<uint64_t>(id->as_int()), rgb);
      if (outcome != RenderMaster::Outcome::accepted) {
        log_warn("refused tile " + std::to_string(id->as_int()) + " from '" + name + "': " + RenderMaster::describe(outcome));
        send(name, wire::make_error_reply("director", m.header.id, "refused", RenderMaster::describe(outcome)));
        return;
      }
      send(name, wire::make(MsgType::reply, "director", "tile_done", Value::Map{}, m.header.id));
      if (master_->done() == 1) first_tile_seconds_ = seconds_since(start_);
      progress_->update(master_->done(), seconds_since(render_start_));
      if (master_->finished()) serve_waiting_tile_requests();
    } else if (m.header.op == "all_gather") {
      on_all_gather(a, m);
    } else if (m.header.op == "ring.shooter" || m.header.op == "ring.result") {
      auto replies = m.header.op == "ring.shooter" ? ring_.on_shooter(name, m.header.id, m.body)
                                                   : ring_.on_result(name, m.header.id, m.body);
      if (!replies) throw FarmFailure{replies.error().message};
      for (auto& r : *replies) send(r.node, wire::make(MsgType::reply, "director", m.header.op, std::move(r.body), r.id));
      if (ring_.solved()) serve_waiting_fetches();
    } else if (m.header.op == "fetch") {
      const Value* key = m.body.find("key");
      if (!key || !key->is_string() || key->as_string() != "radiosity" || !ring_.active()) {
        send(name, wire::make_error_reply("director", m.header.id, "not_found",
                                          "this farm publishes no '" + (key && key->is_string() ? key->as_string() : std::string("?")) +
                                              "' (a radiosity LightOp needs radiosity { ... } in the script)"));
        return;
      }
      waiting_fetches_.emplace_back(name, m.header.id);
      if (ring_.solved()) serve_waiting_fetches();
    } else {
      send(name, wire::make_error_reply("director", m.header.id, "unknown_op",
                                        "the director serves 'tile', 'tile_done', 'all_gather', 'fetch' and the ring's "
                                        "'ring.shooter' and 'ring.result'"));
    }
  }

  // A pool's replicas each send their part; once all have, each gets every part in replica order.
  void on_all_gather(ActorState& a, const wire::Message& m) {
    const Value* part = m.body.find("part");
    const int pool = spec_.pool_of(index_of(a));
    if (!part || !part->is_bytes()) {
      send(a.spec->name, wire::make_error_reply("director", m.header.id, "bad_request", "all_gather needs a part"));
      return;
    }
    if (pool < 0) {  // not in a pool: its own part is everything
      send(a.spec->name, wire::make(MsgType::reply, "director", "all_gather", Value::Map{{"parts", Value::Array{*part}}},
                                    m.header.id));
      return;
    }
    const auto& replicas = spec_.actors[static_cast<size_t>(pool)].inputs;
    for (int r : replicas)
      if (actors_.at(spec_.actors[static_cast<size_t>(r)].name).lost)
        throw FarmFailure{"replica '" + spec_.actors[static_cast<size_t>(r)].name + "' of '" +
                          spec_.actors[static_cast<size_t>(pool)].name +
                          "' was lost before the pool shared its setup; its share cannot be redone"};
    auto& g = gathers_[pool];
    g.parts.resize(replicas.size());
    g.askers.resize(replicas.size());
    const size_t at = static_cast<size_t>(std::find(replicas.begin(), replicas.end(), index_of(a)) - replicas.begin());
    g.parts[at] = *part;
    g.askers[at] = m.header.id;
    for (const auto& p : g.parts)
      if (p.is_nil()) return;
    Value::Array all(g.parts.begin(), g.parts.end());
    for (size_t r = 0; r < replicas.size(); ++r)
      send(spec_.actors[static_cast<size_t>(replicas[r])].name,
           wire::make(MsgType::reply, "director", "all_gather", Value::Map{{"parts", all}}, g.askers[r]));
    gathers_.erase(pool);
  }

  void serve_waiting_fetches() {
    for (auto& [name, id] : waiting_fetches_)
      send(name, wire::make(MsgType::reply, "director", "fetch", Value::Map{{"blob", Bytes{ring_.solution()}}}, id));
    waiting_fetches_.clear();
  }

  // Answers waiting tile requests: a tile each while tiles are free; "none left" once every tile is done.
  void serve_waiting_tile_requests() {
    if (current_phase_ != "render") return;
    while (!waiting_tile_requests_.empty()) {
      auto [name, id] = waiting_tile_requests_.front();
      if (actors_.at(name).lost) {
        waiting_tile_requests_.erase(waiting_tile_requests_.begin());
        continue;
      }
      Value::Map body;
      if (auto t = master_->next(name)) {
        body["tile"] = Value::Map{{"id", t->id}, {"x0", t->rect.x0}, {"y0", t->rect.y0}, {"x1", t->rect.x1}, {"y1", t->rect.y1}};
      } else if (!master_->finished()) {
        return;  // keep waiting
      }
      waiting_tile_requests_.erase(waiting_tile_requests_.begin());
      send(name, wire::make(MsgType::reply, "director", "tile", std::move(body), id));
    }
  }

  static double num(const Value& stats, const char* key) {
    const Value* v = stats.find(key);
    return v && v->is_number() ? v->as_double() : 0.0;
  }

  void report() {
    const double samples = static_cast<double>(spec_.image.width) * spec_.image.height * spec_.image.spp;
    if (!options_.quiet) {
      std::fprintf(stderr, "\n%-12s %9s %7s\n", "phase", "seconds", "share");
      for (const auto& [name, secs] : phases_)
        std::fprintf(stderr, "%-12s %9.3f %6.1f%%\n", name.c_str(), secs, 100.0 * secs / total_seconds_);
      std::fprintf(stderr, "%-12s %9.3f %6.1f%%\n\n", "total", total_seconds_, 100.0);
      std::fprintf(stderr, "%-14s %-10s %8s %9s %11s %9s %9s %8s %6s\n", "actor", "kind", "pid", "requests", "points",
                   "MiB in", "MiB out", "busy s", "peakq");
      for (const auto& a : spec_.actors) {
        const ActorState& s = actors_.at(a.name);
        if (s.lost) {
          std::fprintf(stderr, "%-14s %-10s %8d  lost: %s\n", a.name.c_str(), a.kind.c_str(), static_cast<int>(s.pid),
                       s.loss.c_str());
          continue;
        }
        std::fprintf(stderr, "%-14s %-10s %8d %9.0f %11.0f %9.2f %9.2f %8.3f %6.0f\n", a.name.c_str(), a.kind.c_str(),
                     static_cast<int>(s.pid), num(s.stats, "requests"), num(s.stats, "points"),
                     num(s.stats, "bytes_in") / 1048576.0, num(s.stats, "bytes_out") / 1048576.0,
                     num(s.stats, "busy_seconds"), num(s.stats, "peak_queue"));
      }
      std::fprintf(stderr, "\nrender: %.2f M samples/s\n", samples / render_seconds_ / 1e6);
      std::printf("wrote %s (%dx%d, %d spp)\n", spec_.image.output.c_str(), spec_.image.width, spec_.image.height,
                  spec_.image.spp);
    }
    if (!options_.stats_json.empty()) {
      Value::Map phases;
      for (const auto& [name, secs] : phases_) phases[name] = secs;
      phases["total"] = total_seconds_;
      Value::Array actors;
      double shading_requests = 0, messages = 0;
      for (const auto& a : spec_.actors) {
        const ActorState& st = actors_.at(a.name);
        if (a.is_renderer()) shading_requests += num(st.stats, "requests");
        messages += num(st.stats, "messages_out");
      }
      for (const auto& a : spec_.actors) {
        const ActorState& s = actors_.at(a.name);
        Value entry = s.stats.is_map() ? s.stats : Value(Value::Map{});
        entry.as_map()["name"] = a.name;
        entry.as_map()["kind"] = a.kind;
        entry.as_map()["pid"] = static_cast<int64_t>(s.pid);
        if (s.lost) entry.as_map()["lost"] = s.loss;
        actors.push_back(std::move(entry));
      }
      Value doc = Value::Map{{"script", spec_.script},
                             {"output", spec_.image.output},
                             {"image", spec_.image.to_value()},
                             {"phases_seconds", std::move(phases)},
                             {"render_samples_per_second", samples / render_seconds_},
                             {"first_tile_seconds", first_tile_seconds_},
                             {"render_seconds", render_seconds_},
                             {"totals", Value::Map{{"renderer_shading_requests", shading_requests},
                                                   {"messages_sent", messages}}},
                             {"actors", std::move(actors)}};
      if (ring_.active()) doc.as_map()["radiosity"] = ring_.report();
      std::ofstream out(options_.stats_json);
      out << to_json(doc, 2) << "\n";
      if (!out) log_warn("could not write stats to '" + options_.stats_json + "'");
    }
  }

  const FarmSpec& spec_;
  RunOptions options_;
  LocalLauncher launcher_;
  wire::Socket control_{wire::Socket::Kind::router};
  std::string control_endpoint_;
  std::map<std::string, ActorState> actors_;
  std::unique_ptr<RenderMaster> master_;
  RingCoordinator ring_;
  std::vector<std::pair<std::string, uint64_t>> waiting_fetches_;
  std::vector<std::pair<std::string, uint64_t>> waiting_tile_requests_;
  struct PendingGather {
    std::vector<Value> parts;     // nil until that replica sent its part
    std::vector<uint64_t> askers;  // request ids to answer
  };
  std::map<int, PendingGather> gathers_;
  std::unique_ptr<Progress> progress_;
  bool progress_active_ = false;
  std::string current_phase_ = "prepare";
  std::vector<std::pair<std::string, double>> phases_;
  Clock::time_point render_start_;
  Clock::time_point last_heartbeat_ = Clock::now();
  Clock::time_point start_;
  double render_seconds_ = 0;
  double first_tile_seconds_ = 0;  // from the director's start to the first finished tile
  double total_seconds_ = 0;
};

}  // namespace

int run_farm(const FarmSpec& spec, const RunOptions& options) { return Director(spec, options).run(); }

}  // namespace lf
