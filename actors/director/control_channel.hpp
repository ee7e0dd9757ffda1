#pragma once
// The director's control socket as the Outbox of its parts: every message leaves under the name "director".
#include "actors/director/deployment.hpp"
#include "actors/director/service.hpp"
#include "core/log.hpp"
#include "transport/socket.hpp"

namespace lf {

class ControlChannel final : public Outbox {
 public:
  // Binds where the farm's actors reach it (loopback, or the deployment's address when the farm spans hosts), as
  // a CURVE server in a CURVE farm; returns the endpoint.
  Result<std::string> open(const Deployment& d) {
    if (d.curve()) {
      socket_.make_curve_server(d.director_keys.secret_key);
      d.authenticator->watch(socket_);
    }
    auto endpoint = socket_.bind("tcp://" + (d.local_address.empty() ? std::string("127.0.0.1") : d.local_address) + ":*");
    socket_.set_linger_ms(0);
    return endpoint;
  }
  wire::Socket& socket() { return socket_; }
  void send(const std::string& actor, wire::Message m) override {
    m.header.sender = "director";
    if (!socket_.send_to(actor, m)) log_debug("could not send to '" + actor + "'");
  }

 private:
  wire::Socket socket_{wire::Socket::Kind::router};
};

}  // namespace lf
