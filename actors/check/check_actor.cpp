// check-actor plays the director (and a renderer, and with --inputs constant-light inputs) for one actor process
// and drives it through a farm's whole life, checking each step of docs/PROTOCOL.md within the timeout. As a farm
// does by default, every link speaks CURVE: the actor gets --curve and its keys on standard input (--security none
// checks it without).
//   hello      HELLO arrives from the routing id --name, with protocol version 1, float format f32le, the kind
//              it was given and an endpoint (the same check the director makes)
//   configure  CONFIG (the built-in Cornell box, the actor's inputs) is answered with READY configure
//   setup      PHASE setup is answered with READY setup
//   render     PHASE render is answered with READY render (the director waits for it from every actor)
//   requests   shade requests of 1, 100 and 4096 real Cornell box points: a REPLY each, with the request's id,
//              n equal to the points asked, n radiance triples, all finite and non-negative
//   inputs     (with --inputs N) every input was asked for light while shading
//   malformed  three undecodable packets are each answered with ERROR bad_message (id 0), an unknown operation
//              with ERROR unknown_op (its id), and a good request afterwards still with a REPLY
//   frame      a job's next frame: PHASE frame (another camera) is answered with READY frame, the PHASE setup that
//              follows with READY setup, and a shade request after them with a REPLY
//   heartbeat  a HEARTBEAT arrives within the heartbeat timeout it was configured with
//   bye        PHASE finish: STATS and BYE come back and the process exits with status 0
//   orphaned   a second instance, configured, whose director then falls silent, exits within its heartbeat
//              timeout plus the check timeout
//   sigterm    a third instance, configured, exits on SIGTERM within the check timeout
#include "actors/check/check_actor.hpp"

#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "actors/codecs/control_codec.hpp"
#include "actors/launchers/local_launcher.hpp"
#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/hello.hpp"
#include "core/log.hpp"
#include "actors/codecs/shade_codec.hpp"
#include "render/tracing/camera.hpp"
#include "render/shading/tile_kernel.hpp"
#include "transport/security.hpp"
#include "transport/socket.hpp"

namespace lf {
namespace {

using Clock = std::chrono::steady_clock;
using wire::MsgType;

class Checker {
 public:
  explicit Checker(const CheckOptions& o) : options_(o), curve_(o.security == "curve") {
    if (!curve_) return;
    director_keys_ = wire::make_curve_keypair();
    actor_keys_ = wire::make_curve_keypair();
    renderer_keys_ = wire::make_curve_keypair();
    input_keys_ = wire::make_curve_keypair();
    // The director's side lets in only the actor's key, as a farm's director does.
    auth_ = std::make_unique<wire::Authenticator>(std::set<std::string>{actor_keys_.public_key});
  }

  int run() {
    prepare_points();
    if (!start("check")) return finish();
    const bool hello = check("hello", [&] { return expect_hello(); });
    const bool configured = hello && check("configure", [&] { return configure(options_.heartbeat_timeout); });
    const bool set_up = configured && check("setup", [&] { return phase(wire::Phase::setup); });
    if (set_up) {
      check("render", [&] { return phase(wire::Phase::render); });
      check("requests", [&] { return requests(); });
      if (options_.inputs > 0) check("inputs", [&] { return inputs_asked(); });
      check("malformed", [&] { return malformed(); });
      check("frame", [&] { return next_frame(); });
      check("heartbeat", [&] { return heartbeat(); });
      check("bye", [&] { return bye(); });
    }
    stop_actor();
    if (hello) {
      // A second instance: configured, then abandoned by its director.
      if (start("check-orphan") && expect_hello().empty() && configure(1.0).empty()) {
        check("orphaned", [&] { return orphaned(1.0); });
      } else {
        report("orphaned", "could not bring a second instance up to CONFIG");
      }
      stop_actor();
      // A third: configured, then SIGTERM.
      if (start("check-term") && expect_hello().empty() && configure(options_.heartbeat_timeout).empty()) {
        check("sigterm", [&] { return sigterm(); });
      } else {
        report("sigterm", "could not bring a third instance up to CONFIG");
      }
      stop_actor();
    }
    return finish();
  }

