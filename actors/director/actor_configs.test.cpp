// What each actor is told in CONFIG.
#include "actors/director/actor_configs.hpp"

#include <gtest/gtest.h>

#include "farm/builders.hpp"

namespace lf {
namespace {

TEST(ActorConfigs, EachAskerUsesItsOwnWindowForItsInputs) {
  FarmSpec spec;
  const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  PoolSpec pool;
  pool.op = add_actor(spec, ActorSpec{.name = "cache", .kind = "irradiance", .inputs = {direct}});
  pool.replicas = 2;
  pool.params.window = 7;
  pool.slowdown = {1, 3};
  auto mux = replicate(spec, pool);
  ASSERT_TRUE(mux.ok());
  RendererParams renderer;
  renderer.window = 5;
  add_renderers(spec, 1, *mux, renderer, {}, {});
  auto endpoint = [](int i) { return "tcp://host:" + std::to_string(6000 + i); };

  const ActorConfig m = config_for(spec, *mux, endpoint);
  ASSERT_EQ(m.inputs.size(), 2u);
  for (const auto& in : m.inputs) EXPECT_EQ(in.window, 7);  // the multiplexer's window, per replica
  EXPECT_EQ(m.inputs[0].name, "cache.0");
  EXPECT_EQ(m.inputs[1].endpoint, endpoint(spec.find("cache.1")));

  const ActorConfig r = config_for(spec, spec.find("renderer-0"), endpoint);
  EXPECT_EQ(r.inputs.at(0).window, 5);
  EXPECT_EQ(r.inputs.at(0).name, "cache");

  const ActorConfig rep = config_for(spec, spec.find("cache.1"), endpoint);
  EXPECT_EQ(rep.inputs.at(0).window, 4);  // a LightOp's own inputs
  ASSERT_TRUE(rep.pool);
  EXPECT_EQ(rep.pool->name, "cache");
  EXPECT_EQ(rep.pool->index, 1);
  EXPECT_EQ(rep.pool->count, 2);
  EXPECT_EQ(rep.debug.at("slowdown").as_double(), 3.0);
  EXPECT_FALSE(config_for(spec, 0, endpoint).pool);  // direct is not a replica
}

// Built-in LightOps hold the scene and take normals and materials from it (CONFIG inputs[i].lean); a plug-in gets
// whole requests. The flag survives CONFIG's encoding.
TEST(ActorConfigs, OnlyBuiltInLightOpsAreAskedWithLeanRequests) {
  FarmSpec spec;
  const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  const int plugin = add_actor(spec, ActorSpec{.name = "mine", .kind = "exec", .runtime = {{"cmd", "./mine"}}});
  PoolSpec pool;
  pool.op = add_actor(spec, ActorSpec{.name = "sum", .kind = "combine", .inputs = {direct, plugin}});
  pool.replicas = 2;
  auto mux = replicate(spec, pool);
  ASSERT_TRUE(mux.ok());
  add_renderers(spec, 1, *mux, RendererParams{}, {}, {});
  settle_pool_dispatch(spec);
  auto endpoint = [](int i) { return "tcp://host:" + std::to_string(6000 + i); };

  const ActorConfig r = config_for(spec, spec.find("renderer-0"), endpoint);
  ASSERT_EQ(r.inputs.size(), 1u);
  ASSERT_TRUE(r.inputs[0].is_pool());
  ASSERT_EQ(r.inputs[0].replicas.size(), 2u);
  for (const auto& replica : r.inputs[0].replicas) EXPECT_TRUE(replica.lean) << replica.name;
  auto decoded = ActorConfig::from_value(r.to_value());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_TRUE(decoded->inputs[0].replicas[1].lean);

  const ActorConfig sum = config_for(spec, spec.find("sum.0"), endpoint);
  ASSERT_EQ(sum.inputs.size(), 2u);
  EXPECT_TRUE(sum.inputs[0].lean);   // direct
  EXPECT_FALSE(sum.inputs[1].lean);  // the plug-in
  decoded = ActorConfig::from_value(sum.to_value());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_TRUE(decoded->inputs[0].lean);
  EXPECT_FALSE(decoded->inputs[1].lean);
}

}  // namespace
}  // namespace lf
