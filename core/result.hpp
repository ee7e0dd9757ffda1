#pragma once
// Errors as values: a Result<T> holds either a T or an Error with a message meant for the user.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace lf {

// What kind of failure an Error is, so that code can react to it without reading its text. On the wire an ERROR
// carries the code's name (docs/PROTOCOL.md lists them); the names live in one table (core/result.cpp).
enum class ErrorCode : uint8_t {
  failed,        // no more specific code: a local failure, or a code this build does not know
  bad_message,   // undecodable bytes, or a message of the wrong type for the socket
  unknown_op,    // a REQUEST for an operation the receiver does not serve
  bad_request,   // a body that fails validation
  not_ready,     // the receiver is not configured yet
  shade_failed,  // the LightOp (or one of its inputs) failed on this batch
  refused,       // a result from an actor that does not hold the work, or a second time
  actor_failed,  // actor -> director: the actor cannot go on and is stopping
  not_found,     // fetch: nothing by that key will be published
  incompatible,  // another protocol version or float format
  timeout,       // no answer within the request timeout
  unreachable,   // the request could not be sent
};
std::string_view error_code_name(ErrorCode code);
ErrorCode error_code_from_name(std::string_view name);  // ErrorCode::failed for unknown names

struct Error {
  std::string message;
  ErrorCode code = ErrorCode::failed;
};

template <class T>
class Result {
 public:
  Result(T value) : data_(std::move(value)) {}
  Result(Error error) : data_(std::move(error)) {}

  bool ok() const { return data_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() { return std::get<0>(data_); }
  const T& value() const { return std::get<0>(data_); }
  T& operator*() { return value(); }
  const T& operator*() const { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  const Error& error() const { return std::get<1>(data_); }

 private:
  std::variant<T, Error> data_;
};

struct Ok {};
using Status = Result<Ok>;

inline Error make_error(std::string message, ErrorCode code = ErrorCode::failed) {
  return Error{std::move(message), code};
}

}  // namespace lf
