#include "core/result.hpp"

#include <array>

namespace lf {

namespace {
// The one table of error code names (docs/PROTOCOL.md, "ERROR").
constexpr std::array<std::pair<ErrorCode, std::string_view>, 12> kErrorCodes{{
    {ErrorCode::failed, "failed"},
    {ErrorCode::bad_message, "bad_message"},
    {ErrorCode::unknown_op, "unknown_op"},
    {ErrorCode::bad_request, "bad_request"},
    {ErrorCode::not_ready, "not_ready"},
    {ErrorCode::shade_failed, "shade_failed"},
    {ErrorCode::refused, "refused"},
    {ErrorCode::actor_failed, "actor_failed"},
    {ErrorCode::not_found, "not_found"},
    {ErrorCode::incompatible, "incompatible"},
    {ErrorCode::timeout, "timeout"},
    {ErrorCode::unreachable, "unreachable"},
}};
}  // namespace

std::string_view error_code_name(ErrorCode code) {
  for (const auto& [c, name] : kErrorCodes)
    if (c == code) return name;
  return "failed";
}

ErrorCode error_code_from_name(std::string_view name) {
  for (const auto& [c, n] : kErrorCodes)
    if (n == name) return c;
  return ErrorCode::failed;
}

}  // namespace lf
