#include "actors/director/supervisor.hpp"

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>

#include "actors/runtime/hello.hpp"
#include "actors/runtime/runtime.hpp"
#include "core/log.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf {

using wire::MsgType;

namespace {
double seconds_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }
}  // namespace

Supervisor::Supervisor(const FarmSpec& spec, Launchers& launchers, Outbox& out,
                       std::function<bool(const std::string&)> needs_restart)
    : spec_(spec), launchers_(launchers), out_(out), needs_restart_(std::move(needs_restart)) {
  for (size_t i = 0; i < spec.actors.size(); ++i) {
    ActorRecord r;
    r.spec = &spec.actors[i];
    r.index = static_cast<int>(i);
    r.last_seen = Clock::now();
    actors_.emplace(spec.actors[i].name, r);
  }
}

void Supervisor::send(const std::string& name, wire::Message m) {
  m.header.sender = "director";
  out_.send(name, std::move(m));
}

Status Supervisor::launch(const std::string& director_endpoint, const std::string& local_address,
                          const std::function<std::string(const ActorSpec&)>& stdin_of) {
  if (auto st = launchers_.prepare(spec_.hosts_in_use()); !st)
    return make_error("cannot start the farm: " + st.error().message);
  director_endpoint_ = director_endpoint;
  local_address_ = local_address;
  stdin_of_ = stdin_of;
  for (const auto& a : spec_.actors) {
    if (!a.has_process()) continue;  // a pool its clients dispatch to
    auto pid = start(a);
    if (!pid) return pid.error();
    ActorRecord& r = actors_.at(a.name);
    r.pid = *pid;
    by_pid_[r.pid] = &r;
    r.last_seen = Clock::now();
  }
  return Ok{};
}

Result<pid_t> Supervisor::start(const ActorSpec& a) {
  {
    LaunchRequest how;
    how.argv = {"lightfarm", "actor"};
    if (auto cmd = a.runtime.find("cmd"); cmd != a.runtime.end() && cmd->second.is_array()) {
      // An external actor: its own command, then the arguments every actor gets.
      how.argv.clear();
      for (const auto& part : cmd->second.as_array()) how.argv.push_back(part.as_string());
      how.self = false;
      if (auto cwd = a.runtime.find("cwd"); cwd != a.runtime.end() && cwd->second.is_string()) how.cwd = cwd->second.as_string();
    }
    how.argv.insert(how.argv.end(), {"--kind", a.kind, "--name", a.name, "--director", director_endpoint_});
    const HostSpec* host = spec_.host_of(a);
    if (!host) return make_error(a.loc.str() + ": actor '" + a.name + "' is placed on undeclared host '" + a.host + "'");
    if (!local_address_.empty())
      how.argv.insert(how.argv.end(), {"--bind", "tcp://" + (host->remote() ? host->address : local_address_) + ":*"});
    if (auto agent = agent_sockets_.find(host->name); agent != agent_sockets_.end() && a.loads_scene())
      how.argv.insert(how.argv.end(), {"--agent", agent->second});
    if (stdin_of_) {
      how.argv.push_back("--curve");
      how.stdin_text = stdin_of_(a) + "\n";
    }
    auto pid = launchers_.start(*host, how);
    if (!pid) return make_error(a.loc.str() + ": cannot start actor '" + a.name + "': " + pid.error().message);
    return *pid;
  }
}

void Supervisor::broadcast(const wire::Message& message) {
  for (auto& [name, a] : actors_)
    if (a.said_hello && !a.exited && !a.lost) send(name, message);
}

void Supervisor::send_bye_to_all() {
  for (auto& [name, a] : actors_)
    if (a.said_hello && !a.said_bye && !a.exited && !a.lost) send(name, wire::make(MsgType::bye, "director"));
}

bool Supervisor::all(const std::function<bool(const ActorRecord&)>& done) const {
  // Every actor is looked at, from the last one found not done round to it again: any order gives the same answer.
  const auto start = actors_.lower_bound(first_not_done_);
  auto check = [&](auto from, auto to) {
    for (auto it = from; it != to; ++it)
      if (!it->second.lost && it->second.spec->has_process() && !done(it->second)) {
        first_not_done_ = it->first;
        return false;
      }
    return true;
  };
  return check(start, actors_.end()) && check(actors_.begin(), start);
}

