// A radiosity ring node driven message by message, without processes: this test plays the director (and a
// hostile peer) over inproc:// sockets. A 1x1 ring needs no other node.
#include <gtest/gtest.h>

#include "actors/kinds/ring_node_actor.hpp"
#include "actors/runtime/inproc_actor.hpp"

namespace lf {
namespace {

using wire::MsgType;

class RingNodeActorTest : public ::testing::Test {
 protected:
  test::InprocActor node{"radiosity_node", "radiosity.0.0", [] { return make_ring_node_actor(); }};
  wire::Socket& director = node.director;

  static wire::Incoming receive(wire::Socket& s) { return test::InprocActor::receive(s); }
  wire::Message next(MsgType type) { return node.next(type); }

  void reply(const wire::Message& request, Value body) {
    director.send_to("radiosity.0.0", wire::make_reply("director", request.header.id, std::move(body)));
  }
};

TEST_F(RingNodeActorTest, SolvesThroughTheDirectorAndRefusesHostilePackets) {
  next(MsgType::hello);
  const std::string data = node.data_endpoint();
  director.send_to("radiosity.0.0",
                   wire::make(MsgType::config, "director",
                              Value::Map{{"params", Value::Map{{"node", 0}, {"patch_size", 140.0}, {"max_iterations", 3}}},
                                         {"scene", Value::Map{{"builtin", "cornell"}}},
                                         {"inputs", Value::Array{}}}));
  EXPECT_EQ(wire::phase_of(next(MsgType::ready).header), wire::Phase::configure);
  director.send_to("radiosity.0.0", wire::make_phase("director", wire::Phase::setup));
  auto first = next(MsgType::request);
  ASSERT_EQ(wire::op_of(first.header), wire::Op::ring_shooter);
  EXPECT_EQ(first.body.find("iteration")->as_int(), -1);
  const Value* candidate = first.body.find("candidate");
  ASSERT_TRUE(candidate && candidate->is_map());

  // A hostile peer: garbage, an unknown operation, packets that do not add up, a poll without an iteration. Each
  // gets an ERROR saying what is wrong; the node carries on.
  wire::Socket intruder(wire::Socket::Kind::dealer, "intruder");
  ASSERT_TRUE(intruder.connect(data).ok());
  ASSERT_TRUE(intruder.send_raw({"\xc1", "\x80"}));
  EXPECT_EQ(receive(intruder).message->body.find("code")->as_string(), "bad_message");
  auto refused = [&](const std::string& op, Value body, uint64_t id) {
    // Raw operation names: the node must also refuse one that is not in the protocol.
    wire::Message m = wire::make(MsgType::request, "intruder", std::move(body), id);
    m.header.op = op;
    intruder.send(m);
    auto in = receive(intruder);
    EXPECT_EQ(in.message->header.type, MsgType::error);
    EXPECT_EQ(in.message->header.id, id);
    return in.message->body.find("message")->as_string();
  };
  EXPECT_NE(refused("ring.teleport", Value::Map{}, 1).find("unknown operation 'ring.teleport'"), std::string::npos);
  EXPECT_EQ(refused("ring.visit", Value::Map{{"o", 0}}, 2), "a sample packet needs o, s, it, e, r and home in range");
  Value packet = Value::Map{{"o", 0}, {"s", 0}, {"it", 0}, {"e", 0}, {"r", 1}, {"home", 0},
                            {"p", floats_to_bytes(std::vector<float>(6, 1.0f))},
                            {"n", floats_to_bytes(std::vector<float>(3, 0.0f))},
                            {"v", u64_to_bytes(std::vector<uint64_t>(2, 1))}};
  EXPECT_EQ(refused("ring.visit", packet, 3),
            "a sample packet needs p, n (3 floats per sample) and v (one u64 per sample)");
  Value stranger = packet;
  stranger.as_map()["o"] = 7;  // there is one node
  EXPECT_EQ(refused("ring.back", stranger, 4), "a sample packet needs o, s, it, e, r and home in range");
  EXPECT_EQ(refused("ring.poll", Value::Map{}, 5), "ring.poll needs an epoch and an iteration");
  Value early = packet;
  early.as_map()["n"] = floats_to_bytes(std::vector<float>(6, 0.0f));
  early.as_map()["it"] = 40;
  EXPECT_EQ(refused("ring.visit", early, 7), "a packet of iteration 40 while this node is on 0");
  // A well-formed packet the node never sent: acknowledged, then ignored.
  Value forged = packet;
  forged.as_map()["n"] = floats_to_bytes(std::vector<float>(6, 0.0f));
  intruder.send(wire::make_request("intruder", wire::Op::ring_back, forged, 6));
  EXPECT_EQ(receive(intruder).message->header.type, MsgType::reply);

  // The solve goes on: three shooters, then done, then the elements.
  wire::Message asking = first;
  for (int it = 0; it < 3; ++it) {
    const Value* c = asking.body.find("candidate");
    ASSERT_TRUE(c && c->is_map());
    reply(asking, Value::Map{{"shooter", Value::Map{{"iteration", it}, {"patch", *c->find("patch")},
                                                   {"unshot", *c->find("unshot")}}}});
    asking = next(MsgType::request);
    ASSERT_EQ(wire::op_of(asking.header), wire::Op::ring_shooter);
    EXPECT_EQ(asking.body.find("iteration")->as_int(), it);
    EXPECT_GT(asking.body.find("power_arrived")->as_double(), 0.0);
  }
  reply(asking, Value::Map{{"done", true}});
  auto result = next(MsgType::request);
  ASSERT_EQ(wire::op_of(result.header), wire::Op::ring_result);
  std::vector<uint32_t> patches;
  ASSERT_TRUE(bytes_to_u32(result.body.find("patch")->as_bytes(), patches));
  EXPECT_GT(patches.size(), 50u);
  reply(result, Value::Map{});
  EXPECT_EQ(wire::phase_of(next(MsgType::ready).header), wire::Phase::setup);

  // Another node was lost: the director rolls the ring back to the start in epoch 1. Done or not, the node starts
  // over and reports what it reported first; a packet of epoch 0 is then acknowledged and dropped.
  director.send_to("radiosity.0.0", wire::make(MsgType::rollback, "director",
                                               Value::Map{{"epoch", 1}, {"iteration", -1}, {"patch", Bytes{}},
                                                          {"corners", Bytes{}}, {"points", Bytes{}},
                                                          {"radiosity", Bytes{}}, {"unshot", Bytes{}},
                                                          {"depth", Bytes{}}}));
  auto again = next(MsgType::request);
  ASSERT_EQ(wire::op_of(again.header), wire::Op::ring_shooter);
  EXPECT_EQ(again.body.find("epoch")->as_int(), 1);
  EXPECT_EQ(again.body.find("iteration")->as_int(), -1);
  EXPECT_EQ(*again.body.find("candidate"), *first.body.find("candidate"));
  intruder.send(wire::make_request("intruder", wire::Op::ring_visit, forged, 8));
  EXPECT_EQ(receive(intruder).message->header.type, MsgType::reply);

  director.send_to("radiosity.0.0", wire::make_phase("director", wire::Phase::finish));
  auto stats = next(MsgType::stats);
  EXPECT_GT(stats.body.find("detail")->find("rays")->as_int(), 0);
  next(MsgType::bye);
  EXPECT_EQ(node.join(), 0);
}

}  // namespace
}  // namespace lf
