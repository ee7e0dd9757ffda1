#pragma once
// The actor runtime: one process, one poll loop. It owns the control channel to the director (HELLO, CONFIG,
// PHASE, HEARTBEAT, STATS, BYE), the data socket where peers send requests, and one RequestClient per input.
// Actor logic (renderer, LightOp wrapper) is an Actor: handlers the runtime calls; it never touches sockets.
//
// Life of an actor process:
//   start -> bind data socket -> HELLO -> CONFIG (decoded into ActorConfig, inputs connected) -> configure()
//         -> READY configure
//         -> PHASE setup -> on_phase("setup") ... phase_done("setup") -> READY setup
//         -> PHASE render -> on_phase("render") ...
//         (a job of several frames: -> PHASE frame -> on_frame(view) ... phase_done("frame") -> PHASE setup ...
//          -> PHASE render ...)
//         -> PHASE finish (or BYE) -> STATS -> BYE -> exit 0
// It exits non-zero after fail(), and on its own when the director is silent for longer than the heartbeat
// timeout or SIGINT/SIGTERM arrives: an actor never outlives its farm.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/connections.hpp"
#include "actors/runtime/process.hpp"
#include "actors/runtime/pool_client.hpp"
#include "core/log.hpp"
#include "core/value.hpp"
#include "transport/client.hpp"
#include "transport/security.hpp"
#include "transport/socket.hpp"

namespace lf {

struct ActorArgs {
  std::string kind;
  std::string name;
  std::string director;               // control endpoint, e.g. tcp://127.0.0.1:5555
  std::string bind = "tcp://127.0.0.1:*";  // where the data socket listens
  std::optional<wire::FarmKeys> keys;       // set: every link is CURVE (--curve; the keys come on stdin)
};

struct ActorStats {
  uint64_t requests = 0;      // requests served (LightOps) or sent (renderers)
  uint64_t points = 0;        // shading points shaded (LightOps) or traced (renderers)
  uint64_t tiles = 0;         // renderers only
  double busy_seconds = 0;    // time inside handlers
  uint32_t peak_queue = 0;    // longest request queue seen
  double start_seconds = 0;      // from the process's start (exec) to READY configure
  double configure_seconds = 0;  // CONFIG to READY configure: loading the scene, building the BVH
  Value to_value(const wire::SocketCounters& totals) const;
};


class Runtime;

// PHASE frame: a job's next view.
struct FrameView {
  int frame = 0;
  CameraSpec camera;
  // False while the director replays the views of frames a run does not render (a resumed job) for an actor that no
  // setup carried over the frames asks: it need not set itself up for this view (the next rendered frame's PHASE
  // frame says true).
  bool renew = true;
  // A job with a record: an op that carries its setup over the views keeps it with the director once extended
  // (REQUEST keep_setup), or, `restore`, takes the one the director publishes as "setup/<actor>" instead of
  // extending (a resumed job).
  bool keep = false;
  bool restore = false;
  // The frame's material changes over the shipped scene (frames { materials }; empty: none). An actor holding the
  // scene makes them (actors/runtime/frame_scene.hpp) where they differ from those it holds.
  Value::Array materials;
  // The materials change at this frame (they differ from the frame before's in the job): every actor sets up anew
  // whatever it set up over the scene, renew or not, as a farm of this frame alone would (a resumed run that skips
  // frames gets this at the change it skipped to, taken before the frame it renders).
  bool new_materials = false;
  // A job's frames in flight: the frame before, this number, is still rendering. Its requests (those that name it as
  // their view) are answered as they would have been, while this view is set up; this view's wait for that setup.
  std::optional<int> in_flight;
};

class Actor {
 public:
  virtual ~Actor() = default;
  // CONFIG arrived, decoded and checked; the inputs are connected. Load what is needed; an error stops the actor
  // and is reported to the director.
  virtual Status configure(const ActorConfig& config, Runtime& rt) = 0;
  // PHASE setup or render arrived. Call rt.phase_done(phase) when the phase's work is finished: every actor
  // answers both (a LightOp answers render at once; it renders by answering requests).
  virtual void on_phase(wire::Phase phase, Runtime& rt) = 0;
  // PHASE frame arrived: the job's next frame, seen by `view.camera`. Take the view and call rt.phase_done(frame);
  // at the PHASE setup that follows, redo what depends on it (when view.renew). By default the actor has nothing
  // that depends on the view.
  virtual void on_frame(const FrameView& view, Runtime& rt);
  // A REQUEST on the data socket (`op` is Op::unknown for a name not in the protocol; the raw name is in the
  // header). Answer now or later with rt.reply / rt.reply_error.
  virtual void on_request(const std::string& peer, wire::Op op, wire::Message& request, Runtime& rt) = 0;
  // After any input's replies were dispatched, and after each request: a chance to make progress.
  virtual void on_progress(Runtime&) {}
  // Requests waiting to be served (piggybacked on replies for load balancing).
  virtual size_t queue_length() const { return 0; }
  // True while the actor has work it can do right now (the loop then polls without sleeping).
  virtual bool has_local_work() const { return queue_length() > 0; }
  // PEER_DOWN: input `name` is gone. By default that ends this actor; a multiplexer re-routes instead.
  virtual void on_peer_down(const std::string& name, Runtime& rt);
  // PEER_MOVED: input `name` was restarted; the runtime has connected to its new endpoint and forgotten what was
  // outstanding with the old process (no callbacks run). By default that ends this actor; a ring node's ROLLBACK
  // follows, which redoes the work.
  virtual void on_peer_moved(const std::string& name, Runtime& rt);
  // ROLLBACK (ring nodes): the director rolls the phase's work back to a checkpoint. By default that ends this actor.
  virtual void on_rollback(const Value& body, Runtime& rt);
  // How long the loop may sleep before this actor has something due (ms); -1: nothing due.
  virtual long next_due_ms() const { return -1; }
  // Added to STATS under "detail" (e.g. a multiplexer's per-replica counts).
  virtual Value extra_stats() const { return Value(); }
};

class Runtime {
 public:
  // Heartbeats left out in a row on a control link that carried something else since the last (start_heartbeats).
  static constexpr int kBeatsLeftOut = 3;
  explicit Runtime(ActorArgs args);
  ~Runtime();
  // Runs until the farm ends; returns the process exit status.
  int run(Actor& actor);
  // Ends run() at its next turn as SIGTERM would (status 143), from any thread: for a runtime hosted on a thread of
  // another program, which no signal can reach alone (actors/director/director.test.cpp's launcher).
  void stop() { stop_asked_ = true; }

