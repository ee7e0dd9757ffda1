#include "actors/runtime/hello.hpp"

#include <unistd.h>

#include "transport/protocol.hpp"

namespace lf {

Value Hello::to_value() const {
  Value::Map m{{"kind", kind}, {"pid", pid}, {"endpoint", endpoint}, {"float_format", float_format}};
  if (!local_endpoint.empty()) m["local_endpoint"] = local_endpoint;
  return m;
}

Result<Hello> Hello::check(const Value& body, const std::string& name, const std::string& expected_kind) {
  auto text = [&](const char* key) -> std::string {
    const Value* v = body.find(key);
    return v && v->is_string() ? v->as_string() : std::string();
  };
  Hello h;
  h.kind = text("kind");
  h.endpoint = text("endpoint");
  h.float_format = text("float_format");
  h.local_endpoint = text("local_endpoint");
  if (!h.local_endpoint.empty() && h.local_endpoint.rfind("ipc://", 0) != 0)
    return make_error("actor '" + name + "' offers a local endpoint that is not ipc://", ErrorCode::bad_request);
  if (const Value* pid = body.find("pid"); pid && pid->is_int()) h.pid = pid->as_int();
  if (h.float_format != wire::kFloatFormat)
    return make_error("actor '" + name + "' is incompatible: float format '" + (h.float_format.empty() ? "?" : h.float_format) +
                          "', expected '" + std::string(wire::kFloatFormat) + "'",
                      ErrorCode::incompatible);
  if (h.kind != expected_kind)
    return make_error("actor '" + name + "' says it is a '" + (h.kind.empty() ? "?" : h.kind) + "', expected '" +
                          expected_kind + "'",
                      ErrorCode::bad_request);
  if (h.endpoint.empty())
    return make_error("actor '" + name + "' sent no data endpoint in its HELLO", ErrorCode::bad_request);
  return h;
}

Hello my_hello(const std::string& kind, const std::string& endpoint) {
  return Hello{kind, static_cast<int64_t>(::getpid()), endpoint, std::string(wire::kFloatFormat)};
}

}  // namespace lf
