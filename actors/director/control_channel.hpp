#pragma once
// The director's control socket as the Outbox of its parts: every message leaves under the name "director".
#include "actors/director/service.hpp"
#include "core/log.hpp"
#include "transport/socket.hpp"

namespace lf {

class ControlChannel final : public Outbox {
 public:
  wire::Socket& socket() { return socket_; }
  void send(const std::string& actor, wire::Message m) override {
    m.header.sender = "director";
    if (!socket_.send_to(actor, m)) log_debug("could not send to '" + actor + "'");
  }

 private:
  wire::Socket socket_{wire::Socket::Kind::router};
};

}  // namespace lf