std::string Supervisor::late(const std::function<bool(const ActorRecord&)>& done) const {
  constexpr size_t kNamed = 10;
  std::string names;
  size_t count = 0;
  for (const auto& [name, a] : actors_) {
    if (a.lost || !a.spec->has_process() || done(a)) continue;
    if (count++ < kNamed) names += (names.empty() ? "'" : ", '") + name + "'";
  }
  if (count > kNamed) names += " and " + std::to_string(count - kNamed) + " more";
  return names;
}

Status Supervisor::on_message(const std::string& peer, Result<wire::Message>& message) {
  auto it = actors_.find(peer);
  // An actor's heartbeat thread speaks under its own routing id; it says nothing but HEARTBEAT.
  if (const auto beats_for = it == actors_.end() ? heartbeat_owner(peer) : std::nullopt) {
    auto owner = actors_.find(*beats_for);
    if (owner != actors_.end() && message && message->header.type == MsgType::heartbeat) {
      ActorRecord& a = owner->second;
      if (a.lost) return Ok{};
      a.last_seen = Clock::now();
      // Its running figures (the monitor's); a plug-in may send none.
      if (message->body.is_map()) {
        a.live = std::move(message->body);
        a.live_at = a.last_seen;
      }
      return Ok{};
    }
  }
  if (!message) {
    const Error& e = message.error();
    if (it != actors_.end() && e.code == ErrorCode::incompatible)
      return make_error("actor '" + peer + "' is an " + e.message + "; refusing it");
    strangers_.warn("dropped a bad control message from '" + peer + "': " + e.message);
    return Ok{};
  }
  if (it == actors_.end()) {
    strangers_.warn("ignored a message from '" + peer + "', which is not part of this farm");
    return Ok{};
  }
  ActorRecord& a = it->second;
  if (a.lost) return Ok{};  // whatever a lost actor still says is not counted
  a.last_seen = Clock::now();
  wire::Message& m = *message;
  switch (m.header.type) {
    case MsgType::hello: {
      auto hello = Hello::check(m.body, peer, a.spec->kind);
      if (!hello) return hello.error();
      a.endpoint = hello->endpoint;
      a.local_endpoint = hello->local_endpoint;
      a.said_hello = true;
      if (a.rejoining) events_.push_back({.kind = SupervisorEvent::Kind::hello_again, .actor = a.name()});
      return Ok{};
    }
    case MsgType::ready:
      if (auto phase = wire::phase_of(m.header)) {
        a.ready = *phase;
        if (a.rejoining && *phase == wire::Phase::configure) {
          a.rejoining = false;
          events_.push_back({.kind = SupervisorEvent::Kind::configured_again, .actor = a.name()});
        }
      } else {
        log_warn("'" + peer + "' said READY for '" + m.header.op + "', which is not a phase");
      }
      return Ok{};
    case MsgType::error:
      return make_error("actor '" + peer + "' failed: " + wire::error_of(m).message);
    case MsgType::stats: a.stats = m.body; return Ok{};
    case MsgType::progress: {
      const Value *what = m.body.find("what"), *done = m.body.find("done"), *total = m.body.find("total");
      if (what && what->is_string() && done && done->is_int() && total && total->is_int() && done->as_int() >= 0 &&
          total->as_int() > 0 && done->as_int() <= total->as_int() && what->as_string().size() <= 64) {
        events_.push_back({.kind = SupervisorEvent::Kind::progress,
                           .actor = a.name(),
                           .what = what->as_string(),
                           .done = static_cast<uint64_t>(done->as_int()),
                           .total = static_cast<uint64_t>(total->as_int())});
      } else {
        strangers_.warn("'" + peer + "' sent a malformed PROGRESS");
      }
      return Ok{};
    }
    case MsgType::bye: a.said_bye = true; return Ok{};
    case MsgType::heartbeat: return Ok{};
    case MsgType::request:
      events_.push_back({.kind = SupervisorEvent::Kind::request, .actor = a.name(), .message = std::move(m)});
      return Ok{};
    default:
      log_warn("ignored a " + std::string(wire::type_name(m.header.type)) + " from '" + peer + "'");
      return Ok{};
  }
}

// Renderers and pool replicas may be lost from the moment they should say hello until the frame is done: their
// work goes to the others (one lost before its pool's CONFIG is simply left out of it).
bool Supervisor::recoverable(const ActorRecord& a) const {
  if (stage_ < Stage::hello || stage_ > Stage::render) return false;
  return a.spec->is_renderer() || spec_.pool_of(a.index) >= 0;
}

