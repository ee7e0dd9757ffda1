#include "actors/runtime/runtime.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>

#include "actors/codecs/control_codec.hpp"
#include "actors/runtime/hello.hpp"
#include "actors/runtime/process.hpp"
#include "core/log.hpp"
#include "core/private_dir.hpp"
#include "render/scene/loaded_scene.hpp"

namespace lf {

using wire::MsgType;
using Clock = std::chrono::steady_clock;

Value ActorStats::to_value(const wire::SocketCounters& t) const {
  return Value::Map{{"requests", requests},
                    {"start_seconds", start_seconds},
                    {"configure_seconds", configure_seconds},
                    {"memory_pss_bytes", proportional_set_bytes()},
                    {"scene_from_agent", scene_was_preloaded()},
                    {"points", points},
                    {"tiles", tiles},
                    {"busy_seconds", busy_seconds},
                    {"cpu_seconds", process_cpu_seconds()},
                    {"peak_queue", uint64_t{peak_queue}},
                    {"bytes_in", t.bytes_in},
                    {"bytes_out", t.bytes_out},
                    {"messages_in", t.messages_in},
                    {"messages_out", t.messages_out}};
}

void Actor::on_frame(const FrameView&, Runtime& rt) { rt.phase_done(wire::Phase::frame); }

void Actor::on_peer_down(const std::string& name, Runtime& rt) {
  rt.fail("input '" + name + "' was lost and this actor has no other");
}

void Actor::on_peer_moved(const std::string& name, Runtime& rt) {
  rt.fail("input '" + name + "' was restarted, and this actor cannot redo what it had asked of it");
}

void Actor::on_rollback(const Value&, Runtime& rt) { rt.fail("the director asked for a rollback, which only ring nodes do"); }

Runtime::Runtime(ActorArgs args)
    : args_(std::move(args)), control_(wire::Socket::Kind::dealer, args_.name), data_(wire::Socket::Kind::router) {
  // Let BYE and the last STATS leave before the socket closes.
  control_.set_linger_ms(2000);
  if (args_.keys) {
    const auto& k = *args_.keys;
    authenticator_ = std::make_unique<wire::Authenticator>(std::set<std::string>(k.allowed.begin(), k.allowed.end()));
    control_.make_curve_client(k.own.public_key, k.own.secret_key, k.director);
    data_.make_curve_server(k.own.secret_key);
    authenticator_->watch(data_);
  }
}

namespace {
constexpr std::string_view kHeartbeatSuffix = "#heartbeat";
}

std::string heartbeat_identity(const std::string& actor) { return actor + std::string(kHeartbeatSuffix); }

std::optional<std::string> heartbeat_owner(const std::string& identity) {
  if (identity.size() <= kHeartbeatSuffix.size() || !identity.ends_with(kHeartbeatSuffix)) return std::nullopt;
  return identity.substr(0, identity.size() - kHeartbeatSuffix.size());
}

void Runtime::start_heartbeats() {
  heartbeat_thread_ = std::thread([this] {
    wire::block_signals_in_this_thread();
    wire::Socket beat(wire::Socket::Kind::dealer, heartbeat_identity(args_.name));
    if (args_.keys) beat.make_curve_client(args_.keys->own.public_key, args_.keys->own.secret_key, args_.keys->director);
    if (!beat.connect(args_.director)) return;
    int left_out = 0;
    for (auto last_beat = Clock::time_point{}; !heartbeat_stop_;) {
      // Any message is a sign of life: a renderer handing in tiles need not beat too (at 10,000 actors the beats
      // were a third of the director's messages). Every fourth beat still goes, with the monitor's figures.
      const auto last_sent = Clock::time_point(Clock::duration(last_control_send_.load(std::memory_order_relaxed)));
      if (left_out < kBeatsLeftOut && last_sent > last_beat) {
        ++left_out;
      } else {
        Value live;
        {
          std::lock_guard<std::mutex> lock(live_mutex_);
          live = live_;
        }
        beat.send(wire::make(MsgType::heartbeat, args_.name, std::move(live)));
        left_out = 0;
      }
      // Four beats per timeout, at least one a second, so one late beat is never taken for a death. The interval
      // is read again while waiting: CONFIG may shorten it (a 1 s timeout) in the middle of the first wait.
      const auto sent = last_beat = Clock::now();
      auto due = [&] {
        return sent + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(heartbeat_interval_.load()));
      };
      // Asleep until due, woken early only to stop or to take a new interval: a thread that looked at the clock
      // every 20 ms woke 50 times a second in every actor (256 actors on two cores: 12,800 context switches a
      // second before any work).
      std::unique_lock<std::mutex> lock(heartbeat_mutex_);
      while (!heartbeat_stop_ && Clock::now() < due()) heartbeat_wake_.wait_until(lock, due());
    }
  });
}

