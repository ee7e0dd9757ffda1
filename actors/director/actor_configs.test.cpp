// What each actor is told in CONFIG.
#include "actors/director/actor_configs.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>

#include "farm/builders.hpp"
#include "farm/light_path_check.hpp"

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

// Each asker is told where each input's answer can be other than zero (CONFIG inputs[i].answers_at), from the
// light paths the network composes: a glossy op's points are glossy ones, a pool's as its replicas', and a
// plug-in's, which says nothing, everywhere. It survives CONFIG's encoding.
TEST(ActorConfigs, AskersAreToldWhereEachInputsAnswerReaches) {
  FarmSpec spec;
  const int paths = add_actor(spec, ActorSpec{.name = "paths", .kind = "pathtrace"});
  const int direct = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  const int shiny = add_actor(spec, ActorSpec{.name = "shiny", .kind = "glossy", .inputs = {paths}});
  const int mirror = add_actor(spec, ActorSpec{.name = "mirror", .kind = "specular", .inputs = {direct}});
  const int lamps = add_actor(spec, ActorSpec{.name = "lamps", .kind = "emission"});
  const int plugin = add_actor(spec, ActorSpec{.name = "mine", .kind = "exec", .runtime = {{"cmd", "./mine"}}});
  PoolSpec pool;
  pool.op = add_actor(spec, ActorSpec{.name = "cache", .kind = "irradiance", .inputs = {paths}});
  pool.replicas = 2;
  auto cache = replicate(spec, pool);
  ASSERT_TRUE(cache.ok());
  const int sum = add_actor(spec, ActorSpec{.name = "sum", .kind = "combine",
                                            .inputs = {direct, shiny, mirror, lamps, *cache, plugin}});
  add_renderers(spec, 1, sum, RendererParams{}, {}, {});
  settle_pool_dispatch(spec);
  auto endpoint = [](int i) { return "tcp://host:" + std::to_string(6000 + i); };
  const auto answers = answer_ends(spec);

  const ActorConfig told = config_for(spec, sum, endpoint, {}, std::nullopt, &answers);
  auto decoded = ActorConfig::from_value(told.to_value());
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  const char* expected[] = {"DG", "G", "S", "L", "D", nullptr};
  for (const ActorConfig* c : std::initializer_list<const ActorConfig*>{&told, &*decoded}) {
    ASSERT_EQ(c->inputs.size(), 6u);
    for (size_t i = 0; i < 6; ++i) {
      SCOPED_TRACE(c->inputs[i].name);
      if (!expected[i]) {
        EXPECT_FALSE(c->inputs[i].answers);
        continue;
      }
      ASSERT_TRUE(c->inputs[i].answers);
      EXPECT_EQ(c->inputs[i].answers->letters(), expected[i]);
    }
  }
  EXPECT_TRUE(told.inputs[4].is_pool());
  // The renderer asks a combine with a plug-in among its inputs: what that answers is not known.
  EXPECT_FALSE(config_for(spec, spec.find("renderer-0"), endpoint, {}, std::nullopt, &answers).inputs[0].answers);
  // Not told (a caller without the composition): nothing is left out.
  EXPECT_FALSE(config_for(spec, sum, endpoint).inputs[0].answers);

  Value bad = told.to_value();
  bad.as_map()["inputs"].as_array()[0].as_map()["answers_at"] = "DQ";
  auto refused = ActorConfig::from_value(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("answers_at must be letters of L, D, G and S"), std::string::npos)
      << refused.error().message;
}

// Each client of a large pool connects to a subset of its replicas (farm/pool_subset.hpp): CONFIG lists every
// replica, the client's subset first, and says how many that is; the clients' subsets cover every replica evenly.
// A client also connects to the replicas on its own host (IPC, no CURVE), up to as many again. The subset
// survives CONFIG's encoding; `subset = 0` asks for all.
TEST(ActorConfigs, ClientsOfALargePoolGetEvenSubsetsAndTheRestAsSpares) {
  struct Case {
    int64_t asked;
    bool renderers_beside_replicas;
  };
  for (const Case c : {Case{-1, false}, Case{0, false}, Case{-1, true}}) {
    SCOPED_TRACE(testing::Message() << "subset " << c.asked << (c.renderers_beside_replicas ? ", shared hosts" : ""));
    FarmSpec spec;
    PoolSpec pool;
    pool.op = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
    pool.replicas = 16;
    pool.params.subset = c.asked;
    pool.hosts = {"h0", "h1", "h2", "h3"};
    auto mux = replicate(spec, pool);
    ASSERT_TRUE(mux.ok());
    RendererParams renderer;
    renderer.window = 1;
    add_renderers(spec, 12, *mux, renderer, c.renderers_beside_replicas ? pool.hosts : std::vector<std::string>{"r"}, {});
    settle_pool_dispatch(spec);
    auto endpoint = [](int i) { return "tcp://host:" + std::to_string(6000 + i); };
    std::map<std::string, int> dealt;
    for (int k = 0; k < 12; ++k) {
      const ActorSpec& me = spec.actors[static_cast<size_t>(spec.find("renderer-" + std::to_string(k)))];
      const ActorConfig r = config_for(spec, spec.find(me.name), endpoint);
      const InputSpec& in = r.inputs.at(0);
      ASSERT_EQ(in.replicas.size(), 16u);
      std::set<std::string> names;
      for (const auto& replica : in.replicas) names.insert(replica.name);
      EXPECT_EQ(names.size(), 16u);
      // 16 replicas over 12 clients need 2 each; a window of 1 asks 2. Beside 4 replicas of its host, a client
      // connects to 2 of them more (those not dealt to it already).
      if (c.asked == 0) {
        EXPECT_EQ(in.subset, 0);
      } else if (!c.renderers_beside_replicas) {
        EXPECT_EQ(in.subset, 2);
      } else {
        EXPECT_EQ(in.subset, 4);
        for (size_t i = 2; i < 4; ++i)
          EXPECT_EQ(spec.actors[static_cast<size_t>(spec.find(in.replicas[i].name))].host, me.host) << in.replicas[i].name;
      }
      for (size_t i = 0; i < (c.asked == 0 ? 16u : 2u); ++i) ++dealt[in.replicas[i].name];
      auto decoded = ActorConfig::from_value(r.to_value());
      ASSERT_TRUE(decoded.ok()) << decoded.error().message;
      EXPECT_EQ(decoded->inputs[0].subset, in.subset);
    }
    ASSERT_EQ(dealt.size(), 16u);
    for (const auto& [name, n] : dealt) {
      if (c.asked == 0) EXPECT_EQ(n, 12) << name;
      else EXPECT_TRUE(n == 1 || n == 2) << name << ": " << n;  // 24 connections over 16 replicas
    }
  }
}

