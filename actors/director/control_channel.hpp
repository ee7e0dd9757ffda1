#pragma once
// The director's control socket as the Outbox of its parts: every message leaves under the name "director".
#include <chrono>
#include <unordered_map>

#include "actors/director/deployment.hpp"
#include "actors/director/service.hpp"
#include "core/log.hpp"
#include "transport/socket.hpp"

namespace lf {

class ControlChannel final : public Outbox {
 public:
  // Binds where the farm's actors reach it (loopback, or the deployment's address when the farm spans hosts), as
  // a CURVE server in a CURVE farm; returns the endpoint. The director beats every `heartbeat_interval` seconds.
  Result<std::string> open(const Deployment& d, double heartbeat_interval) {
    heartbeat_interval_ = std::chrono::duration<double>(heartbeat_interval);
    if (d.curve()) {
      socket_.make_curve_server(d.director_keys.secret_key);
      d.authenticator->watch(socket_);
    }
    // Every actor of a farm connects at once. With ZeroMQ's default backlog (100) a farm of thousands had its
    // connects dropped and retried on TCP's SYN back-off (1, 3, 7, 15 s): 10,000 actors took 15 s to say HELLO.
    socket_.set_backlog(4096);
    auto endpoint = socket_.bind("tcp://" + (d.local_address.empty() ? std::string("127.0.0.1") : d.local_address) + ":*");
    socket_.set_linger_ms(0);
    return endpoint;
  }
  wire::Socket& socket() { return socket_; }
  void send(const std::string& actor, wire::Message m) override {
    // Any message is a sign of life: a HEARTBEAT to an actor sent something within the last interval adds
    // nothing (it hears from the director within two intervals all the same). At 10,000 actors in render, the
    // beats were a third of the director's messages.
    const auto now = std::chrono::steady_clock::now();
    auto& last = last_sent_[actor];
    if (m.header.type == wire::MsgType::heartbeat && now - last < heartbeat_interval_) return;
    last = now;
    m.header.sender = "director";
    if (!socket_.send_to(actor, m)) log_debug("could not send to '" + actor + "'");
  }

 private:
  wire::Socket socket_{wire::Socket::Kind::router};
  std::chrono::duration<double> heartbeat_interval_{1.0};
  std::unordered_map<std::string, std::chrono::steady_clock::time_point> last_sent_;
};

}  // namespace lf
