#include "transport/message.hpp"

#include <gtest/gtest.h>

#include <random>

namespace lf::wire {

TEST(Message, EveryTypeRoundTrips) {
  for (uint64_t n = 1; n <= 11; ++n) {
    Message m = make(*type_from_number(n), "renderer-0",
                     Value::Map{{"count", 3}, {"p", floats_to_bytes(std::vector<float>{1, 2, 3})},
                                {"nested", Value::Array{1.5, "x", true, nullptr}}},
                     1000 + n);
    m.header.op = op_name(Op::shade);
    m.header.queue = 7;
    auto back = decode(encode_header(m.header), encode_body(m.body));
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->header.type, m.header.type);
    EXPECT_EQ(back->header.id, 1000 + n);
    EXPECT_EQ(back->header.sender, "renderer-0");
    EXPECT_EQ(op_from_name(back->header.op), Op::shade);
    EXPECT_EQ(back->header.queue, 7u);
    EXPECT_EQ(back->body, m.body);
  }
}

TEST(Message, WrongVersionSaysIncompatible) {
  Header h;
  h.version = 7;
  h.type = MsgType::hello;
  auto r = decode_header(encode_header(h));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "incompatible peer: protocol version 7, expected 1");
}

TEST(Message, UnknownTypeIsRefused) {
  Header h;
  std::string bytes = encode_header(h);
  // Patch the type byte: "t" is followed by a positive fixint.
  auto pos = bytes.find("\xa1t");
  ASSERT_NE(pos, std::string::npos);
  bytes[pos + 2] = 99;
  auto r = decode_header(bytes);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "unknown message type 99");
}

TEST(Message, TruncatedHeaderAndBodyAreErrors) {
  Message m = make_request("a", Op::shade, Value::Map{{"k", Value::Array{1, 2, 3, 4}}}, 0);
  std::string h = encode_header(m.header), b = encode_body(m.body);
  for (size_t cut = 0; cut < h.size(); ++cut) EXPECT_FALSE(decode_header(h.substr(0, cut)).ok()) << cut;
  for (size_t cut = 0; cut < b.size(); ++cut) EXPECT_FALSE(decode_body(b.substr(0, cut)).ok()) << cut;
  auto r = decode_body(b.substr(0, b.size() - 1));
  EXPECT_EQ(r.error().message, "body is truncated");
}

TEST(Message, TrailingBytesAreErrors) {
  std::string b = encode_body(Value::Map{{"a", 1}}) + "xx";
  auto r = decode_body(b);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "body has 2 trailing bytes");
}

TEST(Message, OversizedHeaderIsRefusedBeforeDecoding) {
  Header h;
  h.sender = std::string(5000, 'x');
  auto r = decode_header(encode_header(h));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("exceeds the limit"), std::string::npos);
}

TEST(Message, LongSenderIsRefused) {
  Header h;
  h.sender = std::string(kMaxNameBytes + 1, 'x');
  auto r = decode_header(encode_header(h));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "header field 's' (sender) is not a short string");
}

TEST(Message, HostileContainerSizeIsRefusedWithoutAllocating) {
  // array32 announcing 4 billion elements, with nothing behind it.
  std::string bytes = "\x81\xa1" "a" "\xdd\xff\xff\xff\xff";
  auto r = decode_body(bytes);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "body declares a container or string larger than the message");
}

TEST(Message, DeepNestingIsRefused) {
  std::string bytes = "\x81\xa1" "a" + std::string(100, '\x91') + "\x01";
  auto r = decode_body(bytes);
  ASSERT_FALSE(r.ok());
}

TEST(Message, BodyMustBeAMapAndHeaderFieldsTyped) {
  EXPECT_EQ(decode_body(encode_body(Value(3))).error().message, "body is not a map");
  EXPECT_TRUE(decode_body(encode_body(Value())).ok());
  EXPECT_EQ(decode_header(encode_body(Value::Map{{"t", 1}})).error().message,
            "header has no protocol version 'v'");
  EXPECT_EQ(decode_header(encode_body(Value::Map{{"v", "one"}, {"t", 1}})).error().message,
            "header field 'v' (protocol version) is not an unsigned integer");
  EXPECT_EQ(decode_header(encode_body(Value::Map{{"v", 1}})).error().message, "header has no message type 't'");
  EXPECT_EQ(decode_header(encode_body(Value::Map{{"v", 1}, {"t", 4}, {"id", -1}})).error().message,
            "header field 'id' is not an unsigned integer");
}

TEST(Message, RandomBytesNeverCrash) {
  std::mt19937 rng(12345);
  int accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string bytes(rng() % 64, '\0');
    for (auto& c : bytes) c = static_cast<char>(rng());
    accepted += decode_header(bytes).ok();
    accepted += decode_body(bytes).ok();
  }
  EXPECT_LT(accepted, 200);  // random bytes are almost never a valid header or map body
}

TEST(Message, MutatedValidMessagesNeverCrash) {
  Message m = make_request("renderer-0", Op::shade,
                           Value::Map{{"n", 2}, {"p", floats_to_bytes(std::vector<float>{1, 2, 3, 4, 5, 6})}}, 42);
  const std::string h = encode_header(m.header), b = encode_body(m.body);
  std::mt19937 rng(7);
  for (int i = 0; i < 20000; ++i) {
    std::string hh = h, bb = b;
    std::string& target = (i % 2) ? hh : bb;
    int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) target[rng() % target.size()] = static_cast<char>(rng());
    (void)decode(hh, bb);
  }
  SUCCEED();
}

TEST(Message, OperationsAndPhasesRoundTripThroughTheirOneTable) {
  for (Op op : {Op::shade, Op::tile, Op::tile_done, Op::fetch, Op::ring_shooter, Op::ring_result,
                Op::ring_visit, Op::ring_back, Op::ring_return, Op::ring_poll, Op::trace}) {
    auto m = make_request("a", op, Value::Map{}, 1);
    auto back = decode(encode_header(m.header), encode_body(m.body));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(op_of(back->header), op) << op_name(op);
  }
  for (Phase p : {Phase::configure, Phase::setup, Phase::render, Phase::finish}) {
    EXPECT_EQ(phase_of(make_phase("director", p).header), p);
    EXPECT_EQ(phase_of(make_ready("a", p).header), p);
  }
  EXPECT_EQ(op_from_name("ring.spin"), Op::unknown);
  EXPECT_FALSE(phase_from_name("lunch"));
  // A PHASE header's op is a phase, never an operation; a REQUEST's is never a phase.
  EXPECT_EQ(op_of(make_phase("director", Phase::render).header), Op::unknown);
  EXPECT_FALSE(phase_of(make_request("a", Op::shade, Value::Map{}, 1).header));
}

TEST(Message, ErrorRepliesCarryTheirCode) {
  auto m = make_error_reply("direct", 7, ErrorCode::bad_request, "no points");
  auto back = decode(encode_header(m.header), encode_body(m.body));
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->body.find("code")->as_string(), "bad_request");
  Error e = error_of(*back);
  EXPECT_EQ(e.code, ErrorCode::bad_request);
  EXPECT_EQ(e.message, "no points");
  // A code this build does not know reads as `failed`, never as something it is not.
  auto foreign = make(MsgType::error, "x", Value::Map{{"code", "on_fire"}, {"message", "m"}}, 1);
  EXPECT_EQ(error_of(foreign).code, ErrorCode::failed);
  // A version mismatch is recognisable by code, not by its text.
  Header h;
  h.version = 9;
  EXPECT_EQ(decode_header(encode_header(h)).error().code, ErrorCode::incompatible);
}

}  // namespace lf::wire