// CONFIG as the director sends it, over the actor table and the deployment: a pool's client gets each live replica
// at the endpoint it reaches it by (IPC on its own host, TCP with the replica's key elsewhere), the scene's path in
// its own host's cache, and nothing of a replica lost before it was configured; a restarted replica's new address
// goes to every configured actor that asks it.
TEST(ConfigBuilder, ClientsReachLiveReplicasByTheirHostsEndpointAndKey) {
  FarmSpec spec;
  spec.hosts = {HostSpec{}, HostSpec{.name = "far", .launcher = "ssh", .address = "10.0.0.2"}};
  PoolSpec pool;
  pool.op = add_actor(spec, ActorSpec{.name = "direct", .kind = "direct"});
  pool.replicas = 3;
  pool.hosts = {"local", "far", "local"};
  auto mux = replicate(spec, pool);
  ASSERT_TRUE(mux.ok()) << mux.error().message;
  add_renderers(spec, 1, *mux, RendererParams{}, {}, {});
  settle_pool_dispatch(spec);

  Deployment d;
  d.scene_bytes = "scene";
  d.scene_hash = "h";
  d.scene_paths = {{"local", "/cache/h.lfscene"}, {"far", "/far-cache/h.lfscene"}};
  std::map<std::string, ActorRecord> table;
  for (size_t i = 0; i < spec.actors.size(); ++i) {
    ActorRecord r;
    r.spec = &spec.actors[i];
    r.index = static_cast<int>(i);
    r.endpoint = "tcp://" + std::string(r.spec->host == "far" ? "10.0.0.2" : "127.0.0.1") + ":" + std::to_string(7000 + i);
    r.local_endpoint = "ipc:///run/" + r.spec->name;
    table[r.spec->name] = r;
    d.actor_keys[r.spec->name].public_key = "key-of-" + r.spec->name;
  }
  table.at("direct.2").lost = true;
  const ConfigBuilder builder(spec, d);

  const ActorRecord& renderer = table.at("renderer-0");
  const ActorConfig c = builder.build(renderer, table);
  ASSERT_EQ(c.inputs.size(), 1u);
  ASSERT_TRUE(c.inputs[0].is_pool());
  ASSERT_EQ(c.inputs[0].replicas.size(), 2u);  // direct.2 was lost before
  EXPECT_EQ(c.inputs[0].replicas[0].endpoint, "ipc:///run/direct.0");
  EXPECT_EQ(c.inputs[0].replicas[0].key, "");  // same host: the private folder, no CURVE
  EXPECT_EQ(c.inputs[0].replicas[1].endpoint, table.at("direct.1").endpoint);
  EXPECT_EQ(c.inputs[0].replicas[1].key, "key-of-direct.1");
  EXPECT_EQ(c.scene.cache, "/cache/h.lfscene");
  EXPECT_EQ(builder.build(table.at("direct.1"), table).scene.cache, "/far-cache/h.lfscene");

  // A client that offers no IPC socket itself is reached over TCP even on the same host.
  table.at("renderer-0").local_endpoint.clear();
  EXPECT_EQ(builder.build(table.at("renderer-0"), table).inputs[0].replicas[0].endpoint, table.at("direct.0").endpoint);

}

TEST(ConfigBuilder, ARestartedInputsAskersLearnWhereItListensNow) {
  FarmSpec spec;
  const int node = add_actor(spec, ActorSpec{.name = "ring.0.0", .kind = "radiosity_node"});
  add_actor(spec, ActorSpec{.name = "ring.0.1", .kind = "radiosity_node", .inputs = {node}});
  add_actor(spec, ActorSpec{.name = "late", .kind = "radiosity_node", .inputs = {node}});
  Deployment d;
  std::map<std::string, ActorRecord> table;
  for (size_t i = 0; i < spec.actors.size(); ++i) {
    ActorRecord r;
    r.spec = &spec.actors[i];
    r.index = static_cast<int>(i);
    r.endpoint = "tcp://127.0.0.1:" + std::to_string(7000 + i);
    r.configured = r.spec->name != "late";  // not configured yet: its CONFIG will say where the node is
    table[r.spec->name] = r;
  }
  table.at("ring.0.0").endpoint = "tcp://127.0.0.1:7100";
  const auto moved = ConfigBuilder(spec, d).peer_moved(table.at("ring.0.0"), table);
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved[0].first, "ring.0.1");
  EXPECT_EQ(moved[0].second.find("endpoint")->as_string(), "tcp://127.0.0.1:7100");
  EXPECT_EQ(moved[0].second.find("key")->as_string(), "");  // no CURVE in this farm
}

}  // namespace
}  // namespace lf