bool Supervisor::may_still_speak(pid_t pid) const {
  const auto it = by_pid_.find(pid);
  return it != by_pid_.end() && it->second->pid == pid && !it->second->said_bye;
}

Status Supervisor::on_exit(const ExitReport& r) {
  if (const auto it = by_pid_.find(r.pid); it != by_pid_.end() && it->second->pid == r.pid) {
    ActorRecord& a = *it->second;
    const std::string& name = a.name();
    a.exited = true;
    if (a.lost) return Ok{};  // already accounted for (we killed it)
    // In the finish stage a clean exit is an actor finishing, even if its BYE is still on the way.
    if (stage_ == Stage::finish && (a.said_bye || (WIFEXITED(r.status) && WEXITSTATUS(r.status) == 0))) {
      a.said_bye = true;
      return Ok{};
    }
    const std::string why = a.killed_hung ? "stopped answering (no heartbeat for " + seconds_text(spec_.heartbeat_timeout) +
                                                "); it was killed"
                                          : r.describe();
    if (recoverable(a)) return lose(a, why);
    if (restartable(a)) return restart(a, why);
    const std::string when = starting_up(stage_) ? "during start-up" : "during " + std::string(stage_name(stage_));
    // A part of a partitioned scene is held nowhere else: rays that cross it cannot be answered.
    const std::string held = a.spec->is_geometry() ? "; the part of the scene it held is not held anywhere else" : "";
    return make_error("actor '" + name + "' (" + launchers_.where(r.pid) + ") " + why + " " + when + held);
  }
  return Ok{};
}

// Ring nodes from the moment they should say hello until the frame is done (whether one is still needed is the ring
// service's to say).
bool Supervisor::restartable(const ActorRecord& a) const {
  return a.spec->is_ring_node() && stage_ >= Stage::hello && stage_ <= Stage::render;
}

Status Supervisor::restart(ActorRecord& a, const std::string& why) {
  if (!needs_restart_ || !needs_restart_(a.name())) {
    a.lost = true;
    a.loss = why;
    log_warn("ring node '" + a.name() + "' " + why + " after the ring's solution was complete; it is not needed any more",
             LogKind::loss);
    return Ok{};
  }
  if (a.restarts >= kMaxRestarts)
    return make_error("ring node '" + a.name() + "' " + why + " during " + std::string(stage_name(stage_)) +
                      ", after " + std::to_string(a.restarts) + " restarts; stopping the farm");
  ++a.restarts;
  log_warn("ring node '" + a.name() + "' " + why + "; restarting it (" + std::to_string(a.restarts) + " of at most " +
           std::to_string(kMaxRestarts) + ")",
           LogKind::recovery);
  auto pid = start(*a.spec);
  if (!pid) return make_error("cannot restart ring node '" + a.name() + "': " + pid.error().message);
  const bool was_configured = a.configured;
  a.pid = *pid;
  by_pid_[a.pid] = &a;
  a.said_hello = a.said_bye = a.exited = a.configured = a.killed_hung = false;
  a.ready.reset();
  a.last_seen = Clock::now();
  // Before its CONFIG the new process simply joins like everyone else; after it, it rejoins a farm under way.
  if (!was_configured) return Ok{};
  a.rejoining = true;
  events_.push_back({.kind = SupervisorEvent::Kind::lost, .actor = a.name(), .why = why});
  return Ok{};
}