void Runtime::set_heartbeat_interval(double seconds) {
  {
    std::lock_guard<std::mutex> lock(heartbeat_mutex_);
    heartbeat_interval_ = seconds;
  }
  heartbeat_wake_.notify_all();
}

void Runtime::stop_heartbeats() {
  {
    std::lock_guard<std::mutex> lock(heartbeat_mutex_);
    heartbeat_stop_ = true;
  }
  heartbeat_wake_.notify_all();
  if (heartbeat_thread_.joinable()) heartbeat_thread_.join();
}

Runtime::~Runtime() {
  stop_heartbeats();
  local_.reset();
  if (!local_dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(local_dir_, ec);
  }
}

wire::Socket& Runtime::socket_of(const std::string& peer) {
  auto it = reply_via_.find(peer);
  return it == reply_via_.end() ? data_ : *it->second;
}

void Runtime::add_busy(Clock::time_point since) {
  stats_.busy_seconds += std::chrono::duration<double>(Clock::now() - since).count();
}

void Runtime::send_control(wire::Message m) {
  m.header.sender = args_.name;
  control_.send(m);
  last_control_send_.store(Clock::now().time_since_epoch().count(), std::memory_order_relaxed);
}

void Runtime::reply(const std::string& peer, uint64_t id, Value body) {
  socket_of(peer).send_to(peer, wire::make_reply(args_.name, id, std::move(body),
                                       actor_ ? static_cast<uint32_t>(actor_->queue_length()) : 0));
}

void Runtime::reply_error(const std::string& peer, uint64_t id, ErrorCode code, const std::string& message) {
  socket_of(peer).send_to(peer, wire::make_error_reply(args_.name, id, code, message));
}

void Runtime::reply_unknown_op(const std::string& peer, const wire::Message& request, const std::string& served) {
  reply_error(peer, request.header.id, ErrorCode::unknown_op,
              "unknown operation '" + request.header.op + "' (" + served + ")");
}

void Runtime::ask_director(wire::Op op, Value body, DirectorCallback callback) {
  uint64_t id = next_director_id_++;
  director_pending_.emplace(id, std::move(callback));
  send_control(wire::make_request(args_.name, op, std::move(body), id));
}

void Runtime::phase_done(wire::Phase phase) { send_control(wire::make_ready(args_.name, phase)); }

void Runtime::fail(const std::string& message) {
  log_error(message);
  send_control(wire::make_error_reply(args_.name, 0, ErrorCode::actor_failed, message));
  stopping_ = true;
  exit_status_ = 1;
}

void Runtime::report_progress(const std::string& what, uint64_t done, uint64_t total) {
  const auto now = Clock::now();
  auto [last, first] = progress_sent_.try_emplace(what, now);
  if (!first && done < total && now - last->second < std::chrono::milliseconds(250)) return;
  last->second = now;
  send_control(wire::make(MsgType::progress, args_.name,
                          Value::Map{{"what", what}, {"done", static_cast<int64_t>(done)}, {"total", static_cast<int64_t>(total)}}));
}

