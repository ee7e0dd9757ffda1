// The FarmSpec builders without Lua: pools, renderers, rings, validation and DOT.
#include "farm/builders.hpp"

#include <gtest/gtest.h>

namespace lf {
namespace {

int add(FarmSpec& s, const std::string& name, const std::string& kind, std::vector<int> inputs = {}) {
  const int line = static_cast<int>(s.actors.size()) + 1;
  return add_actor(s, ActorSpec{.name = name, .kind = kind, .inputs = std::move(inputs), .loc = {"farm.lua", line}});
}

std::vector<std::string> names(const FarmSpec& s) {
  std::vector<std::string> out;
  for (const auto& a : s.actors) out.push_back(a.name);
  return out;
}

TEST(Builders, UniqueNamesCountUp) {
  FarmSpec s;
  add(s, "direct", "direct");
  EXPECT_EQ(s.actors[static_cast<size_t>(add(s, "direct", "direct"))].name, "direct-2");
  EXPECT_EQ(unique_name(s, "direct"), "direct-3");
  EXPECT_EQ(unique_name(s, "photons"), "photons");
}

TEST(Builders, ReplicateCopiesTheOpAndNamesReplicasAfterIt) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  const int cache = add(s, "cache", "irradiance", {direct});
  PoolSpec pool;
  pool.op = cache;
  pool.replicas = 3;
  pool.params.window = 7;
  auto mux = replicate(s, pool);
  ASSERT_TRUE(mux.ok()) << mux.error().message;
  const ActorSpec& m = s.actors[static_cast<size_t>(*mux)];
  EXPECT_EQ(m.name, "cache");
  EXPECT_TRUE(m.is_multiplexer());
  EXPECT_EQ(m.params.at("window").as_int(), 7);
  ASSERT_EQ(m.inputs.size(), 3u);
  for (int r = 0; r < 3; ++r) {
    const ActorSpec& rep = s.actors[static_cast<size_t>(m.inputs[static_cast<size_t>(r)])];
    EXPECT_EQ(rep.name, "cache." + std::to_string(r));
    EXPECT_EQ(rep.inputs, std::vector<int>{direct});  // replicas share their inputs
    EXPECT_EQ(s.pool_of(m.inputs[static_cast<size_t>(r)]), *mux);
  }
}

TEST(Builders, NestedPoolsRenameInnerReplicasUnderTheOuterOnes) {
  FarmSpec s;
  const int op = add(s, "direct", "direct");
  PoolSpec inner;
  inner.op = op;
  inner.replicas = 2;
  auto in = replicate(s, inner);
  ASSERT_TRUE(in.ok());
  PoolSpec outer;
  outer.op = *in;
  outer.replicas = 2;
  auto out = replicate(s, outer);
  ASSERT_TRUE(out.ok()) << out.error().message;
  std::vector<std::string> n = names(s);
  std::sort(n.begin(), n.end());
  EXPECT_EQ(n, (std::vector<std::string>{"direct", "direct.0", "direct.0.0", "direct.0.1", "direct.1", "direct.1.0",
                                         "direct.1.1"}));
  // Every actor's pool at once says what pool_of says of each: the inner replicas' inner pools, the inner pools'
  // outer one, nothing for the outer pool.
  const std::vector<int> pools = s.pools();
  ASSERT_EQ(pools.size(), s.actors.size());
  int replicas = 0;
  for (size_t i = 0; i < s.actors.size(); ++i) {
    EXPECT_EQ(pools[i], s.pool_of(static_cast<int>(i))) << s.actors[i].name;
    replicas += pools[i] >= 0;
  }
  EXPECT_EQ(replicas, 6);
}

TEST(Builders, ReplicateRefusesWiredOpsAndBadSlowdowns) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  add(s, "cache", "irradiance", {direct});
  PoolSpec pool;
  pool.op = direct;
  EXPECT_EQ(replicate(s, pool).error().message,
            "lightop 'direct' is already wired elsewhere; give the multiplexer a LightOp of its own");
  FarmSpec t;
  pool.op = add(t, "direct", "direct");
  pool.slowdown = {1, 2, 3};
  EXPECT_EQ(replicate(t, pool).error().message, "multiplexer: slowdown must list one factor per replica (2)");
  pool.slowdown = {4, 1};
  auto ok = replicate(t, pool);
  ASSERT_TRUE(ok.ok());
  // The knob lands in the replica's debug settings, never in its parameters.
  EXPECT_EQ(t.actors[static_cast<size_t>(t.find("direct.0"))].debug.at("slowdown").as_double(), 4.0);
  EXPECT_TRUE(t.actors[static_cast<size_t>(t.find("direct.1"))].debug.empty());
  EXPECT_TRUE(t.actors[static_cast<size_t>(t.find("direct.0"))].params.empty());
}

TEST(Builders, RenderersAndTheirParametersAreDefinedOnce) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  RendererParams p = RendererParams::read(ParamTable(Value::Map{{"mode", "sync"}}, "renderers"));
  EXPECT_EQ(p.batch, 1);
  EXPECT_EQ(p.window, 1);
  add_renderers(s, 3, direct, p, {}, {});
  EXPECT_EQ(s.renderer_count(), 3);
  EXPECT_EQ(s.lighting, direct);
  // What the actor reads back from its CONFIG is what the script said.
  const ActorSpec& r = s.actors[static_cast<size_t>(s.find("renderer-2"))];
  RendererParams back = RendererParams::read(ParamTable(r.params, "renderer"));
  EXPECT_EQ(back.batch, 1);
  EXPECT_EQ(input_window(r), 1);
  EXPECT_THROW(RendererParams::read(ParamTable(Value::Map{{"window", 0}}, "renderers")), ParamError);
}

