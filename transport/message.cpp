#include "transport/message.hpp"

#include <msgpack.hpp>

#include <cmath>

#include "core/name_table.hpp"

namespace lf::wire {

std::string_view type_name(MsgType type) {
  switch (type) {
    case MsgType::hello: return "HELLO";
    case MsgType::config: return "CONFIG";
    case MsgType::phase: return "PHASE";
    case MsgType::request: return "REQUEST";
    case MsgType::reply: return "REPLY";
    case MsgType::error: return "ERROR";
    case MsgType::stats: return "STATS";
    case MsgType::heartbeat: return "HEARTBEAT";
    case MsgType::bye: return "BYE";
    case MsgType::ready: return "READY";
    case MsgType::peer_down: return "PEER_DOWN";
    case MsgType::peer_moved: return "PEER_MOVED";
    case MsgType::rollback: return "ROLLBACK";
    case MsgType::progress: return "PROGRESS";
  }
  return "?";
}

std::optional<MsgType> type_from_number(uint64_t n) {
  if (n >= 1 && n <= 14) return static_cast<MsgType>(n);
  return std::nullopt;
}

namespace {
// The one table of operation and phase names on the wire.
constexpr std::pair<Op, std::string_view> kOps[] = {
    {Op::shade, "shade"},
    {Op::tile, "tile"},
    {Op::tile_done, "tile_done"},
    {Op::fetch, "fetch"},
    {Op::ring_shooter, "ring.shooter"},
    {Op::ring_result, "ring.result"},
    {Op::ring_visit, "ring.visit"},
    {Op::ring_back, "ring.back"},
    {Op::ring_return, "ring.return"},
    {Op::ring_poll, "ring.poll"},
    {Op::trace, "trace"},
    {Op::pool_part, "pool_part"},
    {Op::keep_setup, "keep_setup"},
};
constexpr std::pair<Phase, std::string_view> kPhases[] = {
    {Phase::configure, "configure"},
    {Phase::setup, "setup"},
    {Phase::render, "render"},
    {Phase::finish, "finish"},
    {Phase::frame, "frame"},
};
}  // namespace

std::string_view op_name(Op op) { return name_in<Op>(kOps, op).value_or("?"); }
Op op_from_name(std::string_view name) { return value_in<Op>(kOps, name).value_or(Op::unknown); }
std::string_view phase_name(Phase phase) { return name_in<Phase>(kPhases, phase).value_or("?"); }
std::optional<Phase> phase_from_name(std::string_view name) { return value_in<Phase>(kPhases, name); }

Op op_of(const Header& header) { return header.type == MsgType::request ? op_from_name(header.op) : Op::unknown; }

std::optional<Phase> phase_of(const Header& header) {
  if (header.type != MsgType::phase && header.type != MsgType::ready) return std::nullopt;
  return phase_from_name(header.op);
}

namespace {

// msgpack's packer writes into any buffer with write(); this one is the std::string the frame is sent from, so an
// encoded body is not copied out of an sbuffer (a copy per message, and a fresh allocation for a large one).
struct StringBuffer {
  std::string bytes;
  void write(const char* data, size_t size) { bytes.append(data, size); }
};

template <class Buffer>
using PackerInto = msgpack::packer<Buffer>;
using Packer = PackerInto<msgpack::sbuffer>;
using BodyPacker = PackerInto<StringBuffer>;

template <class Packer>
void pack_string(Packer& pk, std::string_view s) {
  pk.pack_str(static_cast<uint32_t>(s.size()));
  pk.pack_str_body(s.data(), static_cast<uint32_t>(s.size()));
}

template <class Packer>
void pack_value(Packer& pk, const Value& v) {
  const auto& s = v.storage();
  switch (s.index()) {
    case 0: pk.pack_nil(); break;
    case 1: v.as_bool() ? pk.pack_true() : pk.pack_false(); break;
    case 2: pk.pack_int64(v.as_int()); break;
    case 3: pk.pack_double(v.as_double()); break;
    case 4: pack_string(pk, v.as_string()); break;
    case 5: {
      const auto& b = v.as_bytes().data;
      pk.pack_bin(static_cast<uint32_t>(b.size()));
      pk.pack_bin_body(b.data(), static_cast<uint32_t>(b.size()));
      break;
    }
    case 6:
      pk.pack_array(static_cast<uint32_t>(v.as_array().size()));
      for (const auto& e : v.as_array()) pack_value(pk, e);
      break;
    default:
      pk.pack_map(static_cast<uint32_t>(v.as_map().size()));
      for (const auto& [k, e] : v.as_map()) {
        pack_string(pk, k);
        pack_value(pk, e);
      }
  }
}

// Objects may point into the input buffer: we copy into Values before the buffer goes away.
bool reference_everything(msgpack::type::object_type, std::size_t, void*) { return true; }

Result<msgpack::object_handle> unpack_checked(std::string_view bytes, const char* what) {
  if (bytes.empty()) return make_error(std::string(what) + " is empty");
  // No valid message has more elements than bytes, so cap container sizes by the length: hostile headers that
  // announce 2^32 elements are refused before anything is allocated for them.
  const size_t n = bytes.size();
  msgpack::unpack_limit limit(n, n, n, n, 0, kMaxDepth);
  try {
    std::size_t offset = 0;
    msgpack::object_handle oh =
        msgpack::unpack(bytes.data(), bytes.size(), offset, reference_everything, nullptr, limit);
    if (offset != bytes.size())
      return make_error(std::string(what) + " has " + std::to_string(bytes.size() - offset) + " trailing bytes");
    return oh;
  } catch (const msgpack::insufficient_bytes&) {
    return make_error(std::string(what) + " is truncated");
  } catch (const msgpack::depth_size_overflow&) {
    return make_error(std::string(what) + " nests deeper than " + std::to_string(kMaxDepth) + " levels");
  } catch (const msgpack::size_overflow&) {
    return make_error(std::string(what) + " declares a container or string larger than the message");
  } catch (const std::bad_alloc&) {
    return make_error(std::string(what) + " is too large to decode");
  } catch (const std::exception& e) {
    return make_error(std::string(what) + " is not valid msgpack (" + e.what() + ")");
  }
}

Result<Value> to_value(const msgpack::object& o, size_t depth) {
  if (depth > kMaxDepth) return make_error("nesting too deep");
  switch (o.type) {
    case msgpack::type::NIL: return Value();
    case msgpack::type::BOOLEAN: return Value(o.via.boolean);
    case msgpack::type::POSITIVE_INTEGER:
      if (o.via.u64 > static_cast<uint64_t>(INT64_MAX)) return make_error("integer out of range");
      return Value(static_cast<int64_t>(o.via.u64));
    case msgpack::type::NEGATIVE_INTEGER: return Value(o.via.i64);
    case msgpack::type::FLOAT32:
    case msgpack::type::FLOAT64: return Value(o.via.f64);
    case msgpack::type::STR: return Value(std::string(o.via.str.ptr, o.via.str.size));
    case msgpack::type::BIN: return Value(Bytes{std::string(o.via.bin.ptr, o.via.bin.size)});
    case msgpack::type::ARRAY: {
      Value::Array a;
      a.reserve(o.via.array.size);
      for (uint32_t i = 0; i < o.via.array.size; ++i) {
        auto e = to_value(o.via.array.ptr[i], depth + 1);
        if (!e) return e.error();
        a.push_back(std::move(*e));
      }
      return Value(std::move(a));
    }
    case msgpack::type::MAP: {
      Value::Map m;
      for (uint32_t i = 0; i < o.via.map.size; ++i) {
        const auto& kv = o.via.map.ptr[i];
        if (kv.key.type != msgpack::type::STR) return make_error("map key is not a string");
        auto e = to_value(kv.val, depth + 1);
        if (!e) return e.error();
        m.insert_or_assign(std::string(kv.key.via.str.ptr, kv.key.via.str.size), std::move(*e));
      }
      return Value(std::move(m));
    }
    default: return make_error("msgpack extension types are not used by this protocol");
  }
}

}  // namespace

std::string encode_header(const Header& h) {
  msgpack::sbuffer buf(64);
  Packer pk(&buf);
  pk.pack_map(6);
  pack_string(pk, "v");
  pk.pack_uint32(h.version);
  pack_string(pk, "t");
  pk.pack_uint8(static_cast<uint8_t>(h.type));
  pack_string(pk, "id");
  pk.pack_uint64(h.id);
  pack_string(pk, "s");
  pack_string(pk, h.sender);
  pack_string(pk, "op");
  pack_string(pk, h.op);
  pack_string(pk, "q");
  pk.pack_uint32(h.queue);
  return std::string(buf.data(), buf.size());
}

// An upper bound of the encoded size, so the buffer is allocated once instead of doubling (and copying) its way up
// to a 200 KB shading batch.
static size_t encoded_size_bound(const Value& v) {
  switch (v.storage().index()) {
    case 4: return v.as_string().size() + 5;
    case 5: return v.as_bytes().data.size() + 5;
    case 6: {
      size_t n = 5;
      for (const auto& e : v.as_array()) n += encoded_size_bound(e);
      return n;
    }
    case 7: {
      size_t n = 5;
      for (const auto& [k, e] : v.as_map()) n += k.size() + 5 + encoded_size_bound(e);
      return n;
    }
    default: return 9;
  }
}

std::string encode_body(const Value& body) {
  StringBuffer buf;
  buf.bytes.reserve(encoded_size_bound(body));
  BodyPacker pk(buf);
  pack_value(pk, body);
  return std::move(buf.bytes);
}

Result<Header> decode_header(std::string_view bytes) {
  if (bytes.size() > kMaxHeaderBytes)
    return make_error("header of " + std::to_string(bytes.size()) + " bytes exceeds the limit of " +
                      std::to_string(kMaxHeaderBytes));
  auto oh = unpack_checked(bytes, "header");
  if (!oh) return oh.error();
  const msgpack::object& o = oh->get();
  if (o.type != msgpack::type::MAP) return make_error("header is not a map");

  Header h;
  bool have_version = false, have_type = false;
  for (uint32_t i = 0; i < o.via.map.size; ++i) {
    const auto& kv = o.via.map.ptr[i];
    if (kv.key.type != msgpack::type::STR) return make_error("header key is not a string");
    std::string_view key(kv.key.via.str.ptr, kv.key.via.str.size);
    const auto& val = kv.val;
    auto as_uint = [&](uint64_t max, uint64_t& out) -> bool {
      if (val.type != msgpack::type::POSITIVE_INTEGER || val.via.u64 > max) return false;
      out = val.via.u64;
      return true;
    };
    auto as_str = [&](size_t max, std::string& out) -> bool {
      if (val.type != msgpack::type::STR || val.via.str.size > max) return false;
      out.assign(val.via.str.ptr, val.via.str.size);
      return true;
    };
    uint64_t u = 0;
    if (key == "v") {
      if (!as_uint(UINT32_MAX, u)) return make_error("header field 'v' (protocol version) is not an unsigned integer");
      h.version = static_cast<uint32_t>(u);
      have_version = true;
    } else if (key == "t") {
      if (!as_uint(UINT8_MAX, u)) return make_error("header field 't' (message type) is not a small unsigned integer");
      auto t = type_from_number(u);
      if (!t) return make_error("unknown message type " + std::to_string(u));
      h.type = *t;
      have_type = true;
    } else if (key == "id") {
      if (!as_uint(UINT64_MAX, h.id)) return make_error("header field 'id' is not an unsigned integer");
    } else if (key == "s") {
      if (!as_str(kMaxNameBytes, h.sender)) return make_error("header field 's' (sender) is not a short string");
    } else if (key == "op") {
      if (!as_str(kMaxOpBytes, h.op)) return make_error("header field 'op' is not a short string");
    } else if (key == "q") {
      if (!as_uint(UINT32_MAX, u)) return make_error("header field 'q' (queue length) is not an unsigned integer");
      h.queue = static_cast<uint32_t>(u);
    }
    // Unknown keys are ignored so that a later minor revision can add optional fields.
  }
  if (!have_version) return make_error("header has no protocol version 'v'");
  // The version is checked before the type so that a newer peer with new types is refused as "incompatible".
  if (h.version != kProtocolVersion)
    return make_error("incompatible peer: protocol version " + std::to_string(h.version) + ", expected " +
                          std::to_string(kProtocolVersion),
                      ErrorCode::incompatible);
  if (!have_type) return make_error("header has no message type 't'");
  return h;
}

Result<Value> decode_body(std::string_view bytes) {
  if (bytes.size() > kMaxBodyBytes)
    return make_error("body of " + std::to_string(bytes.size()) + " bytes exceeds the limit of " +
                      std::to_string(kMaxBodyBytes));
  auto oh = unpack_checked(bytes, "body");
  if (!oh) return oh.error();
  const msgpack::object& o = oh->get();
  if (o.type != msgpack::type::MAP && o.type != msgpack::type::NIL) return make_error("body is not a map");
  auto v = to_value(o, 0);
  if (!v) return make_error("body: " + v.error().message);
  return v;
}

Result<Message> decode(std::string_view header, std::string_view body) {
  auto h = decode_header(header);
  if (!h) return h.error();
  auto b = decode_body(body);
  if (!b) return b.error();
  return Message{std::move(*h), std::move(*b)};
}

Message make(MsgType type, std::string sender, Value body, uint64_t id) {
  Message m;
  m.header.type = type;
  m.header.sender = std::move(sender);
  m.header.id = id;
  m.body = std::move(body);
  return m;
}

Message make_request(std::string sender, Op op, Value body, uint64_t id) {
  Message m = make(MsgType::request, std::move(sender), std::move(body), id);
  m.header.op = op_name(op);
  return m;
}

Message make_reply(std::string sender, uint64_t id, Value body, uint32_t queue) {
  Message m = make(MsgType::reply, std::move(sender), std::move(body), id);
  m.header.queue = queue;
  return m;
}

Message make_phase(std::string sender, Phase phase, Value::Map body) {
  body["phase"] = std::string(phase_name(phase));
  Message m = make(MsgType::phase, std::move(sender), std::move(body));
  m.header.op = phase_name(phase);
  return m;
}

Message make_ready(std::string sender, Phase phase) {
  Message m = make(MsgType::ready, std::move(sender), Value::Map{{"phase", std::string(phase_name(phase))}});
  m.header.op = phase_name(phase);
  return m;
}

Message make_error_reply(std::string sender, uint64_t id, ErrorCode code, std::string message) {
  return make(MsgType::error, std::move(sender),
              Value::Map{{"code", std::string(error_code_name(code))}, {"message", std::move(message)}}, id);
}

Error error_of(const Message& error) {
  const Value* text = error.body.find("message");
  const Value* code = error.body.find("code");
  return make_error(text && text->is_string() ? text->as_string() : "?",
                    code && code->is_string() ? error_code_from_name(code->as_string()) : ErrorCode::failed);
}

}  // namespace lf::wire
