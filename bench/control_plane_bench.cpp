// The director alone against simulated actors: how far its control plane goes. The director runs here, unchanged
// (run_farm with a launcher of its own); the actors are simulated in one child process, each over its own TCP
// connection with its own routing id (one ZeroMQ ROUTER that connects once per actor), and answer as real actors
// do: HELLO, READY of every phase, HEARTBEAT every second (left out, as the runtime does, after anything else was
// sent since the last, up to three in a row), renderers' tiles (one being "rendered" for --tile-ms
// while the next is asked for, like a renderer's tiles in flight; the pixels are a grey of the tile's size, and
// the next tile is asked for with them, as the built-in renderer does — or, with --tile-requests alone (or both,
// each count run twice), by a request of its own, as a renderer that does not use tile_done's `next`; with
// --tiles-per-message 2 (renderers { tiles_per_message = 2 }) a finished tile waits for the next and both go in one
// tile_done asking for two, with three tiles held at most as the built-in renderer's tiles_in_flight), STATS
// and BYE. Nothing is rendered, so what is measured is the director: launch to last HELLO, configure, tiles per
// second against the tiles offered, its CPU share while tiles flow, its memory, and whether any actor was lost or
// went without the director's heartbeat.
//
//   build/bench/control_plane_bench [--curve] [--actors 100,1000,10000] [--tile-ms 200] [--tiles-per-renderer 6]
//                                   [--tile-requests with-pixels|alone|both] [--tiles-per-message 1,2]
//                                   [--json bench-control-plane.json]
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zmq.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <queue>
#include <sstream>
#include <string>
#include <set>
#include <unordered_map>
#include <vector>

#include "actors/codecs/control_codec.hpp"
#include "actors/director/director.hpp"
#include "actors/launchers/launcher.hpp"
#include "actors/runtime/hello.hpp"
#include "actors/runtime/runtime.hpp"
#include "bench_util.hpp"
#include "core/value.hpp"
#include "farm/builders.hpp"
#include "transport/message.hpp"

