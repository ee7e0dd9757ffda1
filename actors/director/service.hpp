#pragma once
// Director services: the central capabilities actors ask the director for, each registered by the operations it
// serves (tiles, setup exchanges, the radiosity ring's barrier: what cannot go peer to peer). The director owns the control socket and the actor table; a service sees only requests,
// phases and losses, and answers through an Outbox. So each is tested by feeding it messages and reading the
// Outbox (see *.test.cpp beside each), and a new central capability is a new Service, never a new branch in the
// director.
#include <string>
#include <vector>

#include "core/result.hpp"
#include "core/value.hpp"
#include "transport/message.hpp"
#include "transport/protocol.hpp"

namespace lf {

// Where everything the director's parts say to actors goes: the control socket (ControlChannel), a recorder in
// tests. One method; the others are the same message built for the purpose (a recorder may keep them apart).
class Outbox {
 public:
  virtual ~Outbox() = default;
  virtual void send(const std::string& actor, wire::Message message) = 0;
  virtual void reply(const std::string& actor, uint64_t id, Value body) {
    send(actor, wire::make_reply("director", id, std::move(body)));
  }
  virtual void refuse(const std::string& actor, uint64_t id, ErrorCode code, const std::string& message) {
    send(actor, wire::make_error_reply("director", id, code, message));
  }
  // A message the director starts (not an answer), e.g. ROLLBACK.
  virtual void tell(const std::string& actor, wire::MsgType type, Value body) {
    send(actor, wire::make(type, "director", std::move(body)));
  }
};

class Service {
 public:
  virtual ~Service() = default;
  // The operations this service serves; each operation has one service.
  virtual std::vector<wire::Op> ops() const = 0;
  // A request from `actor`, a live member of this farm. An error stops the farm with its message (a broken
  // invariant, not a bad request: those are refused through the Outbox and the farm goes on).
  virtual Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) = 0;
  // The director entered `phase` (its PHASE messages are on their way).
  virtual Status on_phase(wire::Phase, Outbox&) { return Ok{}; }
  // `actor` was lost (died or hung) in setup or render, and the farm goes on without it: its work goes elsewhere.
  // An error stops the farm (the work cannot be redone).
  virtual Status on_lost(const std::string& /*actor*/, const std::string& /*why*/, Outbox&) { return Ok{}; }
  // Whether `actor`, lost, had work that exists nowhere else and must be restarted (Supervisor: ring nodes).
  virtual bool needs_restart(const std::string& /*actor*/) const { return false; }
  // A restarted `actor` is configured again and its peers know where it listens.
  virtual Status on_rejoined(const std::string& /*actor*/, Outbox&) { return Ok{}; }
  // Whether the service's part of `phase` is done, beyond every actor's READY (the ring's solution is in: a READY
  // setup sent before a rollback does not count).
  virtual bool phase_complete(wire::Phase) const { return true; }
};

}  // namespace lf
