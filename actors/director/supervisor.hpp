#pragma once
// The supervisor: the director's actor table. It launches every actor through its host's launcher, reads what
// actors say on the control channel (HELLO, READY, STATS, BYE, HEARTBEAT, ERROR; REQUESTs go to the services),
// watches heartbeats and process exits, and decides what a death means:
//   - during setup and render, a renderer or a pool replica that dies or misses heartbeats (it is then SIGKILLed, so
//     it can never answer late) is *lost*: the services hear of it (its tiles go back), and a replica's pool gets
//     PEER_DOWN and re-sends its packets; the last renderer, or a pool's last replica, stops the farm naming each
//     loss (a nested pool left empty is itself a lost replica of the pool above);
//   - a radiosity ring node that dies or hangs from start-up to the end of render (its elements exist nowhere
//     else) is *restarted*: the same command again, up to kMaxRestarts times. One not yet configured just joins
//     like the others; otherwise the services hear of the loss (the ring service rolls the ring back), the director
//     configures the new process when it says HELLO and tells the others where it listens once it is READY
//     configure. One lost after the ring's solution is complete is simply lost;
//   - any other death, an ERROR from an actor, or a bad HELLO stops the farm with a message naming the actor.
// Socket-free: the director passes messages in and sends what the supervisor says through an Outbox, so the
// supervisor is tested by feeding it messages and exits (supervisor.test.cpp).
#include <sys/types.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>
#include <unordered_map>
#include <optional>
#include <utility>
#include <string>
#include <vector>

#include "actors/launchers/launcher.hpp"
#include "actors/director/service.hpp"
#include "actors/director/stage.hpp"
#include "core/log.hpp"
#include "core/result.hpp"
#include "farm/farm_spec.hpp"
#include "transport/message.hpp"

namespace lf {

// How often the director beats: four times per timeout, and at least once a second (docs/PROTOCOL.md).
inline double heartbeat_interval(double heartbeat_timeout) { return std::min(1.0, heartbeat_timeout / 4); }

using Clock = std::chrono::steady_clock;

struct ActorRecord {
  const ActorSpec* spec = nullptr;
  int index = -1;  // in FarmSpec::actors
  pid_t pid = 0;
  std::string endpoint;  // its data socket, from HELLO
  std::string local_endpoint;  // its same-host IPC socket, if it offered one
  std::optional<wire::Phase> ready;  // the last phase it said READY for
  bool said_hello = false;
  bool said_bye = false;
  bool exited = false;
  bool lost = false;         // died or hung after launch, and the farm went on without it
  bool configured = false;   // CONFIG was sent
  bool killed_hung = false;  // SIGKILLed for missing heartbeats
  int restarts = 0;          // times this actor's process was started again
  bool rejoining = false;    // restarted, and not yet READY configure
  std::string loss;          // why it was lost
  Clock::time_point last_seen;
  Value stats;
  Value live;                   // its last HEARTBEAT's figures (requests, points, busy_seconds, queue, ...), if any
  Clock::time_point live_at{};  // when they came
  const std::string& name() const { return spec->name; }
};

// What the supervisor hands the director, in the order it happened (as radiosity/ring_protocol returns actions):
// the director routes each in one place (Director::route).
struct SupervisorEvent {
  enum class Kind {
    request,           // a REQUEST for a director service: `message`
    lost,              // `actor` was lost (`why`) and the farm goes on: the services take back its work
    peer_down,         // then, for a pool's replica: tell `to`, who dispatches to the pool, that `actor` is gone
    hello_again,       // a restarted actor said HELLO: it needs its CONFIG
    configured_again,  // ... and READY configure: it rejoins the phase under way
    progress,          // PROGRESS from `actor`: `what` is `done` of `total`
  };
  Kind kind = Kind::request;
  std::string actor;
  wire::Message message;  // request
  std::string why;        // lost
  std::string to;         // peer_down
  std::string what;       // progress
  uint64_t done = 0, total = 0;
};

class Supervisor {
 public:
  static constexpr int kMaxRestarts = 3;

  // `needs_restart(actor)`: whether a lost ring node's work exists nowhere else (then it is restarted; otherwise
  // just lost). A question the supervisor asks while it judges an exit, so not an event.
  Supervisor(const FarmSpec& spec, Launchers& launchers, Outbox& out,
             std::function<bool(const std::string& actor)> needs_restart = {});
  // The events since the last call, oldest first.
  std::vector<SupervisorEvent> take_events() { return std::exchange(events_, {}); }

