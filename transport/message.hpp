#pragma once
// Message encoding and validation. Decoding never throws and never trusts its input: every failure is an Error
// whose message says what was wrong with the bytes.
#include <string>
#include <string_view>

#include "core/result.hpp"
#include "core/value.hpp"
#include "transport/protocol.hpp"

namespace lf::wire {

struct Header {
  uint32_t version = kProtocolVersion;
  MsgType type = MsgType::heartbeat;
  uint64_t id = 0;        // request id; a REPLY/ERROR echoes the request's
  std::string sender;     // actor name
  std::string op;         // operation for REQUEST (see Op); phase name for PHASE and READY (see Phase)
  uint32_t queue = 0;     // sender's queue length (requests waiting), piggybacked for load balancing
};

struct Message {
  Header header;
  Value body;  // nil or a map
};

std::string encode_header(const Header& header);
std::string encode_body(const Value& body);

// Validates and decodes. A version mismatch is reported as such ("protocol version 7, expected 1") so that the
// receiver can refuse the peer by name.
Result<Header> decode_header(std::string_view bytes);
Result<Value> decode_body(std::string_view bytes);
Result<Message> decode(std::string_view header, std::string_view body);

// The operation a REQUEST names (Op::unknown for a name not in the table), and the phase of a PHASE or READY.
Op op_of(const Header& header);
std::optional<Phase> phase_of(const Header& header);

// Makers for every message kind; the only places a header's `op` is written.
Message make(MsgType type, std::string sender, Value body = {}, uint64_t id = 0);
Message make_request(std::string sender, Op op, Value body, uint64_t id);
Message make_reply(std::string sender, uint64_t id, Value body, uint32_t queue = 0);
// `body`: what the phase carries besides its name (PHASE frame: {frame, camera}).
Message make_phase(std::string sender, Phase phase, Value::Map body = {});
Message make_ready(std::string sender, Phase phase);
Message make_error_reply(std::string sender, uint64_t id, ErrorCode code, std::string message);
// An ERROR's body as an Error: its code and message ("?" when the body says nothing).
Error error_of(const Message& error);

}  // namespace lf::wire