Status Supervisor::lose(ActorRecord& a, const std::string& why) {
  a.lost = true;
  a.loss = why;
  if (a.spec->is_renderer()) {
    std::string all;
    bool any_left = false;
    for (auto& [n, other] : actors_) {
      if (!other.spec->is_renderer()) continue;
      any_left = any_left || !other.lost;
      all += (all.empty() ? "" : ", ") + n + " " + other.loss;
    }
    if (!any_left) return make_error("every renderer was lost: " + all);
    events_.push_back({.kind = SupervisorEvent::Kind::lost, .actor = a.name(), .why = why});
    return Ok{};
  }
  ActorRecord& pool = actors_.at(spec_.actors[static_cast<size_t>(spec_.pool_of(a.index))].name);
  std::string replicas;
  bool any_left = false;
  for (int r : pool.spec->inputs) {
    const ActorRecord& rep = actors_.at(spec_.actors[static_cast<size_t>(r)].name);
    any_left = any_left || !rep.lost;
    if (rep.lost) replicas += (replicas.empty() ? "" : ", ") + rep.name() + " " + rep.loss;
  }
  // A replica whose pool shares its setup, lost before the setup is over: its share exists nowhere else. Said at
  // once, rather than "sends its work to the others" and a failure later.
  if (stage_ <= Stage::setup)
    if (const LightOpKind* kind = find_lightop_kind(a.spec->kind); kind && kind->shares_setup_for(a.spec->params))
      return make_error("replica '" + a.name() + "' " + why + " during " +
                        (starting_up(stage_) ? std::string("start-up") : std::string("setup")) + "; the replicas of '" +
                        pool.name() + "' share their setup (" + std::string(kind->name) +
                        "), so its share cannot be redone");
  if (!any_left) {
    if (spec_.pool_of(pool.index) >= 0 && !pool.exited) {
      // A nested pool with no replica left is itself a lost replica of the pool above.
      launchers_.kill(pool.pid, SIGKILL);
      return lose(pool, "lost every replica (" + replicas + ")");
    }
    return make_error("lost the last replica of '" + pool.name() + "': " + replicas);
  }
  events_.push_back({.kind = SupervisorEvent::Kind::lost, .actor = a.name(), .why = why});
  log_warn("replica '" + a.name() + "' " + why + "; '" + pool.name() + "' sends its work to the others", LogKind::loss);
  // Whoever dispatches to the pool hears of it, after the services: its multiplexer, or each of its clients. One
  // not yet configured hears nothing: its CONFIG will leave the replica out.
  auto tell = [&](const std::string& to) {
    events_.push_back({.kind = SupervisorEvent::Kind::peer_down, .actor = a.name(), .to = to});
  };
  if (pool.spec->has_process()) {
    if (pool.configured) tell(pool.name());
    return Ok{};
  }
  for (auto& [name, client] : actors_) {
    const auto& inputs = client.spec->inputs;
    if (client.configured && !client.lost && !client.exited &&
        std::find(inputs.begin(), inputs.end(), pool.index) != inputs.end())
      tell(name);
  }
  return Ok{};
}

void Supervisor::forgive_silence(Clock::time_point now) {
  for (auto& [name, a] : actors_) a.last_seen = now;
}

Status Supervisor::check_heartbeats(Clock::time_point now) {
  if (stage_ <= Stage::hello) return Ok{};  // the hello timeout covers start-up
  // A look at every actor, a twentieth of the timeout apart: once a turn, it was most of the director's main
  // thread at 10,000 actors (a turn comes with every few messages).
  if (seconds_between(last_silence_check_, now) < spec_.heartbeat_timeout / 20) return Ok{};
  last_silence_check_ = now;
  for (auto& [name, a] : actors_) {
    if (a.exited || a.said_bye || a.lost || a.killed_hung || !a.spec->has_process()) continue;
    if (seconds_between(a.last_seen, now) <= spec_.heartbeat_timeout) continue;
    if (recoverable(a) || restartable(a)) {
      // A hung process (e.g. SIGSTOPped) counts as dead; SIGKILL makes sure it can never answer late.
      a.killed_hung = true;
      launchers_.kill(a.pid, SIGKILL);
      continue;
    }
    return make_error("actor '" + name + "' has been silent for " + seconds_text(spec_.heartbeat_timeout) +
                      " (missed heartbeats)");
  }
  return Ok{};
}

void Supervisor::send_heartbeats(Clock::time_point now) {
  if (seconds_between(last_heartbeat_, now) < heartbeat_interval(spec_.heartbeat_timeout)) return;
  last_heartbeat_ = now;
  broadcast(wire::make(MsgType::heartbeat, "director"));
}

std::string Supervisor::in_flight() const {
  std::string text;
  for (const auto& [name, a] : actors_) {
    auto figure = [&a = a](const char* key) {
      const Value* v = a.live.find(key);
      return v && v->is_number() ? v->as_int() : int64_t{0};
    };
    if (a.lost || (figure("in_flight") == 0 && figure("queue") == 0)) continue;
    text += (text.empty() ? "" : ", ") + name + " " + std::to_string(figure("in_flight")) + " out / " +
            std::to_string(figure("queue")) + " queued";
  }
  return text;
}

}  // namespace lf