 private:
  // Each check returns an empty string on success, else what is wrong.
  template <class Fn>
  bool check(const char* name, Fn&& fn) {
    std::string why = fn();
    report(name, why);
    return why.empty();
  }

  void report(const char* name, const std::string& why) {
    if (why.empty()) {
      std::printf("PASS %-10s\n", name);
    } else {
      std::printf("FAIL %-10s %s\n", name, why.c_str());
      ++failures_;
    }
    std::fflush(stdout);
  }

  int finish() { return failures_ == 0 ? 0 : 1; }

  void prepare_points() {
    auto scene = Scene::builtin("cornell");
    RayTracer tracer(*scene);
    ImageSpec image;
    image.width = image.height = 64;
    image.spp = 4;
    Camera camera(CameraSpec{}, 64, 64);
    TileWork work;
    trace_tile(*scene, tracer, camera, image, TileRect{0, 0, 64, 64}, work);
    points_ = std::move(work.points);
  }

  bool start(const std::string& name) {
    name_ = name;
    control_ = std::make_unique<wire::Socket>(wire::Socket::Kind::router);
    if (curve_) {
      auth_->watch(*control_);
      control_->make_curve_server(director_keys_.secret_key);
    }
    auto endpoint = control_->bind("tcp://127.0.0.1:*");
    if (!endpoint) {
      report("launch", endpoint.error().message);
      return false;
    }
    std::vector<std::string> argv = options_.command;
    argv.insert(argv.end(), {"--kind", options_.kind, "--name", name, "--director", *endpoint});
    LaunchRequest request{argv, false, {}};
    if (curve_) {
      // As the director gives them: one line on standard input, the renderer's key the one its data socket admits.
      argv.push_back("--curve");
      request.argv = argv;
      wire::FarmKeys keys{actor_keys_, director_keys_.public_key, {renderer_keys_.public_key}};
      request.stdin_text = keys.to_line() + "\n";
    }
    refused_before_ = curve_ ? auth_->refused() : 0;
    auto pid = launcher_.start(request);
    if (!pid) {
      report("launch", pid.error().message);
      return false;
    }
    pid_ = *pid;
    exit_ = std::nullopt;
    return true;
  }

  void stop_actor() {
    beating_ = false;
    launcher_.stop_all(std::chrono::milliseconds(200));
    data_.reset();
    control_.reset();
  }

  void send_control(wire::Message m) {
    control_->send_to(name_, m);
    last_sent_ = Clock::now();
  }

  // As the director does (Supervisor::send_heartbeats): a HEARTBEAT when the actor has heard nothing for a quarter of
  // its heartbeat timeout (at most a second), once it is configured, unless the check is the director's silence.
  void keep_alive() {
    if (!beating_ || !control_) return;
    if (std::chrono::duration<double>(Clock::now() - last_sent_).count() >= std::min(1.0, heartbeat_timeout_ / 4))
      send_control(wire::make(MsgType::heartbeat, "director"));
  }

  // Next control message from the actor, skipping heartbeats unless wanted; or why none came.
  Result<wire::Message> next_control(double seconds, bool want_heartbeat = false) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
    wire::Poller poller;
    poller.add(*control_);
    while (Clock::now() < deadline) {
      keep_alive();
      poller.wait(20);
      while (auto in = control_->receive()) {
        if (in->message && in->message->header.type == MsgType::heartbeat && !want_heartbeat) {
          saw_heartbeat_ = true;  // from the actor's control socket or its heartbeat thread's
          continue;
        }
        last_peer_ = in->peer;
        if (!in->message) return make_error(in->message.error().message);
        return std::move(*in->message);
      }
      if (auto e = launcher_.reap_one()) {
        exit_ = *e;
        return make_error("the actor " + e->describe());
      }
    }
    return make_error("nothing within " + seconds_text(seconds));
  }

