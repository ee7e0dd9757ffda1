#include "core/result.hpp"

#include "core/name_table.hpp"

namespace lf {

namespace {
// The one table of error code names (docs/PROTOCOL.md, "ERROR").
constexpr std::pair<ErrorCode, std::string_view> kErrorCodes[] = {
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
};
}  // namespace

std::string_view error_code_name(ErrorCode code) {
  return name_in<ErrorCode>(kErrorCodes, code).value_or("failed");
}

ErrorCode error_code_from_name(std::string_view name) {
  return value_in<ErrorCode>(kErrorCodes, name).value_or(ErrorCode::failed);
}

}  // namespace lf