using namespace lf;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double cpu_seconds(int who) {
  rusage u{};
  getrusage(who, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// Lines through a pipe: the launcher's commands to the simulator, the simulator's exits and figures back.
bool write_line(int fd, const std::string& line) {
  const std::string text = line + "\n";
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

struct LineReader {
  int fd;
  std::string buffer;
  // Whatever whole lines are there now (non-blocking fd).
  std::vector<std::string> take() {
    char chunk[65536];
    for (;;) {
      const ssize_t n = ::read(fd, chunk, sizeof chunk);
      if (n <= 0) break;
      buffer.append(chunk, static_cast<size_t>(n));
    }
    std::vector<std::string> lines;
    size_t start = 0;
    for (size_t nl; (nl = buffer.find('\n', start)) != std::string::npos; start = nl + 1)
      lines.push_back(buffer.substr(start, nl - start));
    buffer.erase(0, start);
    return lines;
  }
};

// ---------------------------------------------------------------------------------------------------------------
// The simulated actors (the child process).

class Simulator {
 public:
  Simulator(int commands, int reports, double tile_ms, bool next_with_pixels, int per_message)
      : commands_{commands},
        reports_(reports),
        tile_ms_(tile_ms),
        next_with_pixels_(next_with_pixels),
        per_message_(per_message),
        capacity_(per_message + 1) {
    ctx_ = zmq_ctx_new();
    zmq_ctx_set(ctx_, ZMQ_IO_THREADS, 1);
    zmq_ctx_set(ctx_, ZMQ_MAX_SOCKETS, 64);
    router_ = zmq_socket(ctx_, ZMQ_ROUTER);
    const int linger = 0, hwm = 0;
    zmq_setsockopt(router_, ZMQ_LINGER, &linger, sizeof linger);
    zmq_setsockopt(router_, ZMQ_SNDHWM, &hwm, sizeof hwm);
    zmq_setsockopt(router_, ZMQ_RCVHWM, &hwm, sizeof hwm);
  }
  ~Simulator() {
    zmq_close(router_);
    zmq_ctx_term(ctx_);
  }

  int run() {
    while (!quit_) {
      for (const std::string& line : commands_.take()) command(line);
      fire_timers();
      long wait_ms = 100;
      if (!timers_.empty())
        wait_ms = std::clamp<long>(static_cast<long>(std::ceil(
                                       std::chrono::duration<double, std::milli>(timers_.top().due - Clock::now()).count())),
                                   0, 100);
      zmq_pollitem_t items[2] = {{router_, 0, ZMQ_POLLIN, 0}, {nullptr, commands_.fd, ZMQ_POLLIN, 0}};
      if (zmq_poll(items, 2, wait_ms) < 0 && zmq_errno() != EINTR) break;
      for (int burst = 0; burst < 4096 && receive(); ++burst) {
      }
    }
    report_figures();
    return 0;
  }

 private:
  struct Actor {
    std::string name, kind;
    long handle = 0;
    bool renderer = false, gone = false, rendering = false;
    int width = 0, height = 0;
    uint64_t next_id = 1;
    int asked = 0;                               // tiles asked for and not yet answered
    std::unordered_map<uint64_t, int> tile_asks;  // request id -> tiles it asked for
    bool none_left = false, said_ready = false;
    std::deque<control::Tile> assigned;  // the first is being rendered
    std::vector<control::FinishedTile> finished;  // rendered, waiting to go with the next
    Clock::time_point last_from_director;
    Clock::time_point last_sent, last_beat;  // anything, a beat (or its slot)
    int left_out = 0;                         // beats left out in a row
    double longest_silence = 0;  // the director's, seen by this actor
  };
  enum class What { beat, tile_finished };
  struct Timer {
    Clock::time_point due;
    size_t actor;
    What what;
    bool operator>(const Timer& o) const { return due > o.due; }
  };

  void command(const std::string& line) {
    std::istringstream in(line);
    std::string verb;
    in >> verb;
    if (verb == "start") {
      Actor a;
      std::string endpoint;
      std::string own_public, own_secret, director_public;
      in >> a.handle >> a.kind >> a.name >> endpoint >> own_public >> own_secret >> director_public;
      a.renderer = a.kind == "renderer";
      const size_t index = actors_.size();
      by_name_[a.name] = index;
      if (own_public != "-" && !own_public.empty()) {
        // ZeroMQ takes a socket's options into each connection as it is made: one keypair per actor.
        zmq_setsockopt(router_, ZMQ_CURVE_SERVERKEY, director_public.c_str(), director_public.size());
        zmq_setsockopt(router_, ZMQ_CURVE_PUBLICKEY, own_public.c_str(), own_public.size());
        zmq_setsockopt(router_, ZMQ_CURVE_SECRETKEY, own_secret.c_str(), own_secret.size());
      }
      zmq_setsockopt(router_, ZMQ_ROUTING_ID, a.name.data(), a.name.size());
      zmq_setsockopt(router_, ZMQ_CONNECT_ROUTING_ID, a.name.data(), a.name.size());
      if (zmq_connect(router_, endpoint.c_str()) != 0) {
        write_line(reports_, "exit " + std::to_string(a.handle) + " " + std::to_string(5 << 8));
        return;
      }
      a.last_from_director = Clock::now();
      actors_.push_back(a);
      Hello hello = my_hello(a.kind, "tcp://127.0.0.1:9");
      hello.pid = a.handle;
      send(index, wire::make(wire::MsgType::hello, a.name, hello.to_value()));
      // Beats spread over the second, as independent processes' would be.
      timers_.push({Clock::now() + std::chrono::milliseconds(static_cast<long>(index * 7919 % 1000)), index, What::beat});
    } else if (verb == "kill") {
      long handle = 0;
      int signal = 0;
      in >> handle >> signal;
      for (size_t i = 0; i < actors_.size(); ++i)
        if (actors_[i].handle == handle) leave(i, signal);
    } else if (verb == "quit") {
      quit_ = true;
    }
  }

  void leave(size_t i, int wait_status) {
    Actor& a = actors_[i];
    if (a.gone) return;
    a.gone = true;
    write_line(reports_, "exit " + std::to_string(a.handle) + " " + std::to_string(wait_status));
  }

  void send(size_t i, const wire::Message& m) {
    const Actor& a = actors_[i];
    const std::string header = wire::encode_header(m.header), body = wire::encode_body(m.body);
    zmq_send(router_, a.name.data(), a.name.size(), ZMQ_SNDMORE);
    zmq_send(router_, header.data(), header.size(), ZMQ_SNDMORE);
    zmq_send(router_, body.data(), body.size(), 0);
    ++sent_;
    actors_[i].last_sent = Clock::now();
  }

  int free_slots(const Actor& a) const {
    return a.none_left ? 0 : std::max(0, capacity_ - a.asked - static_cast<int>(a.assigned.size() + a.finished.size()));
  }

  void ask_tiles(size_t i, int count) {
    Actor& a = actors_[i];
    a.asked += count;
    a.tile_asks[a.next_id] = count;
    send(i, wire::make_request(a.name, wire::Op::tile, control::encode_tile_request(per_message_ > 1 ? count : 0),
                               a.next_id++));
  }

  // Keeps `capacity_` tiles with this renderer (one rendering, the rest asked for ahead or finished and waiting to
  // be sent); READY render once none is left.
  void keep_busy(size_t i) {
    Actor& a = actors_[i];
    while (int free = free_slots(a)) ask_tiles(i, per_message_ > 1 ? free : 1);
    if (!a.rendering && !a.assigned.empty()) {
      a.rendering = true;
      timers_.push({Clock::now() + std::chrono::microseconds(static_cast<long>(tile_ms_ * 1000)), i, What::tile_finished});
    }
    if (a.none_left && a.asked == 0 && a.assigned.empty() && a.finished.empty() && !a.rendering && !a.said_ready) {
      a.said_ready = true;
      send(i, wire::make_ready(a.name, wire::Phase::render));
    }
  }

  bool receive() {
    zmq_msg_t frames[3];
    int count = 0;
    for (;; ++count) {
      if (count == 3) return true;  // malformed: more frames than a message has (the rest is read next time)
      zmq_msg_init(&frames[count]);
      if (zmq_msg_recv(&frames[count], router_, ZMQ_DONTWAIT) < 0) {
        zmq_msg_close(&frames[count]);
        if (count == 0) return false;
        break;
      }
      if (!zmq_msg_more(&frames[count])) {
        ++count;
        break;
      }
    }
    if (count == 3) {
      const std::string name(static_cast<const char*>(zmq_msg_data(&frames[0])), zmq_msg_size(&frames[0]));
      auto decoded = wire::decode(
          std::string_view(static_cast<const char*>(zmq_msg_data(&frames[1])), zmq_msg_size(&frames[1])),
          std::string_view(static_cast<const char*>(zmq_msg_data(&frames[2])), zmq_msg_size(&frames[2])));
      if (auto it = by_name_.find(name); it != by_name_.end() && decoded) handle(it->second, *decoded);
    }
    for (int k = 0; k < count; ++k) zmq_msg_close(&frames[k]);
    ++received_;
    return true;
  }

  void handle(size_t i, const wire::Message& m) {
    Actor& a = actors_[i];
    if (a.gone) return;
    const auto now = Clock::now();
    a.longest_silence = std::max(a.longest_silence, std::chrono::duration<double>(now - a.last_from_director).count());
    a.last_from_director = now;
    switch (m.header.type) {
      case wire::MsgType::config:
        if (const Value* image = m.body.find("image")) {
          if (const Value* w = image->find("width")) a.width = static_cast<int>(w->as_int());
          if (const Value* h = image->find("height")) a.height = static_cast<int>(h->as_int());
        }
        send(i, wire::make_ready(a.name, wire::Phase::configure));
        break;
      case wire::MsgType::phase: {
        const auto phase = wire::phase_of(m.header);
        if (!phase) break;
        if (*phase == wire::Phase::finish) {
          send(i, wire::make(wire::MsgType::stats, a.name, Value::Map{{"tiles", int64_t{0}}}));
          send(i, wire::make(wire::MsgType::bye, a.name));
          leave(i, 0);
        } else if (*phase == wire::Phase::render && a.renderer) {
          keep_busy(i);
        } else {
          send(i, wire::make_ready(a.name, *phase));
        }
        break;
      }
      case wire::MsgType::reply: {
        auto ask = a.tile_asks.find(m.header.id);
        if (ask == a.tile_asks.end()) break;  // a tile_done's
        a.asked -= ask->second;
        a.tile_asks.erase(ask);
        auto tiles = control::decode_tile_reply(m.body, a.width, a.height);
        if (tiles && !tiles->empty())
          a.assigned.insert(a.assigned.end(), tiles->begin(), tiles->end());
        else
          a.none_left = true;
        keep_busy(i);
        break;
      }
      case wire::MsgType::bye:
        send(i, wire::make(wire::MsgType::bye, a.name));
        leave(i, 0);
        break;
      default:
        break;  // heartbeats (counted above), errors
    }
  }

  void fire_timers() {
    const auto now = Clock::now();
    while (!timers_.empty() && timers_.top().due <= now) {
      const Timer t = timers_.top();
      timers_.pop();
      Actor& a = actors_[t.actor];
      if (a.gone) continue;
      if (t.what == What::beat) {
        // As the runtime beats: left out after anything else was sent since the last beat, up to three in a row.
        if (a.left_out < Runtime::kBeatsLeftOut && a.last_sent > a.last_beat) {
          ++a.left_out;
        } else {
          send(t.actor, wire::make(wire::MsgType::heartbeat, a.name));
          a.left_out = 0;
        }
        a.last_beat = Clock::now();  // after the beat's own send
        timers_.push({t.due + std::chrono::seconds(1), t.actor, What::beat});
      } else {
        const control::Tile tile = a.assigned.front();
        a.assigned.pop_front();
        a.rendering = false;
        a.finished.push_back({tile.id, std::vector<float>(static_cast<size_t>(3 * tile.rect.pixel_count()), 0.5f)});
        ++tiles_;
        // As the built-in renderer: a finished tile waits for the next while another is held.
        if (static_cast<int>(a.finished.size()) >= per_message_ || a.assigned.empty()) {
          const std::vector<control::FinishedTile> sending = std::move(a.finished);
          a.finished.clear();
          const uint64_t id = a.next_id++;
          const int next = next_with_pixels_ ? (per_message_ > 1 ? free_slots(a) : std::min(1, free_slots(a))) : 0;
          if (next > 0) a.asked += next, a.tile_asks[id] = next;
          send(t.actor, wire::make_request(a.name, wire::Op::tile_done,
                                           per_message_ > 1 ? control::encode_tile_done(sending, next)
                                                            : control::encode_tile_done(sending[0].id, sending[0].rgb, next > 0),
                                           id));
        }
        keep_busy(t.actor);
      }
    }
  }

  void report_figures() {
    double longest = 0;
    for (const Actor& a : actors_) longest = std::max(longest, a.longest_silence);
    write_line(reports_, "figures " + std::to_string(cpu_seconds(RUSAGE_SELF)) + " " + std::to_string(longest) + " " +
                             std::to_string(sent_) + " " + std::to_string(received_) + " " + std::to_string(tiles_));
  }

  LineReader commands_;
  int reports_;
  double tile_ms_;
  bool next_with_pixels_;  // the next tile asked for in tile_done (the built-in renderer), else by a request of its own
  int per_message_;        // finished tiles a tile_done carries (and tiles asked for at once)
  int capacity_;           // tiles held at once: rendering, asked for, finished and not yet sent
  void* ctx_ = nullptr;
  void* router_ = nullptr;
  bool quit_ = false;
  std::vector<Actor> actors_;
  std::unordered_map<std::string, size_t> by_name_;
  std::priority_queue<Timer, std::vector<Timer>, std::greater<>> timers_;
  uint64_t sent_ = 0, received_ = 0, tiles_ = 0;
};

// ---------------------------------------------------------------------------------------------------------------
// The director's side: a launcher whose processes are the simulator's actors.

struct SimulatorFigures {
  double cpu = 0, longest_director_silence = 0;
  uint64_t sent = 0, received = 0, tiles = 0;
};

class SimulatedLauncher final : public Launcher {
 public:
  SimulatedLauncher(int commands, int reports) : commands_(commands), reports_{reports} {}
  std::string name() const override { return "simulated"; }
  Result<Shipped> ship(const std::string&, const std::string&) override { return make_error("no scene files here"); }
  Result<pid_t> start(const LaunchRequest& request) override {
    std::map<std::string, std::string> opt;
    for (size_t i = 2; i + 1 < request.argv.size(); ++i)
      if (request.argv[i].rfind("--", 0) == 0) opt[request.argv[i].substr(2)] = request.argv[i + 1];
    const pid_t handle = next_++;
    running_.insert(handle);
    // With CURVE, the actor's keys (the first line of its stdin: LFKEYS1 own-public own-secret director ...).
    std::string keys = "-";
    if (!request.stdin_text.empty()) {
      std::istringstream in(request.stdin_text);
      std::string magic, own_public, own_secret, director_public;
      in >> magic >> own_public >> own_secret >> director_public;
      keys = own_public + " " + own_secret + " " + director_public;
    }
    write_line(commands_, "start " + std::to_string(handle) + " " + opt["kind"] + " " + opt["name"] + " " +
                              opt["director"] + " " + keys);
    return handle;
  }
  std::optional<ExitReport> reap_one() override {
    for (const std::string& line : reports_.take()) {
      std::istringstream in(line);
      std::string verb;
      in >> verb;
      if (verb == "exit") {
        long handle = 0;
        int status = 0;
        in >> handle >> status;
        exits_.push_back({static_cast<pid_t>(handle), status});
      } else if (verb == "figures") {
        in >> figures.cpu >> figures.longest_director_silence >> figures.sent >> figures.received >> figures.tiles;
        have_figures = true;
      }
    }
    if (exits_.empty()) return std::nullopt;
    const ExitReport e = exits_.front();
    exits_.pop_front();
    running_.erase(e.pid);
    return e;
  }
  void kill(pid_t pid, int signal) override { write_line(commands_, "kill " + std::to_string(pid) + " " + std::to_string(signal)); }
  void stop_all(std::chrono::milliseconds grace) override {
    const auto until = Clock::now() + grace;
    while (!running_.empty() && Clock::now() < until) {
      while (reap_one()) {
      }
      usleep(2000);
    }
    for (pid_t p : running_) kill(p, SIGKILL);
    while (!running_.empty()) {
      while (reap_one()) {
      }
      usleep(2000);
    }
  }
  // Asks the simulator for its figures and to end.
  void finish() {
    write_line(commands_, "quit");
    for (int i = 0; i < 5000 && !have_figures; ++i) {
      reap_one();
      usleep(2000);
    }
    if (!have_figures) std::fprintf(stderr, "the simulator sent no figures\n");
  }

  SimulatorFigures figures;
  bool have_figures = false;

 private:
  int commands_;
  LineReader reports_;
  std::deque<ExitReport> exits_;
  std::set<pid_t> running_;
  pid_t next_ = 100000;
};

struct Row {
  int actors = 0, renderers = 0, tiles = 0;
  bool next_with_pixels = true;
  int per_message = 1;
  int status = 0;
  double hello = 0, configure = 0, render = 0, launch_to_first_tile = 0;
  double offered_tiles_per_second = 0, tiles_per_second = 0;
  double director_cpu_render = 0;  // share of one core while tiles flow
  double director_cpu_total = 0, director_peak_mb = 0, simulator_cpu = 0, longest_director_silence = 0;
  int lost = 0;
};

// CPU seconds of this process, sampled while the director runs, to take its share during the render stage alone.
class CpuSampler {
 public:
  CpuSampler() : start_(Clock::now()), thread_([this] {
    while (!stop_) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        samples_.push_back({seconds_since(start_), cpu_seconds(RUSAGE_SELF)});
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }) {}
  ~CpuSampler() {
    stop_ = true;
    thread_.join();
  }
  // CPU seconds per second between t0 and t1 (seconds since construction).
  double share(double t0, double t1) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto at = [&](double t) {
      for (size_t i = 1; i < samples_.size(); ++i)
        if (samples_[i].first >= t) return samples_[i].second;
      return samples_.empty() ? 0.0 : samples_.back().second;
    };
    return t1 > t0 ? (at(t1) - at(t0)) / (t1 - t0) : 0.0;
  }

 private:
  Clock::time_point start_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::pair<double, double>> samples_;
  std::thread thread_;
};

// The director's side of one measurement, in a process of its own (a director ends every child of its process
// when its farm ends, so the simulator must not be one). Writes its figures as one line to `result`.
void run_director(int actors, int tiles_per_renderer, bool curve, int commands, int reports, int result) {
  Row row;
  row.actors = actors;
  row.renderers = actors - 1;
  // One `direct` and the rest renderers; tiles of 16 x 16, enough for every renderer to take several.
  FarmSpec spec;
  spec.scene.builtin = "cornell";
  const int tile = 16;
  row.tiles = row.renderers * tiles_per_renderer;
  const int across = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(row.tiles))));
  spec.image.width = across * tile;
  spec.image.height = static_cast<int>(std::ceil(static_cast<double>(row.tiles) / across)) * tile;
  row.tiles = (spec.image.width / tile) * (spec.image.height / tile);
  spec.image.spp = 1;
  spec.image.tile = tile;
  const auto out = std::filesystem::temp_directory_path() / ("control-plane-" + std::to_string(getpid()));
  std::filesystem::create_directories(out);
  spec.image.output = (out / "frame.exr").string();
  spec.security = curve ? "curve" : "none";
  spec.light_paths = "partial";
  const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  add_renderers(spec, row.renderers, direct, RendererParams{}, {}, {});
  Launchers launchers;
  auto owned = std::make_unique<SimulatedLauncher>(commands, reports);
  SimulatedLauncher* sim = owned.get();
  launchers.set("local", std::move(owned));
  RunOptions options;
  options.quiet = true;
  options.checkpoint_every = 0;
  options.stats_json = (out / "stats.json").string();
  double render_share = 0;
  {
    CpuSampler sampler;
    row.status = run_farm(spec, options, launchers);
    std::ifstream in(options.stats_json);
    const std::string stats((std::istreambuf_iterator<char>(in)), {});
    row.hello = bench::phase_seconds(stats, "hello");
    row.configure = bench::phase_seconds(stats, "configure");
    row.render = bench::json_number(stats, "render_seconds");
    row.launch_to_first_tile = bench::json_number(stats, "first_tile_seconds");
    for (size_t at = stats.find("\"lost\""); at != std::string::npos; at = stats.find("\"lost\"", at + 1)) ++row.lost;
    const double before_render = bench::phase_seconds(stats, "prepare") + bench::phase_seconds(stats, "launch") +
                                 row.hello + row.configure + bench::phase_seconds(stats, "setup");
    render_share = sampler.share(before_render, before_render + row.render);
  }
  sim->finish();
  std::filesystem::remove_all(out);
  std::ostringstream line;
  line << row.status << " " << row.tiles << " " << row.hello << " " << row.configure << " " << row.render << " "
       << row.launch_to_first_tile << " " << render_share << " " << row.lost << " " << sim->figures.cpu << " "
       << sim->figures.longest_director_silence;
  write_line(result, line.str());
}