  std::string expect_hello() {
    auto m = next_control(options_.timeout);
    if (!m && curve_ && auth_->refused() > refused_before_)
      return "no HELLO: the director's side refused " + std::to_string(auth_->refused() - refused_before_) +
             " connection(s) from '" + name_ + "' that did not speak CURVE with its keys: with --curve an actor reads " +
             "its keys from the first line of standard input and speaks CURVE on every link (docs/PROTOCOL.md, " +
             "\"Security\"); --security none checks it without";
    if (!m) return "no HELLO: " + m.error().message;
    if (m->header.type != MsgType::hello) return "expected HELLO, got " + std::string(wire::type_name(m->header.type));
    if (last_peer_ != name_)
      return "HELLO came from routing id '" + printable(last_peer_) + "', not the actor's --name '" + name_ +
             "' (set ZMQ_ROUTING_ID to the name before connecting)";
    auto hello = Hello::check(m->body, name_, options_.kind);
    if (!hello) return hello.error().message;
    data_ = std::make_unique<wire::Socket>(wire::Socket::Kind::dealer, "check-renderer");
    if (curve_) data_->make_curve_client(renderer_keys_.public_key, renderer_keys_.secret_key, actor_keys_.public_key);
    if (auto st = data_->connect(hello->endpoint); !st) return st.error().message;
    return {};
  }

  std::string configure(double heartbeat_timeout) {
    ActorConfig config;
    for (int i = 0; i < options_.inputs; ++i) {
      if (!fake_input_) start_fake_input();
      config.inputs.push_back({"check-input", fake_endpoint_, 4, curve_ ? input_keys_.public_key : std::string()});
    }
    heartbeat_timeout_ = heartbeat_timeout;
    config.scene = SceneSpec{"cornell", "", {}};
    config.heartbeat_timeout = heartbeat_timeout;
    config.request_timeout = options_.timeout;
    send_control(wire::make(MsgType::config, "director", config.to_value()));
    beating_ = true;
    return expect_ready(wire::Phase::configure);
  }

