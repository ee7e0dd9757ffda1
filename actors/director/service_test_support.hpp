#pragma once
// What the director service tests share: an Outbox that records every answer in order.
#include <optional>
#include <string>
#include <vector>

#include "actors/director/service.hpp"

namespace lf::test {

struct Sent {
  std::string actor;
  uint64_t id = 0;
  bool refused = false;
  ErrorCode code = ErrorCode::failed;
  std::string message;  // when refused
  Value body;           // when replied or told
  std::optional<wire::MsgType> told;  // set: a message the service started
};

class RecordingOutbox final : public Outbox {
 public:
  void reply(const std::string& actor, uint64_t id, Value body) override { sent.push_back({actor, id, false, {}, {}, std::move(body)}); }
  void refuse(const std::string& actor, uint64_t id, ErrorCode code, const std::string& message) override {
    sent.push_back({actor, id, true, code, message, {}});
  }
  void tell(const std::string& actor, wire::MsgType type, Value body) override {
    sent.push_back({actor, 0, false, {}, {}, std::move(body), type});
  }
  void send(const std::string& actor, wire::Message m) override {
    sent.push_back({actor, m.header.id, false, {}, {}, std::move(m.body), m.header.type});
  }
  // Takes what was sent so far.
  std::vector<Sent> take() { return std::exchange(sent, {}); }
  std::vector<Sent> sent;
};

}  // namespace lf::test
