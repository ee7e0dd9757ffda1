#pragma once
// The director's services as one: each request goes to the service of its operation (an operation nobody serves is
// refused, naming those that are served), and phases, losses and rejoins go to every service in order.
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

#include "actors/director/service.hpp"

namespace lf {

class ServiceRouter {
 public:
  explicit ServiceRouter(std::initializer_list<Service*> services);
  Status request(const std::string& actor, wire::Message& m, Outbox& out);
  Status phase(wire::Phase phase, Outbox& out);
  Status lost(const std::string& actor, const std::string& why, Outbox& out);
  Status rejoined(const std::string& actor, Outbox& out);
  // Whether any service holds work of `actor` that exists nowhere else (it is then restarted, not just lost).
  bool needs_restart(const std::string& actor) const;
  // Whether every service's part of `phase` is done.
  bool phase_complete(wire::Phase phase) const;

 private:
  std::vector<Service*> services_;
  std::map<wire::Op, Service*> by_op_;
};

}  // namespace lf