void Runtime::refresh_live(size_t queue_length) {
  const auto now = Clock::now();
  if (now - live_refreshed_ < std::chrono::milliseconds(250)) return;
  live_refreshed_ = now;
  wire::SocketCounters total;
  for (const wire::SocketCounters& c : {control_.counters(), data_.counters()}) {
    total.bytes_in += c.bytes_in;
    total.bytes_out += c.bytes_out;
  }
  if (local_) {
    total.bytes_in += local_->counters().bytes_in;
    total.bytes_out += local_->counters().bytes_out;
  }
  uint64_t in_flight = 0;  // requests sent to inputs and not yet answered
  for (auto& row : connections_.rows()) {
    total.bytes_in += row.client->socket().counters().bytes_in;
    total.bytes_out += row.client->socket().counters().bytes_out;
    in_flight += row.client->outstanding();
  }
  Value live = Value::Map{{"in_flight", in_flight},                {"requests", stats_.requests},
                          {"points", stats_.points},
                          {"tiles", stats_.tiles},               {"busy_seconds", stats_.busy_seconds},
                          {"queue", static_cast<uint64_t>(queue_length)}, {"bytes_in", total.bytes_in},
                          {"bytes_out", total.bytes_out}};
  std::lock_guard<std::mutex> lock(live_mutex_);
  live_ = std::move(live);
}

void Runtime::send_stats_and_bye() {
  wire::SocketCounters total;
  auto add = [&](const wire::SocketCounters& c) {
    total.bytes_in += c.bytes_in;
    total.bytes_out += c.bytes_out;
    total.messages_in += c.messages_in;
    total.messages_out += c.messages_out;
  };
  add(control_.counters());
  add(data_.counters());
  if (local_) add(local_->counters());
  for (auto& row : connections_.rows()) add(row.client->socket().counters());
  Value stats = stats_.to_value(total);
  if (actor_) {
    Value detail = actor_->extra_stats();
    if (!detail.is_nil()) stats.as_map()["detail"] = std::move(detail);
  }
  Value::Array pools;
  for (const auto& in : connections_.lighting())
    if (in.pool) pools.push_back(in.pool->stats());
  if (!pools.empty()) stats.as_map()["pools"] = std::move(pools);
  send_control(wire::make(MsgType::stats, args_.name, std::move(stats)));
  send_control(wire::make(MsgType::bye, args_.name));
}

void Runtime::handle_control(wire::Message& m, Actor& actor) {
  switch (m.header.type) {
    case MsgType::config: return on_config(m, actor);
    case MsgType::phase: {
      const auto phase = wire::phase_of(m.header);
      if (!phase || *phase == wire::Phase::configure) {
        log_warn("ignored PHASE '" + m.header.op + "' from the director (not a phase this protocol has)");
        return;
      }
      if (*phase == wire::Phase::finish) {
        send_stats_and_bye();
        stopping_ = true;
        return;
      }
      auto started = Clock::now();
      if (*phase == wire::Phase::frame) {
        // The director's own message: one it cannot read is a broken farm, not a frame to skip.
        auto frame = control::decode_frame(m.body);
        if (!frame) return fail(frame.error().message);
        // A replayed view names the actors that must set themselves up for it (docs/PROTOCOL.md).
        const auto& renew = frame->renew;
        actor.on_frame(FrameView{frame->frame, frame->camera,
                                 !renew || std::find(renew->begin(), renew->end(), args_.name) != renew->end(),
                                 frame->keep, frame->restore, std::move(frame->materials),
                                 frame->new_materials, frame->in_flight},
                       *this);
      } else {
        actor.on_phase(*phase, *this);
      }
      add_busy(started);
      return;
    }
    case MsgType::reply:
    case MsgType::error: {
      auto it = director_pending_.find(m.header.id);
      if (it == director_pending_.end()) return;
      auto cb = std::move(it->second);
      director_pending_.erase(it);
      if (m.header.type == MsgType::error) {
        cb(wire::error_of(m));
      } else {
        cb(std::move(m));
      }
      return;
    }
    case MsgType::bye:
      send_stats_and_bye();
      stopping_ = true;
      return;
    case MsgType::heartbeat: return;
    case MsgType::peer_down: {
      auto name = control::decode_peer_down(m.body);
      if (!name) return log_warn("ignored " + name.error().message);
      if (auto* in = connections_.replica_lost(*name)) {
        if (in->pool->live() == 0) fail("lost the last replica of '" + in->name + "'");
        return;
      }
      actor.on_peer_down(*name, *this);
      return;
    }
    case MsgType::peer_moved: return on_peer_moved(m, actor);
    case MsgType::rollback: {
      auto started = Clock::now();
      actor.on_rollback(m.body, *this);
      add_busy(started);
      return;
    }
    default: log_warn("ignored a " + std::string(wire::type_name(m.header.type)) + " from the director");
  }
}

