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

}  // namespace
}  // namespace lf
