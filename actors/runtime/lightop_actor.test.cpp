// The LightOp wrapper driven message by message, without processes: the runtime runs on a thread, this test plays
// the director and a renderer over inproc:// sockets (CZMQ's habit), and checks every reply.
#include <gtest/gtest.h>

#include "actors/runtime/inproc_actor.hpp"
#include "actors/runtime/lightop_actor.hpp"
#include "actors/codecs/shade_codec.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

using wire::MsgType;

class LightOpActorTest : public ::testing::Test {
 protected:
  test::InprocActor actor{"direct", "direct", [] { return make_lightop_actor("direct"); }};

  static wire::Incoming receive(wire::Socket& s) { return test::InprocActor::receive(s); }

  // HELLO -> CONFIG -> READY configure -> PHASE setup -> READY setup
  void bring_up(Value::Map params) {
    auto hello = actor.next(MsgType::hello);
    EXPECT_EQ(hello.body.find("kind")->as_string(), "direct");
    actor.send(wire::make(MsgType::config, "director",
                                          Value::Map{{"params", std::move(params)},
                                                     {"scene", Value::Map{{"builtin", "cornell"}}},
                                                     {"inputs", Value::Array{}}}));
    while (true) {
      auto m = actor.next(MsgType::ready);
      if (wire::phase_of(m.header) == wire::Phase::configure) break;
    }
    actor.send(wire::make_phase("director", wire::Phase::setup));
    EXPECT_EQ(wire::phase_of(actor.next(MsgType::ready).header), wire::Phase::setup);
  }
};

ShadingPoints floor_points(size_t n) {
  ShadingPoints pts;
  for (size_t i = 0; i < n; ++i)
    pts.push_back({400.0f + 0.5f * static_cast<float>(i), 0.0f, 100.0f}, {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0));
  return pts;
}

TEST_F(LightOpActorTest, ShadesLikeTheInProcessOpAndSurvivesBadPackets) {
  bring_up(Value::Map{{"light_samples", 4}});
  wire::Socket renderer(wire::Socket::Kind::dealer, "renderer-0");
  ASSERT_TRUE(renderer.connect(actor.data_endpoint()).ok());

  // Garbage, an unknown operation, and an inconsistent batch: each answered with ERROR, none fatal.
  ASSERT_TRUE(renderer.send_raw({"\xc1\xc1", "\x80"}));
  auto bad = receive(renderer);
  ASSERT_TRUE(bad.message.ok());
  EXPECT_EQ(bad.message->header.type, MsgType::error);
  EXPECT_EQ(bad.message->body.find("code")->as_string(), "bad_message");

  wire::Message teapot = wire::make(MsgType::request, "renderer-0", Value::Map{}, 7);
  teapot.header.op = "teapot";  // not an operation of the protocol
  renderer.send(teapot);
  auto unknown = receive(renderer);
  EXPECT_EQ(unknown.message->header.id, 7u);
  EXPECT_EQ(unknown.message->body.find("message")->as_string(), "unknown operation 'teapot' (this actor serves 'shade')");

  Value broken = encode_shade_request(floor_points(4), 0, 4);
  broken.as_map()["n"] = 9;
  renderer.send(wire::make_request("renderer-0", wire::Op::shade, broken, 8));
  auto refused = receive(renderer);
  EXPECT_EQ(refused.message->header.type, MsgType::error);
  EXPECT_EQ(refused.message->body.find("code")->as_string(), "bad_request");

  // A real batch: the answer equals the same LightOp class run in-process, bit for bit.
  auto pts = floor_points(64);
  renderer.send(wire::make_request("renderer-0", wire::Op::shade, encode_shade_request(pts, 0, pts.size()), 9));
  auto reply = receive(renderer);
  ASSERT_TRUE(reply.message.ok());
  ASSERT_EQ(reply.message->header.type, MsgType::reply) << to_json(reply.message->body);
  EXPECT_EQ(reply.message->header.id, 9u);
  auto radiance = decode_radiance(reply.message->body, pts.size());
  ASSERT_TRUE(radiance.ok()) << radiance.error().message;

  auto scene = Scene::builtin("cornell");
  RayTracer tracer(*scene);
  LocalInputs none;
  auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 4}}, "direct"));
  run_to_completion(op->setup(SceneContext{&*scene, &tracer}, none));
  std::vector<RGB> expected(pts.size());
  run_to_completion(op->shade(pts, expected, none));
  EXPECT_EQ(*radiance, expected);
  EXPECT_GT(average((*radiance)[0]), 0.0f);

  // finish: STATS counts the one good request, then BYE, then the runtime returns 0.
  actor.send(wire::make_phase("director", wire::Phase::finish));
  wire::Message stats;
  do stats = actor.next(MsgType::stats);
  while (stats.header.type != MsgType::stats);
  EXPECT_EQ(stats.body.find("requests")->as_int(), 1);
  EXPECT_EQ(stats.body.find("points")->as_int(), 64);
  actor.next(MsgType::bye);
  EXPECT_EQ(actor.join(), 0);
}

TEST_F(LightOpActorTest, BadParametersFailConfigurationWithTheReason) {
  actor.next(MsgType::hello);
  actor.send(wire::make(MsgType::config, "director",
                                        Value::Map{{"params", Value::Map{{"light_samples", "many"}}},
                                                   {"scene", Value::Map{{"builtin", "cornell"}}}}));
  auto err = actor.next(MsgType::error);
  EXPECT_EQ(err.body.find("message")->as_string(),
            "lightop 'direct': parameter 'light_samples' must be an integer, got a string");
  EXPECT_EQ(actor.join(), 1);
}