  const std::string& name() const { return args_.name; }
  const std::string& kind() const { return args_.kind; }

  void reply(const std::string& peer, uint64_t id, Value body);
  void reply_error(const std::string& peer, uint64_t id, ErrorCode code, const std::string& message);
  // The standard answer to an operation this actor does not serve.
  void reply_unknown_op(const std::string& peer, const wire::Message& request, const std::string& served);

  // The lighting network's inputs, in script order. An input is one actor, or a pool whose replicas this actor
  // dispatches to itself (CONFIG inputs[i].pool): ask_input() serves both; input(i) is the connection of a single
  // actor (ring nodes, a multiplexer's replicas).
  size_t input_count() const { return connections_.lighting().size(); }
  // `part` >= 0: the body's points lie in that part of a partitioned scene, and a pool sends them to a replica that
  // holds it (partition { colocate = true }).
  void ask_input(size_t i, wire::Op op, Value body, wire::RequestClient::Callback callback, int64_t part = -1);
  // Input i is a pool some of whose replicas hold a scene part themselves: the asker should say each request's part.
  bool input_holds_parts(size_t i) const { return connections_.lighting()[i].holds_parts; }
  bool input_is_pool(size_t i) const { return connections_.lighting()[i].pool != nullptr; }
  // Input i takes normals and materials from the scene (CONFIG inputs[i].lean; a pool: every replica does).
  bool input_is_lean(size_t i) const { return connections_.lighting()[i].lean; }
  // Where input i's answer can be other than zero (CONFIG inputs[i].answers_at); nullopt: anywhere.
  const std::optional<AnswerEnds>& input_answers(size_t i) const { return connections_.lighting()[i].answers; }
  // Throws for a pool.
  wire::RequestClient& input(size_t i) { return *connections_.rows().at(connections_.lighting()[i].row).client; }
  const std::string& input_name(size_t i) const { return connections_.lighting()[i].name; }
  // A partitioned scene's geometry actors (CONFIG 'geometry', part order), connected like inputs and polled with
  // them, but not inputs of the lighting network.
  size_t geometry_count() const { return connections_.count(Group::geometry); }
  wire::RequestClient& geometry(size_t part) { return *connections_.in_group(Group::geometry, part).client; }
  const std::string& geometry_name(size_t part) { return connections_.in_group(Group::geometry, part).name; }
  // The other replicas of this actor's pool when it shares its setup peer to peer (CONFIG pool.peers, replica
  // order), connected like inputs; not inputs of the lighting network.
  size_t pool_peer_count() const { return connections_.count(Group::pool_peer); }
  wire::RequestClient& pool_peer(size_t k) { return *connections_.in_group(Group::pool_peer, k).client; }
  const std::string& pool_peer_name(size_t k) { return connections_.in_group(Group::pool_peer, k).name; }

