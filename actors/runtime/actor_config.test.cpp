// CONFIG decoding: what the director sends comes back field for field; every malformed field is refused by name.
#include "actors/runtime/actor_config.hpp"

#include <gtest/gtest.h>

namespace lf {
namespace {

TEST(ActorConfig, RoundTripsEveryField) {
  ActorConfig c;
  c.params = Value::Map{{"light_samples", 4}};
  c.scene = SceneSpec{"cornell", "", {}};
  c.camera.fov = 45;
  c.image.width = 64;
  c.inputs = {{"direct", "tcp://127.0.0.1:5000", 8}, {"caustics", "tcp://127.0.0.1:5001", 2}};
  c.runtime = Value::Map{{"cwd", "/tmp"}};
  c.debug = Value::Map{{"slowdown", 4.0}};
  c.pool = PoolPlace{"direct", 1, 3};
  c.heartbeat_timeout = 2.5;
  c.request_timeout = 30;
  c.geometry = {{"geometry.0", "tcp://127.0.0.1:5002", 4}, {"geometry.1", "tcp://127.0.0.1:5003", 4}};
  c.part_boxes = {0, 0, 0, 1, 1, 1, 1, 0, 0, 2, 1, 1};
  c.part_triangles = {3, 5, 8};
  c.local_part = 1;
  c.frame_materials = {Value::Map{{"name", "light"}, {"emission", Value::Array{1.0, 1.0, 1.0}}}};
  InputSpec pool{"pathtrace", "", 4, ""};
  pool.strategy = "least_loaded";
  pool.replicas = {{"pathtrace.0", "tcp://127.0.0.1:5004", 4}, {"pathtrace.1", "tcp://127.0.0.1:5005", 4}};
  pool.replicas[1].part = 1;
  c.inputs.push_back(pool);
  auto back = ActorConfig::from_value(c.to_value());
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->to_value(), c.to_value());
  EXPECT_EQ(back->inputs[0].window, 8);
  EXPECT_EQ(back->pool->index, 1);
  EXPECT_EQ(back->camera.fov, 45);
  EXPECT_EQ(back->geometry[1].name, "geometry.1");
  EXPECT_EQ(back->part_boxes, c.part_boxes);
  EXPECT_EQ(back->part_triangles, c.part_triangles);
  EXPECT_EQ(back->local_part, 1);
  EXPECT_EQ(back->frame_materials, c.frame_materials);
  EXPECT_EQ(back->inputs[2].replicas[0].part, -1);
  EXPECT_EQ(back->inputs[2].replicas[1].part, 1);
}

TEST(ActorConfig, RefusesMalformedFieldsByName) {
  auto refused = [](Value::Map body) {
    auto r = ActorConfig::from_value(Value(std::move(body)));
    EXPECT_FALSE(r.ok());
    return r.ok() ? std::string() : r.error().message;
  };
  EXPECT_EQ(refused({{"params", 3}}), "CONFIG 'params' must be a map");
  EXPECT_EQ(refused({{"inputs", Value::Array{Value::Map{{"name", "x"}}}}}), "CONFIG names an input without name or endpoint");
  EXPECT_EQ(refused({{"inputs", Value::Array{Value::Map{{"name", "x"}, {"endpoint", "e"}, {"window", 0}}}}}),
            "CONFIG input 'x': window must be an integer in [1, 1024]");
  EXPECT_EQ(refused({{"pool", Value::Map{{"name", "p"}, {"index", 3}, {"count", 2}}}}),
            "CONFIG 'pool' must be {name, index, count} with 0 <= index < count");
  EXPECT_EQ(refused({{"geometry", Value::Array{Value::Map{{"name", "g"}, {"endpoint", "e"}}}}}),
            "CONFIG 'part_boxes' must hold 6 floats for each of the 1 parts");
  EXPECT_EQ(refused({{"part_triangles", "abc"}}), "CONFIG 'part_triangles' must be u32 triangle ids");
  EXPECT_EQ(refused({{"local_part", 0}}), "CONFIG 'local_part' must name one of the 0 parts, with its part_triangles");
  EXPECT_EQ(refused({{"frame_materials", Value::Array{3}}}),
            "CONFIG 'frame_materials' must be a list of material changes, each a map with a name");
  EXPECT_EQ(refused({{"heartbeat_timeout", "soon"}}), "CONFIG 'heartbeat_timeout' must be a positive number of seconds");
  EXPECT_FALSE(ActorConfig::from_value(Value(3)).ok());
  // The minimal CONFIG of an older director: everything optional has its default.
  auto minimal = ActorConfig::from_value(Value::Map{{"scene", Value::Map{{"builtin", "cornell"}}}});
  ASSERT_TRUE(minimal.ok());
  EXPECT_TRUE(minimal->inputs.empty());
  EXPECT_EQ(minimal->request_timeout, 120);
}

}  // namespace
}  // namespace lf