  std::string expect_ready(wire::Phase phase) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.timeout);
    while (Clock::now() < deadline) {
      pump_fake_input();
      auto m = next_control(0.05);
      if (!m) {
        if (m.error().message.rfind("nothing within", 0) == 0) continue;
        return m.error().message;
      }
      if (m->header.type == MsgType::error) {
        const Value* text = m->body.find("message");
        return "the actor failed: " + (text && text->is_string() ? text->as_string() : std::string("?"));
      }
      if (m->header.type == MsgType::ready && wire::phase_of(m->header) == phase) return {};
    }
    return "no READY " + std::string(wire::phase_name(phase)) + " within " + seconds_text(options_.timeout);
  }

  std::string phase(wire::Phase phase) {
    send_control(wire::make_phase("director", phase));
    return expect_ready(phase);
  }

  // One shade request of `n` points; empty string if answered well.
  std::string shade(size_t n, uint64_t id) {
    n = std::min(n, points_.size());
    data_->send(wire::make_request("check-renderer", wire::Op::shade, encode_shade_request(points_, 0, n), id));
    while (true) {
      auto m = next_data();
      if (!m) {
        if (exit_) return m.error().message + " while shading " + std::to_string(n) + " points";
        if (m.error().code == ErrorCode::timeout)
          return "no REPLY to " + std::to_string(n) + " points within " + seconds_text(options_.timeout);
        return m.error().message;
      }
      if (m->header.id != id) continue;  // e.g. an ERROR for an earlier malformed packet
      if (m->header.type == MsgType::error)
        return "ERROR for " + std::to_string(n) + " points: " + wire::error_of(*m).message;
      if (m->header.type != MsgType::reply) return "expected REPLY, got " + std::string(wire::type_name(m->header.type));
      auto radiance = decode_radiance(m->body, n);  // n must agree with the request and with the data
      if (!radiance) return radiance.error().message;
      for (const RGB& c : *radiance)
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z) || c.x < 0 || c.y < 0 || c.z < 0)
          return "radiance must be finite and non-negative";
      return {};
    }
  }

  // A job's next frame, as the director's FrameLoop drives it (docs/PROTOCOL.md, "Jobs of frames").
  std::string next_frame() {
    CameraSpec moved;
    moved.eye = {378, 273, -800};
    send_control(wire::make_phase("director", wire::Phase::frame, control::encode_frame({2, moved, std::nullopt})));
    if (std::string why = expect_ready(wire::Phase::frame); !why.empty()) return why;
    if (std::string why = phase(wire::Phase::setup); !why.empty()) return why + " (after PHASE frame)";
    if (std::string why = shade(100, 200); !why.empty()) return "after the frame: " + why;
    return {};
  }

  std::string requests() {
    uint64_t id = 100;
    for (size_t n : {size_t{1}, size_t{100}, size_t{4096}})
      if (std::string why = shade(n, id++); !why.empty()) return why;
    return {};
  }

  // The next message on the data socket within the timeout, feeding the fake inputs meanwhile.
  Result<wire::Message> next_data() {
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.timeout);
    wire::Poller poller;
    poller.add(*data_);
    while (Clock::now() < deadline) {
      pump_fake_input();
      keep_alive();
      poller.wait(10);
      if (auto in = data_->receive()) {
        if (!in->message) return make_error("undecodable answer: " + in->message.error().message);
        return std::move(*in->message);
      }
      if (auto e = launcher_.reap_one()) {
        exit_ = *e;
        return make_error("the actor " + e->describe());
      }
    }
    return make_error("nothing within " + seconds_text(options_.timeout), ErrorCode::timeout);
  }

  std::string malformed() {
    Header newer;
    newer.version = 99;
    const std::vector<std::vector<std::string>> bad{
        {"\xc1 not msgpack", "\x80"}, {"only one frame"}, {encode_header(newer), encode_body(Value::Map{})}};
    for (size_t i = 0; i < bad.size(); ++i) {
      data_->send_raw(bad[i]);
      auto m = next_data();
      if (!m) return "no ERROR for malformed packet " + std::to_string(i + 1) + ": " + m.error().message;
      if (m->header.type != MsgType::error || wire::error_of(*m).code != ErrorCode::bad_message)
        return "malformed packet " + std::to_string(i + 1) + " was answered with a " +
               std::string(wire::type_name(m->header.type)) + ", not ERROR bad_message";
    }
    wire::Message unknown = wire::make(MsgType::request, "check-renderer", Value::Map{}, 300);
    unknown.header.op = "no_such_op";
    data_->send(unknown);
    auto m = next_data();
    if (!m) return "no ERROR for an unknown operation: " + m.error().message;
    if (m->header.type != MsgType::error || m->header.id != 300 || wire::error_of(*m).code != ErrorCode::unknown_op)
      return "an unknown operation was not answered with ERROR unknown_op and its id";
    if (std::string why = shade(10, 200); !why.empty()) return "after malformed packets: " + why;
    return {};
  }

  std::string inputs_asked() {
    if (fake_requests_ > 0) return {};
    return "asked its input nothing while shading (an actor given inputs must ask them for light)";
  }

  std::string sigterm() {
    ::kill(pid_, SIGTERM);
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.timeout);
    while (Clock::now() < deadline) {
      if (launcher_.reap_one()) return {};
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return "still running " + seconds_text(options_.timeout) + " after SIGTERM";
  }

  static std::string printable(const std::string& id) {
    std::string out;
    for (unsigned char c : id) {
      if (c >= 0x20 && c < 0x7f) {
        out += static_cast<char>(c);
      } else {
        char hex[5];
        std::snprintf(hex, sizeof hex, "\\x%02x", c);
        out += hex;
      }
    }
    return out;
  }

  using Header = wire::Header;
  static std::string encode_header(const Header& h) { return wire::encode_header(h); }
  static std::string encode_body(const Value& v) { return wire::encode_body(v); }

  std::string heartbeat() {
    const double wait = heartbeat_timeout_ + options_.timeout;
    const auto deadline = Clock::now() + std::chrono::duration<double>(wait);
    while (!saw_heartbeat_ && Clock::now() < deadline) {
      auto m = next_control(0.05, true);
      if (m && m->header.type == MsgType::heartbeat) saw_heartbeat_ = true;
      if (!m && exit_) return m.error().message;
    }
    return saw_heartbeat_ ? std::string() : "no HEARTBEAT within " + seconds_text(wait);
  }

  std::string bye() {
    send_control(wire::make_phase("director", wire::Phase::finish));
    bool stats = false, said_bye = false;
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.timeout);
    while (Clock::now() < deadline && !exit_) {
      auto m = next_control(0.05);
      if (m) {
        stats = stats || m->header.type == MsgType::stats;
        said_bye = said_bye || m->header.type == MsgType::bye;
      }
    }
    if (!said_bye) return "no BYE after PHASE finish";
    if (!stats) return "no STATS before BYE";
    if (!exit_) return "still running " + seconds_text(options_.timeout) + " after BYE";
    if (!WIFEXITED(exit_->status) || WEXITSTATUS(exit_->status) != 0) return "the actor " + exit_->describe();
    return {};
  }

  std::string orphaned(double heartbeat_timeout) {
    // Say nothing more, not even a HEARTBEAT; the actor must notice and leave.
    beating_ = false;
    const auto deadline = Clock::now() + std::chrono::duration<double>(heartbeat_timeout + options_.timeout);
    while (Clock::now() < deadline) {
      if (auto e = launcher_.reap_one()) return {};
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return "still running " + seconds_text(heartbeat_timeout + options_.timeout) + " after its director fell silent";
  }

  // A constant-light input: answers every shade request with radiance 0.5.
  void start_fake_input() {
    fake_input_ = std::make_unique<wire::Socket>(wire::Socket::Kind::router);
    if (curve_) {
      auth_->watch(*fake_input_);
      fake_input_->make_curve_server(input_keys_.secret_key);
    }
    fake_endpoint_ = *fake_input_->bind("tcp://127.0.0.1:*");
  }
  void pump_fake_input() {
    if (!fake_input_) return;
    while (auto in = fake_input_->receive()) {
      if (!in->message) continue;
      ++fake_requests_;
      const Value* n = in->message->body.find("n");
      const size_t count = n && n->is_int() ? static_cast<size_t>(n->as_int()) : 0;
      std::vector<RGB> half(count, RGB{0.5f, 0.5f, 0.5f});
      fake_input_->send_to(in->peer, wire::make_reply("check-input", in->message->header.id, encode_radiance(half)));
    }
  }

  CheckOptions options_;
  bool curve_;
  wire::CurveKeys director_keys_, actor_keys_, renderer_keys_, input_keys_;
  std::unique_ptr<wire::Authenticator> auth_;
  uint64_t refused_before_ = 0;  // the authenticator's count when this instance started
  LocalLauncher launcher_;
  std::unique_ptr<wire::Socket> control_, data_, fake_input_;
  std::string fake_endpoint_;
  std::string name_;
  pid_t pid_ = 0;
  std::optional<ExitReport> exit_;
  ShadingPoints points_;
  double heartbeat_timeout_ = 10;
  bool saw_heartbeat_ = false;
  bool beating_ = false;            // send the actor HEARTBEATs (keep_alive)
  Clock::time_point last_sent_{};   // the last control message to the actor
  std::string last_peer_;     // routing id of the last control message
  uint64_t fake_requests_ = 0;  // requests the fake inputs received
  int failures_ = 0;
};

}  // namespace

int check_actor(const CheckOptions& options) { return Checker(options).run(); }

}  // namespace lf