  using DirectorCallback = std::function<void(Result<wire::Message>)>;
  // A request to the director (tiles, results), answered by a REPLY on the control channel.
  void ask_director(wire::Op op, Value body, DirectorCallback callback);
  void phase_done(wire::Phase phase);
  // Reports the failure to the director and stops the actor with a non-zero status.
  void fail(const std::string& message);
  // PROGRESS of a long setup step to the director: at most 4 a second per step, and always its first and last.
  void report_progress(const std::string& what, uint64_t done, uint64_t total);

  ActorStats& stats() { return stats_; }
  // Adds the time since `since` to busy time.
  void add_busy(std::chrono::steady_clock::time_point since);

 private:
  using Group = Connections::Group;
  void handle_control(wire::Message& m, Actor& actor);
  void on_config(const wire::Message& m, Actor& actor);
  void on_peer_moved(const wire::Message& m, Actor& actor);
  // Connects input `name` at `endpoint` (with the peer's CURVE `key`, empty for a same-host IPC endpoint).
  Result<std::unique_ptr<wire::RequestClient>> connect_input(const std::string& name, const std::string& endpoint,
                                                             const std::string& key, size_t window);
  void handle_data(Actor& actor, wire::Socket& socket);
  wire::Socket& socket_of(const std::string& peer);
  void send_control(wire::Message m);
  void send_stats_and_bye();

  ActorArgs args_;
  std::unique_ptr<wire::Authenticator> authenticator_;  // before the sockets: it serves their handshakes
  Actor* actor_ = nullptr;
  wire::Socket control_;
  wire::Socket data_;
  std::string data_endpoint_;
  // A CURVE farm's actors on one host talk over IPC in a folder only this user can enter (0700): no encryption
  // where the operating system already keeps strangers out (docs/decisions.md). Peers that used it get answers on it.
  std::unique_ptr<wire::Socket> local_;
  std::string local_dir_, local_endpoint_;
  std::map<std::string, wire::Socket*> reply_via_;
  RateLimitedLog bad_messages_;  // anyone can send garbage; it must not flood the log
  // Every connection this actor asks on: single lighting inputs and pools' replicas, geometry actors, pool peers.
  Connections connections_{[this](const std::string& name, const std::string& endpoint, const std::string& key,
                                  size_t window) { return connect_input(name, endpoint, key, window); }};
  std::map<uint64_t, DirectorCallback> director_pending_;
  uint64_t next_director_id_ = 1;
  ActorStats stats_;
  double heartbeat_timeout_ = 30.0;
  double request_timeout_ = 0;
  // Heartbeats come from a thread with a control socket of its own (routing id NAME#heartbeat), so that one long
  // shade or setup never looks like death; a stopped or killed process still goes silent.
  void start_heartbeats();
  void stop_heartbeats();
  std::thread heartbeat_thread_;
  std::atomic<bool> heartbeat_stop_{false};
  std::mutex heartbeat_mutex_;
  std::condition_variable heartbeat_wake_;
  void set_heartbeat_interval(double seconds);
  // The running figures each HEARTBEAT carries (for the director's monitor), refreshed by the main loop.
  void refresh_live(size_t queue_length);
  std::mutex live_mutex_;
  Value live_;
  std::chrono::steady_clock::time_point live_refreshed_{};
  std::atomic<double> heartbeat_interval_{1.0};
  // When this actor last sent the director anything (steady clock ticks): a beat is left out on a link that carried
  // something within the interval, up to kBeatsLeftOut in a row (the monitor's figures ride on beats).
  std::atomic<std::chrono::steady_clock::rep> last_control_send_{0};
  bool configured_ = false;
  bool stopping_ = false;
  std::atomic<bool> stop_asked_{false};
  int exit_status_ = 0;
  std::map<std::string, std::chrono::steady_clock::time_point> progress_sent_;
};

// The routing id an actor's heartbeat thread uses towards the director, and back: the actor a routing id beats for
// (nullopt for any other id).
std::string heartbeat_identity(const std::string& actor);
std::optional<std::string> heartbeat_owner(const std::string& identity);

}  // namespace lf
