#pragma once
// check-actor: launches an actor program and checks it against docs/PROTOCOL.md, playing the director (and, if
// asked, a constant-light input). Prints PASS or FAIL per check; returns 0 only if every check passed.
#include <string>
#include <vector>

namespace lf {

struct CheckOptions {
  std::vector<std::string> command;  // the actor program and its own arguments
  std::string kind = "exec";         // passed as --kind
  double timeout = 5.0;              // seconds allowed for each answer
  int inputs = 0;                    // constant-light inputs to offer the actor
  // As a farm runs it (farm { security }): "curve" passes --curve and the keys on standard input, and every link
  // speaks CURVE; "none" checks the actor without.
  std::string security = "curve";
  // The heartbeat_timeout the actor is configured with (farm { heartbeat_timeout }); like the director, check-actor
  // sends the actor a HEARTBEAT at least four times within it, except where the director's silence is the check.
  double heartbeat_timeout = 10.0;
};

int check_actor(const CheckOptions& options);

}  // namespace lf
