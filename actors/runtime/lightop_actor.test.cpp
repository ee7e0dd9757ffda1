// The LightOp wrapper driven message by message, without processes: the runtime runs on a thread, this test plays
// the director and a renderer over inproc:// sockets (CZMQ's habit), and checks every reply.
#include <gtest/gtest.h>

#include <thread>

#include "actors/runtime/lightop_actor.hpp"
#include "actors/codecs/shade_codec.hpp"
#include "render/lightop_registry.hpp"
#include "render/sampler.hpp"

namespace lf {
namespace {

using wire::MsgType;

class LightOpActorTest : public ::testing::Test {
 protected:
  wire::Socket director{wire::Socket::Kind::router};
  std::string control, data;
  std::thread thread;
  int exit_status = -1;

  void SetUp() override {
    static int n = 0;
    ++n;
    control = *director.bind("inproc://director-" + std::to_string(n));
    ActorArgs args{"direct", "direct", control, "inproc://direct-" + std::to_string(n)};
    thread = std::thread([this, args] {
      auto actor = make_lightop_actor("direct");
      Runtime rt(args);
      exit_status = rt.run(*actor);
    });
  }
  void TearDown() override {
    if (thread.joinable()) {
      director.send_to("direct", wire::make(MsgType::bye, "director"));
      thread.join();
    }
  }

  static wire::Incoming receive(wire::Socket& s) {
    wire::Poller p;
    p.add(s);
    for (int i = 0; i < 500; ++i) {
      if (auto in = s.receive()) return std::move(*in);
      p.wait(10);
    }
    ADD_FAILURE() << "nothing arrived within 5 s";
    return wire::Incoming{{}, make_error("timeout"), 0};
  }

  wire::Message expect_from_director_side(MsgType type) {
    auto in = receive(director);
    EXPECT_TRUE(in.message.ok()) << in.message.error().message;
    EXPECT_EQ(in.peer, "direct");
    EXPECT_EQ(in.message->header.type, type) << wire::type_name(in.message->header.type);
    return std::move(*in.message);
  }

  // HELLO -> CONFIG -> READY configure -> PHASE setup -> READY setup
  void bring_up(Value::Map params) {
    auto hello = expect_from_director_side(MsgType::hello);
    EXPECT_EQ(hello.body.find("kind")->as_string(), "direct");
    data = hello.body.find("endpoint")->as_string();
    director.send_to("direct", wire::make(MsgType::config, "director",
                                          Value::Map{{"params", std::move(params)},
                                                     {"scene", Value::Map{{"builtin", "cornell"}}},
                                                     {"inputs", Value::Array{}}}));
    while (true) {
      auto m = expect_from_director_side(MsgType::ready);
      if (wire::phase_of(m.header) == wire::Phase::configure) break;
    }
    director.send_to("direct", wire::make_phase("director", wire::Phase::setup));
    EXPECT_EQ(wire::phase_of(expect_from_director_side(MsgType::ready).header), wire::Phase::setup);
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
  ASSERT_TRUE(renderer.connect(data).ok());

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
  director.send_to("direct", wire::make_phase("director", wire::Phase::finish));
  wire::Message stats;
  do stats = expect_from_director_side(MsgType::stats);
  while (stats.header.type != MsgType::stats);
  EXPECT_EQ(stats.body.find("requests")->as_int(), 1);
  EXPECT_EQ(stats.body.find("points")->as_int(), 64);
  expect_from_director_side(MsgType::bye);
  thread.join();
  EXPECT_EQ(exit_status, 0);
}

TEST_F(LightOpActorTest, BadParametersFailConfigurationWithTheReason) {
  expect_from_director_side(MsgType::hello);
  director.send_to("direct", wire::make(MsgType::config, "director",
                                        Value::Map{{"params", Value::Map{{"light_samples", "many"}}},
                                                   {"scene", Value::Map{{"builtin", "cornell"}}}}));
  auto err = expect_from_director_side(MsgType::error);
  EXPECT_EQ(err.body.find("message")->as_string(),
            "lightop 'direct': parameter 'light_samples' must be an integer, got a string");
  thread.join();
  EXPECT_EQ(exit_status, 1);
}

}  // namespace
}  // namespace lf
