#include "actors/director/service_router.hpp"

namespace lf {

ServiceRouter::ServiceRouter(std::initializer_list<Service*> services) : services_(services) {
  for (Service* s : services_)
    for (wire::Op op : s->ops()) by_op_[op] = s;
}

Status ServiceRouter::request(const std::string& actor, wire::Message& m, Outbox& out) {
  const wire::Op op = wire::op_of(m.header);
  if (auto it = by_op_.find(op); it != by_op_.end())
    return it->second->on_request(actor, op, m.header.id, std::move(m.body), out);
  std::string served;
  for (const auto& [o, s] : by_op_) served += (served.empty() ? "'" : ", '") + std::string(wire::op_name(o)) + "'";
  out.refuse(actor, m.header.id, ErrorCode::unknown_op,
             "unknown operation '" + m.header.op + "' (the director serves " + served + ")");
  return Ok{};
}

Status ServiceRouter::phase(wire::Phase phase, Outbox& out) {
  for (Service* s : services_)
    if (auto st = s->on_phase(phase, out); !st) return st;
  return Ok{};
}

Status ServiceRouter::lost(const std::string& actor, const std::string& why, Outbox& out) {
  for (Service* s : services_)
    if (auto st = s->on_lost(actor, why, out); !st) return st;
  return Ok{};
}

Status ServiceRouter::rejoined(const std::string& actor, Outbox& out) {
  for (Service* s : services_)
    if (auto st = s->on_rejoined(actor, out); !st) return st;
  return Ok{};
}

bool ServiceRouter::needs_restart(const std::string& actor) const {
  for (const Service* s : services_)
    if (s->needs_restart(actor)) return true;
  return false;
}

bool ServiceRouter::phase_complete(wire::Phase phase) const {
  for (const Service* s : services_)
    if (!s->phase_complete(phase)) return false;
  return true;
}

}  // namespace lf