Row measure(int actors, double tile_ms, int tiles_per_renderer, bool curve, bool next_with_pixels, int per_message) {
  int commands[2], reports[2], result[2];
  if (pipe(commands) != 0 || pipe(reports) != 0 || pipe(result) != 0) std::exit(1);
  std::fflush(stdout);
  const pid_t simulator = fork();
  if (simulator == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives the bench
    close(commands[1]);
    close(reports[0]);
    close(result[0]);
    close(result[1]);
    fcntl(commands[0], F_SETFL, O_NONBLOCK);
    Simulator sim(commands[0], reports[1], tile_ms, next_with_pixels, per_message);
    _exit(sim.run());
  }
  close(commands[0]);
  close(reports[1]);
  const pid_t director = fork();
  if (director == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    close(result[0]);
    fcntl(reports[0], F_SETFL, O_NONBLOCK);
    run_director(actors, tiles_per_renderer, curve, commands[1], reports[0], result[1]);
    _exit(0);
  }
  close(commands[1]);
  close(reports[0]);
  close(result[1]);
  std::string text;
  char chunk[4096];
  for (ssize_t n; (n = ::read(result[0], chunk, sizeof chunk)) > 0;) text.append(chunk, static_cast<size_t>(n));
  close(result[0]);
  int status = 0;
  rusage usage{};
  wait4(director, &status, 0, &usage);
  waitpid(simulator, nullptr, 0);
  Row row;
  row.actors = actors;
  row.next_with_pixels = next_with_pixels;
  row.per_message = per_message;
  row.renderers = actors - 1;
  std::istringstream in(text);
  in >> row.status >> row.tiles >> row.hello >> row.configure >> row.render >> row.launch_to_first_tile >>
      row.director_cpu_render >> row.lost >> row.simulator_cpu >> row.longest_director_silence;
  if (!in) row.status = -1;
  row.director_cpu_total = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                           1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  row.director_peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  row.tiles_per_second = row.render > 0 ? row.tiles / row.render : 0;
  row.offered_tiles_per_second = row.renderers * 1000.0 / tile_ms;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::string counts = "100,300,1000,3000,10000";
  double tile_ms = 200;
  int tiles_per_renderer = 6;
  std::string json_path = "bench-control-plane.json";
  bool curve = false;
  std::string tile_requests = "with-pixels";
  std::string per_message_text = "1,2";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--actors") && i + 1 < argc) counts = argv[++i];
    else if (!std::strcmp(argv[i], "--tile-ms") && i + 1 < argc) tile_ms = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--tiles-per-renderer") && i + 1 < argc) tiles_per_renderer = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) json_path = argv[++i];
    else if (!std::strcmp(argv[i], "--curve")) curve = true;
    else if (!std::strcmp(argv[i], "--tile-requests") && i + 1 < argc) tile_requests = argv[++i];
    else if (!std::strcmp(argv[i], "--tiles-per-message") && i + 1 < argc) per_message_text = argv[++i];
    else {
      std::fprintf(stderr, "usage: control_plane_bench [--curve] [--actors 100,1000] [--tile-ms MS] [--tiles-per-renderer N] "
                           "[--tile-requests with-pixels|alone|both] [--tiles-per-message 1,2] [--json FILE]\n");
      return 2;
    }
  }
  if (tile_requests != "alone" && tile_requests != "with-pixels" && tile_requests != "both") {
    std::fprintf(stderr, "--tile-requests is with-pixels, alone or both\n");
    return 2;
  }
  std::vector<bool> modes;  // the next tile with the pixels, or alone
  if (tile_requests != "alone") modes.push_back(true);
  if (tile_requests != "with-pixels") modes.push_back(false);
  std::vector<int> per_messages;
  {
    std::stringstream in(per_message_text);
    for (std::string item; std::getline(in, item, ',');) {
      const int k = std::atoi(item.c_str());
      if (k < 1 || k > control::kMaxTilesPerMessage) {
        std::fprintf(stderr, "--tiles-per-message takes counts from 1 to %d\n", control::kMaxTilesPerMessage);
        return 2;
      }
      per_messages.push_back(k);
    }
  }
  // Every actor is a TCP connection at each end.
  rlimit files{};
  getrlimit(RLIMIT_NOFILE, &files);
  files.rlim_cur = files.rlim_max;
  setrlimit(RLIMIT_NOFILE, &files);
  std::printf("lightfarm control-plane benchmark: the director against simulated actors (one `direct`, the rest "
              "renderers), a tile every %.0f ms per renderer, %d tiles per renderer, 16x16 tiles, security %s\n\n",
              tile_ms, tiles_per_renderer, curve ? "CURVE" : "none");
  std::printf("%-12s %8s %7s %6s %8s %8s %10s %12s %12s %12s %10s %10s %8s %6s\n", "next tile", "tiles/msg", "actors", "exit", "hello s", "config s",
              "1st tile s", "tiles/s", "offered/s", "dir CPU rnd", "dir MB", "sim CPU s", "max gap", "lost");
  lf::Value::Array runs;
  std::stringstream list(counts);
  for (std::string item; std::getline(list, item, ',');) {
    for (const int per_message : per_messages)
    for (const bool next_with_pixels : modes) {
      const Row r = measure(std::atoi(item.c_str()), tile_ms, tiles_per_renderer, curve, next_with_pixels, per_message);
      std::printf("%-12s %8d %7d %6d %8.2f %8.2f %10.2f %12.0f %12.0f %12.3f %10.0f %10.1f %8.2f %6d\n",
                  r.next_with_pixels ? "with pixels" : "alone", r.per_message, r.actors, r.status,
                  r.hello, r.configure, r.launch_to_first_tile, r.tiles_per_second, r.offered_tiles_per_second,
                  r.director_cpu_render, r.director_peak_mb, r.simulator_cpu, r.longest_director_silence, r.lost);
      std::fflush(stdout);
      runs.push_back(lf::Value::Map{{"actors", r.actors},
                                    {"next_tile", r.next_with_pixels ? "with_pixels" : "alone"},
                                    {"tiles_per_message", r.per_message},
                                    {"exit_status", r.status},
                                    {"tiles", r.tiles},
                                    {"hello_seconds", r.hello},
                                    {"configure_seconds", r.configure},
                                    {"render_seconds", r.render},
                                    {"launch_to_first_tile_seconds", r.launch_to_first_tile},
                                    {"tiles_per_second", r.tiles_per_second},
                                    {"offered_tiles_per_second", r.offered_tiles_per_second},
                                    {"director_cpu_share_render", r.director_cpu_render},
                                    {"director_cpu_seconds", r.director_cpu_total},
                                    {"director_peak_rss_mb", r.director_peak_mb},
                                    {"simulator_cpu_seconds", r.simulator_cpu},
                                    {"longest_director_silence_seconds", r.longest_director_silence},
                                    {"lost", r.lost}});
    }
  }
  const lf::Value doc = lf::Value::Map{{"benchmark", "control_plane"},
                                       {"security", curve ? "curve" : "none"},
                                       {"tile_ms", tile_ms},
                                       {"tiles_per_renderer", tiles_per_renderer},
                                       {"runs", std::move(runs)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