void Runtime::on_config(const wire::Message& m, Actor& actor) {
  if (configured_) return;
  configured_ = true;
  auto config = ActorConfig::from_value(m.body);
  if (!config) return fail(config.error().message);
  heartbeat_timeout_ = config->heartbeat_timeout;
  set_heartbeat_interval(std::min(1.0, heartbeat_timeout_ / 4));
  request_timeout_ = config->request_timeout;
  // Connect to every input before the actor configures, so that it may ask them during setup.
  if (auto st = connections_.connect_config(*config, args_.bind); !st) return fail(st.error().message);
  auto started = Clock::now();
  Status st = actor.configure(*config, *this);
  add_busy(started);
  if (!st) return fail(st.error().message);
  stats_.configure_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  stats_.start_seconds = seconds_since_process_start();
  phase_done(wire::Phase::configure);
}

void Runtime::on_peer_moved(const wire::Message& m, Actor& actor) {
  auto moved = control::decode_peer_moved(m.body);
  if (!moved) return log_warn("ignored " + moved.error().message);
  auto reconnected = connections_.reconnect(moved->name, moved->endpoint, moved->key);
  if (!reconnected) return fail(reconnected.error().message);
  if (!*reconnected) return log_warn("ignored a PEER_MOVED about '" + moved->name + "', not an input");
  actor.on_peer_moved(moved->name, *this);
}

void Runtime::ask_input(size_t i, wire::Op op, Value body, wire::RequestClient::Callback callback, int64_t part) {
  Connections::LightingInput& in = connections_.lighting()[i];
  if (in.pool) return in.pool->request(op, std::move(body), std::move(callback), part);
  connections_.rows()[in.row].client->request(op, std::move(body), std::move(callback));
}

Result<std::unique_ptr<wire::RequestClient>> Runtime::connect_input(const std::string& name, const std::string& endpoint,
                                                                    const std::string& key, size_t window) {
  auto client = std::make_unique<wire::RequestClient>(args_.name, name, window);
  if (args_.keys) {
    // Only a same-host IPC endpoint goes without CURVE.
    if (key.empty() && endpoint.rfind("ipc://", 0) != 0)
      return make_error("the director gives input '" + name + "' no key, and this farm speaks CURVE");
    if (!key.empty()) client->use_curve(args_.keys->own.public_key, args_.keys->own.secret_key, key);
  }
  if (auto st = client->connect(endpoint); !st) return st.error();
  client->set_timeout(request_timeout_);
  return client;
}

void Runtime::handle_data(Actor& actor, wire::Socket& socket) {
  while (auto in = socket.receive()) {
    if (!in->peer.empty()) reply_via_[in->peer] = &socket;
    if (!in->message) {
      // Refuse, tell the sender if we can, and carry on: a bad packet must never take the actor down.
      bad_messages_.warn("dropped a bad message from '" + in->peer + "': " + in->message.error().message);
      if (!in->peer.empty()) reply_error(in->peer, 0, ErrorCode::bad_message, in->message.error().message);
      continue;
    }
    wire::Message& m = *in->message;
    if (m.header.type != MsgType::request) {
      reply_error(in->peer, m.header.id, ErrorCode::bad_message,
                  "expected a REQUEST on the data socket, got " + std::string(wire::type_name(m.header.type)));
      continue;
    }
    auto started = Clock::now();
    actor.on_request(in->peer, wire::op_of(m.header), m, *this);
    add_busy(started);
    if (stopping_) return;
  }
}

