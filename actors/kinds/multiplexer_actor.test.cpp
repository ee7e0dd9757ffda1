// The multiplexer driven over inproc:// without processes: this test plays the director, a renderer and two
// replicas that hold every request unanswered, and counts what reaches each replica. With CONFIG's input window W,
// no replica ever has more than W requests in flight; answering lets the next ones through; a lost replica's
// requests go to the other.
#include "actors/kinds/multiplexer_actor.hpp"

#include <gtest/gtest.h>

#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/inproc_actor.hpp"

namespace lf {
namespace {

using wire::MsgType;

struct Held {
  std::string peer;
  uint64_t id;
  size_t n;
};

class MultiplexerWindowTest : public ::testing::Test {
 protected:
  test::InprocActor pool{"multiplexer", "pool", [] { return make_multiplexer_actor(); }};
  wire::Socket replica[2] = {wire::Socket(wire::Socket::Kind::router), wire::Socket(wire::Socket::Kind::router)};
  std::string replica_endpoint[2];
  wire::Socket renderer{wire::Socket::Kind::dealer, "renderer-0"};

  void SetUp() override {
    static int n = 0;
    ++n;
    for (int r = 0; r < 2; ++r)
      replica_endpoint[r] = *replica[r].bind("inproc://mux-replica-" + std::to_string(n) + "-" + std::to_string(r));
  }

  static std::optional<wire::Incoming> receive(wire::Socket& s, int ms) { return test::InprocActor::poll(s, ms / 1000.0); }

  void bring_up(const std::string& strategy, int64_t window) {
    pool.next(MsgType::hello);
    ActorConfig config;
    config.params = Value::Map{{"strategy", strategy}, {"window", window}};
    for (int r = 0; r < 2; ++r) config.inputs.push_back({"pool." + std::to_string(r), replica_endpoint[r], window});
    pool.send(wire::make(MsgType::config, "director", config.to_value()));
    ASSERT_EQ(wire::phase_of(pool.next(MsgType::ready).header), wire::Phase::configure);
    ASSERT_TRUE(renderer.connect(pool.data_endpoint()).ok());
  }

  // `count` shade requests of `n` points each, ids 1..count, all sent at once.
  void send_requests(uint64_t count, size_t n) {
    ShadingPoints pts;
    for (size_t i = 0; i < n; ++i) pts.push_back({1, 1, 1}, {0, 1, 0}, {0, 1, 0}, 0, i);
    for (uint64_t id = 1; id <= count; ++id)
      renderer.send(wire::make_request("renderer-0", wire::Op::shade, encode_shade_request(pts, 0, pts.size()), id));
  }

  // Everything that reached replica r within `ms`.
  std::vector<Held> drain(int r, int ms = 200) {
    std::vector<Held> got;
    while (auto in = receive(replica[r], ms)) {
      EXPECT_TRUE(in->message.ok());
      got.push_back({in->peer, in->message->header.id, static_cast<size_t>(in->message->body.find("n")->as_int())});
    }
    return got;
  }

  void answer(int r, const Held& h) {
    replica[r].send_to(h.peer, wire::make_reply("pool." + std::to_string(r), h.id,
                                                encode_radiance(std::vector<RGB>(h.n, RGB{1, 1, 1}))));
  }
};

TEST_F(MultiplexerWindowTest, NoReplicaEverHoldsMoreThanTheWindow) {
  bring_up("round_robin", 3);
  send_requests(20, 4);
  auto held0 = drain(0), held1 = drain(1);
  EXPECT_EQ(held0.size(), 3u);  // the window, not the 4-window stall cap of round robin (12)
  EXPECT_EQ(held1.size(), 3u);
  // One answer frees one slot: exactly one more request arrives at that replica.
  answer(0, held0[0]);
  auto next0 = drain(0);
  EXPECT_EQ(next0.size(), 1u);
  EXPECT_TRUE(drain(1).empty());
  auto reply = receive(renderer, 5000);
  ASSERT_TRUE(reply && reply->message.ok());
  EXPECT_EQ(reply->message->header.type, MsgType::reply);
}

TEST_F(MultiplexerWindowTest, AWindowOfOneIsOnePacketPerReplica) {
  bring_up("least_loaded", 1);
  send_requests(6, 2);
  auto held0 = drain(0), held1 = drain(1);
  EXPECT_EQ(held0.size(), 1u);
  EXPECT_EQ(held1.size(), 1u);
  // A lost replica's packet goes to the other, still one at a time.
  pool.send(wire::make(MsgType::peer_down, "director", Value::Map{{"name", "pool.1"}}));
  answer(0, held0[0]);
  size_t answered = 1;
  for (int round = 0; round < 10 && answered < 6; ++round) {
    auto more = drain(0);
    EXPECT_LE(more.size(), 1u);
    for (const auto& h : more) {
      answer(0, h);
      ++answered;
    }
  }
  EXPECT_EQ(answered, 6u);
  EXPECT_TRUE(drain(1, 50).empty());
}

}  // namespace
}  // namespace lf
