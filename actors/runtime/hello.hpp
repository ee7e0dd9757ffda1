#pragma once
// HELLO's body (docs/PROTOCOL.md): who the actor is and where its data socket listens. One check, used by the
// director and by check-actor, so both refuse the same things with the same words.
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "core/value.hpp"

namespace lf {

struct Hello {
  std::string kind;      // must echo the --kind the actor was started with
  int64_t pid = 0;       // the actor's process id on its host (informational)
  std::string endpoint;  // its data socket
  std::string float_format;
  std::string local_endpoint;  // optional: an IPC endpoint for actors on the same host (CURVE farms)

  Value to_value() const;
  // Decodes and checks a HELLO from actor `name` started as `expected_kind`. ErrorCode::incompatible for another
  // float format; bad_request for anything missing or wrong.
  static Result<Hello> check(const Value& body, const std::string& name, const std::string& expected_kind);
};

// The HELLO this process sends.
Hello my_hello(const std::string& kind, const std::string& endpoint);

}  // namespace lf