// A pool whose op shares its setup (a photon map): the replicas send each other their parts directly (pool_part),
// not through the director. The test plays replica 1: it takes replica 0's share, refuses to be fooled by a
// stranger, a round from the future or a part sent twice, gives its own share, and the map holds both.
TEST(LightOpActorPoolTest, ReplicasSendEachOtherTheirSetupPartsDirectly) {
  test::InprocActor actor{"photonmap", "photonmap.0", [] { return make_lightop_actor("photonmap"); }};
  wire::Socket peer_inbox(wire::Socket::Kind::router, "photonmap.1");  // replica 1's data socket
  const std::string peer_endpoint = *peer_inbox.bind("inproc://photonmap.1-data");
  actor.next(MsgType::hello);
  actor.send(wire::make(
      MsgType::config, "director",
      Value::Map{{"params", Value::Map{{"photons", 20000}}},
                 {"scene", Value::Map{{"builtin", "cornell_glass"}}},
                 {"pool", Value::Map{{"name", "photonmap"}, {"index", 0}, {"count", 2},
                                     {"peers", Value::Array{Value::Map{{"name", "photonmap.1"}, {"endpoint", peer_endpoint}}}}}}}));
  while (wire::phase_of(actor.next(MsgType::ready).header) != wire::Phase::configure) {
  }
  actor.send(wire::make_phase("director", wire::Phase::setup));

  // Replica 0's share of round 0 arrives here, not at the director.
  auto share = test::InprocActor::receive(peer_inbox, 30);
  ASSERT_TRUE(share.message.ok());
  EXPECT_EQ(share.peer, "photonmap.0");
  EXPECT_EQ(share.message->header.op, "pool_part");
  EXPECT_EQ(share.message->body.find("round")->as_int(), 0);
  EXPECT_EQ(share.message->body.find("index")->as_int(), 0);
  const std::string part = share.message->body.find("part")->as_bytes().data;
  ASSERT_GT(part.size(), 0u);
  ASSERT_EQ(part.size() % (12 * sizeof(float)), 0u);  // packed photons

  // One socket per sender for the whole test: a ROUTER ignores a second connection under a routing id in use.
  wire::Socket as_peer(wire::Socket::Kind::dealer, "photonmap.1"), as_stranger(wire::Socket::Kind::dealer, "stranger");
  ASSERT_TRUE(as_peer.connect(actor.data_endpoint()).ok());
  ASSERT_TRUE(as_stranger.connect(actor.data_endpoint()).ok());
  auto send_part = [&](wire::Socket& from, int64_t round, int64_t index, uint64_t id) {
    from.send(wire::make_request(&from == &as_peer ? "photonmap.1" : "stranger", wire::Op::pool_part,
                                 map_of("round", round, "index", index, "part", Bytes{part}), id));
    while (true) {  // a server may beat to a client that waits for it
      auto answer = test::InprocActor::receive(from);
      if (!answer.message.ok()) return wire::Message{};
      if (answer.message->header.type != MsgType::heartbeat) return *answer.message;
    }
  };
  auto refused = [](const wire::Message& m) {
    return m.header.type == MsgType::error ? m.body.find("message")->as_string()
                                           : "(not refused: " + std::string(wire::type_name(m.header.type)) + " " + to_json(m.body) + ")";
  };
  EXPECT_EQ(refused(send_part(as_stranger, 0, 1, 1)), "pool_part from 'stranger', which is not replica 1 of this pool");
  EXPECT_EQ(refused(send_part(as_peer, 5, 1, 2)), "pool_part for round 5 while this replica is at round 1");
  EXPECT_EQ(send_part(as_peer, 0, 1, 3).header.type, MsgType::reply);
  EXPECT_EQ(refused(send_part(as_peer, 0, 1, 4)), "pool_part: replica 1 sent round 0 twice");
  // Replica 0 finishes its setup once its own part has been taken too.
  peer_inbox.send_to("photonmap.0", wire::make_reply("photonmap.1", share.message->header.id, Value::Map{}));
  auto next_skipping_progress = [&](MsgType type) {
    while (true) {
      auto in = test::InprocActor::receive(actor.director);
      if (!in.message.ok()) return wire::Message{};
      const MsgType t = in.message->header.type;
      if (t == MsgType::heartbeat || t == MsgType::progress) continue;
      EXPECT_EQ(t, type) << wire::type_name(t) << " " << to_json(in.message->body);
      return *in.message;
    }
  };
  EXPECT_EQ(wire::phase_of(next_skipping_progress(MsgType::ready).header), wire::Phase::setup);

  actor.send(wire::make_phase("director", wire::Phase::finish));
  wire::Message stats = next_skipping_progress(MsgType::stats);
  const int64_t stored = stats.body.find("detail")->find("photons_stored")->as_int();
  EXPECT_EQ(stored, static_cast<int64_t>(2 * part.size() / (12 * sizeof(float))));  // its share and "ours"
  actor.next(MsgType::bye);
  EXPECT_EQ(actor.join(), 0);
}

}  // namespace
}  // namespace lf