int Runtime::run(Actor& actor) {
  actor_ = &actor;
  set_log_name(args_.name);
  auto endpoint = data_.bind(args_.bind);
  if (!endpoint) {
    log_error(endpoint.error().message);
    return 2;
  }
  data_endpoint_ = *endpoint;
  if (args_.keys) {
    // What actors of this host SIGKILLed earlier left behind goes first.
    sweep_stale_private_dirs("actor");
    local_dir_ = make_private_dir("actor");
    if (!local_dir_.empty()) {
      local_ = std::make_unique<wire::Socket>(wire::Socket::Kind::router);
      auto bound = local_->bind("ipc://" + local_dir_ + "/data");
      if (bound) {
        local_endpoint_ = *bound;
      } else {
        log_warn("no same-host IPC socket (" + bound.error().message + "); peers here use CURVE over TCP");
        local_.reset();
      }
    }
  }
  if (auto st = control_.connect(args_.director); !st) {
    log_error(st.error().message);
    return 2;
  }
  Hello hello = my_hello(args_.kind, data_endpoint_);
  hello.local_endpoint = local_endpoint_;
  send_control(wire::make(MsgType::hello, args_.name, hello.to_value()));

  auto last_from_director = Clock::now();
  start_heartbeats();
  wire::Poller poller;
  poller.add(control_);
  poller.add(data_);
  if (local_) poller.add(*local_);
  const size_t first_input = local_ ? 3 : 2;
  size_t polled_inputs = 0;

  while (!stopping_) {
    if (stop_requested()) {
      log_debug("stopping on signal " + std::to_string(stop_signal()));
      return 128 + stop_signal();
    }
    if (stop_asked_) return 128 + SIGTERM;
    if (connections_.take_changed()) {
      // Inputs were connected, or one was replaced (PEER_MOVED): the poller is made again around the live sockets.
      poller.clear();
      poller.add(control_);
      poller.add(data_);
      if (local_) poller.add(*local_);
      for (auto& row : connections_.rows()) poller.add(row.client->socket());
      polled_inputs = connections_.rows().size();
    }
    // While the actor has work of its own, do not sleep in poll.
    long timeout = actor.has_local_work() ? 0 : 100;
    if (long due = actor.next_due_ms(); due >= 0) timeout = std::min(timeout, due);
    const auto& ready = poller.wait(timeout);

    // The control socket is drained every turn, readable or not: see the silence check below.
    while (auto in = control_.receive()) {
      if (!in->message) {
        log_warn("bad message from the director: " + in->message.error().message);
        continue;
      }
      last_from_director = Clock::now();
      handle_control(*in->message, actor);
      if (stopping_) break;
    }
    if (take_resumed()) {
      // This process was stopped (the director's Ctrl-Z, or a debugger): the silence was ours, not the
      // director's, and requests in flight waited for the same reason. Checked here, since the stop may have
      // come anywhere in this turn.
      last_from_director = Clock::now();
      for (auto& row : connections_.rows()) row.client->restart_deadlines();
    }
    // Judged right after reading what the director sent: a long piece of work here must not look like its silence
    // (its heartbeats wait in the queue meanwhile).
    if (std::chrono::duration<double>(Clock::now() - last_from_director).count() > heartbeat_timeout_) {
      log_error("the director has been silent for " + std::to_string(static_cast<int>(heartbeat_timeout_)) +
                " s; stopping");
      return 3;
    }
    if (stopping_) break;
    if (ready[1]) handle_data(actor, data_);
    if (local_ && ready[2] && !stopping_) handle_data(actor, *local_);
    for (size_t i = 0; i < polled_inputs && !stopping_; ++i) {
      auto started = Clock::now();
      wire::RequestClient& client = *connections_.rows()[i].client;
      if (ready[first_input + i]) client.on_readable();
      client.expire_overdue();
      add_busy(started);
    }
    if (!stopping_) {
      auto started = Clock::now();
      actor.on_progress(*this);
      add_busy(started);
    }
    stats_.peak_queue = std::max<uint32_t>(stats_.peak_queue, static_cast<uint32_t>(actor.queue_length()));
    refresh_live(actor.queue_length());

  }
  return exit_status_;
}

}  // namespace lf