TEST(Builders, AMultiplexersWindowIsItsReplicasWindow) {
  FarmSpec s;
  PoolSpec pool;
  pool.op = add(s, "direct", "direct");
  pool.params = MultiplexerParams::read(ParamTable(Value::Map{{"window", 9}}, "multiplexer"));
  auto mux = replicate(s, pool);
  ASSERT_TRUE(mux.ok());
  EXPECT_EQ(input_window(s.actors[static_cast<size_t>(*mux)]), 9);
  EXPECT_EQ(input_window(s.actors[0]), 4);  // a LightOp's default
}

TEST(Builders, ExpandRingWiresEveryNodeToEveryOther) {
  FarmSpec s;
  Value::Map params{{"rings", 2}, {"ring_length", 2}};
  auto config = radiosity::read_ring_config(ParamTable(params, "radiosity"));
  auto op = expand_ring(s, config, params, "radiosity", {}, {});
  ASSERT_TRUE(op.ok());
  EXPECT_EQ(s.actors[static_cast<size_t>(*op)].kind, "radiosity");
  EXPECT_TRUE(s.actors[static_cast<size_t>(*op)].params.empty());
  EXPECT_EQ(names(s), (std::vector<std::string>{"radiosity.0.0", "radiosity.0.1", "radiosity.1.0", "radiosity.1.1",
                                                "radiosity"}));
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(s.actors[static_cast<size_t>(i)].params.at("node").as_int(), i);
    EXPECT_EQ(s.actors[static_cast<size_t>(i)].inputs.size(), 3u);
  }
  EXPECT_EQ(expand_ring(s, config, params, "radiosity", {}, {}).error().message,
            "radiosity: name 'radiosity' is already taken");
}

TEST(Builders, ValidateFindsDanglingOpsCyclesAndUndeclaredHosts) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  EXPECT_EQ(validate(s).error().message, "the script declares no renderers (add renderers { lighting = ... })");
  add_renderers(s, 1, direct, RendererParams{}, {}, {});
  EXPECT_TRUE(validate(s).ok());
  add(s, "lonely", "direct");
  EXPECT_EQ(validate(s).error().message,
            "farm.lua:3: lightop 'lonely' is not connected to the renderers' lighting (nothing would ask it for light)");
  s.actors.pop_back();
  s.actors[0].inputs = {0};
  EXPECT_EQ(validate(s).error().message, "farm.lua:1: 'direct' is its own input through a cycle");
  s.actors[0].inputs.clear();
  s.actors[0].host = "gpu-box";
  EXPECT_EQ(validate(s).error().message, "farm.lua:1: 'direct' is placed on undeclared host 'gpu-box'");
}

TEST(Builders, DotGroupsByHostAndDrawsRingsWithoutParsingNames) {
  FarmSpec s;
  s.hosts.push_back(HostSpec{.name = "far"});
  Value::Map params{{"rings", 1}, {"ring_length", 2}};
  auto op = expand_ring(s, radiosity::read_ring_config(ParamTable(params, "radiosity")), params, "rad", {"far"}, {});
  ASSERT_TRUE(op.ok());
  add_renderers(s, 2, *op, RendererParams{}, {}, {});
  const std::string dot = to_dot(s);
  EXPECT_NE(dot.find("subgraph \"cluster_far\""), std::string::npos);
  EXPECT_NE(dot.find("\"rad.0.0\" -> \"rad.0.1\";"), std::string::npos);
  EXPECT_NE(dot.find("\"rad.0.1\" -> \"rad.0.0\";"), std::string::npos);
  EXPECT_NE(dot.find("\"rad.0.0\" -> \"rad\" [style=dotted];"), std::string::npos);
  EXPECT_NE(dot.find("renderer × 2"), std::string::npos);
  // The arrow says what it carries: reflected radiosity, one diffuse reflection or more.
  EXPECT_NE(dot.find("\"rad\" -> \"renderers\" [label=\"LD+\"];"), std::string::npos) << dot;
}

// Renderers spread over hosts are drawn in each host's box, as many as that host runs.
TEST(Builders, DotDrawsRenderersInTheHostsTheyRunOn) {
  FarmSpec s;
  s.hosts.push_back(HostSpec{.name = "h1"});
  s.hosts.push_back(HostSpec{.name = "h2"});
  s.actors.push_back(ActorSpec{.name = "direct", .kind = "direct"});
  s.lighting = 0;
  add_renderers(s, 3, 0, RendererParams{}, {"h1", "h2"}, {});
  const std::string dot = to_dot(s);
  const size_t h1 = dot.find("subgraph \"cluster_h1\""), h2 = dot.find("subgraph \"cluster_h2\"");
  ASSERT_NE(h1, std::string::npos) << dot;
  ASSERT_NE(h2, std::string::npos) << dot;
  const size_t two = dot.find("\"renderers@h1\" [label=\"renderer × 2\""), one = dot.find("\"renderers@h2\" [label=\"renderer × 1\"");
  ASSERT_NE(two, std::string::npos) << dot;
  ASSERT_NE(one, std::string::npos) << dot;
  EXPECT_TRUE(h1 < two && two < h2 && h2 < one) << "each in its host's box: " << dot;
  EXPECT_NE(dot.find("\"direct\" -> \"renderers@h2\""), std::string::npos) << dot;
  EXPECT_NE(dot.find("\"renderers@h1\" -> film;"), std::string::npos) << dot;
}

}  // namespace
}  // namespace lf