  // Starts every actor (`lightfarm actor ...`, or an exec actor's own command) pointed at `director_endpoint`.
  // With `local_address` (a farm that spans hosts), every actor also gets `--bind tcp://ADDRESS:*`: its host's
  // address, or `local_address` for this machine's actors, so that actors on other hosts reach its data socket.
  // `stdin_of(actor)` (a CURVE farm): the keys line each actor reads, which adds `--curve` to its arguments.
  Status launch(const std::string& director_endpoint, const std::string& local_address = {},
                const std::function<std::string(const ActorSpec&)>& stdin_of = {});
  void set_stage(Stage stage) { stage_ = stage; }
  Stage stage() const { return stage_; }
  // Hosts whose scene-loading actors a host agent forks: host name -> the agent's socket (`--agent`).
  void set_host_agents(std::map<std::string, std::string> sockets) { agent_sockets_ = std::move(sockets); }

  // One control message from `peer` (or why its bytes were refused).
  Status on_message(const std::string& peer, Result<wire::Message>& message);
  // A process ended.
  Status on_exit(const ExitReport& exit);
  // Whether the process `pid` could still have last words in flight on the control socket: an actor that has not
  // said BYE. (A host agent never speaks to the director.)
  bool may_still_speak(pid_t pid) const;
  // Actors silent for longer than the heartbeat timeout: recoverable ones are killed (their exit then counts as a
  // loss), any other stops the farm.
  Status check_heartbeats(Clock::time_point now);
  // The whole farm was paused (Ctrl-Z): nobody's silence until `now` counts.
  void forgive_silence(Clock::time_point now);
  // HEARTBEAT to every live actor, at most 4 per timeout and 1 a second.
  void send_heartbeats(Clock::time_point now);
  // The same message to every live actor that said hello.
  void broadcast(const wire::Message& message);
  // BYE to everyone still there (the farm is ending).
  void send_bye_to_all();

  // True when every actor not lost satisfies `done`.
  bool all(const std::function<bool(const ActorRecord&)>& done) const;
  // The others, for a message: 'a', 'b' (the first ten, then "and N more"). Only when a message needs them: a
  // wait calls all() after every message, and naming thousands of actors each time made it quadratic.
  std::string late(const std::function<bool(const ActorRecord&)>& done) const;
  std::map<std::string, ActorRecord>& actors() { return actors_; }
  const std::map<std::string, ActorRecord>& actors() const { return actors_; }
  const ActorRecord& at(const std::string& name) const { return actors_.at(name); }
  // The actor's pid on its host (remote actors' records hold handles), and "pid N[ on HOST]" for messages.
  pid_t host_pid(const ActorRecord& a) const { return a.pid > 0 ? launchers_.host_pid(a.pid) : 0; }
  std::string where(const ActorRecord& a) const { return launchers_.where(a.pid); }
  // What the live actors have in flight and queued, from their heartbeats ("a 3 out / 2 queued, b ..."), for a
  // frame that makes no progress; empty when nobody has anything.
  std::string in_flight() const;

 private:
  bool recoverable(const ActorRecord& a) const;
  bool restartable(const ActorRecord& a) const;
  Status lose(ActorRecord& a, const std::string& why);
  Status restart(ActorRecord& a, const std::string& why);
  Result<pid_t> start(const ActorSpec& a);
  void send(const std::string& name, wire::Message m);

  const FarmSpec& spec_;
  Launchers& launchers_;
  Outbox& out_;
  std::function<bool(const std::string&)> needs_restart_;
  std::vector<SupervisorEvent> events_;
  std::map<std::string, ActorRecord> actors_;
  // Which actor each process is (a restarted ring node's old pid stays, naming it too): an exit is found without a
  // look at every actor, which made a farm's end quadratic in its actors.
  std::unordered_map<pid_t, ActorRecord*> by_pid_;
  // Where all() last found an actor not done: it looks there first, so a wait's every turn costs one look while
  // that actor is still not done, instead of a walk over every actor before it.
  mutable std::string first_not_done_;
  // How launch() started actors, for restarts.
  std::string director_endpoint_, local_address_;
  std::function<std::string(const ActorSpec&)> stdin_of_;
  std::map<std::string, std::string> agent_sockets_;
  Stage stage_ = Stage::prepare;
  Clock::time_point last_heartbeat_ = Clock::now();
  Clock::time_point last_silence_check_{};
  RateLimitedLog strangers_;  // bad or foreign control messages: logged, never flooding
};

}  // namespace lf
