// The actor-kind table: every name a farm uses has one role, and whether it loads the scene follows the role.
#include "farm/actor_kinds.hpp"

#include <gtest/gtest.h>

#include "farm/farm_spec.hpp"

namespace lf {
namespace {

TEST(ActorKinds, EveryKindHasOneRoleAndLightOpsAreKindsToo) {
  EXPECT_EQ(find_actor_kind("renderer")->role, ActorRole::renderer);
  EXPECT_EQ(find_actor_kind("multiplexer")->role, ActorRole::multiplexer);
  EXPECT_EQ(find_actor_kind("radiosity_node")->role, ActorRole::ring_node);
  EXPECT_EQ(find_actor_kind("geometry")->role, ActorRole::geometry);
  EXPECT_EQ(find_actor_kind("exec")->role, ActorRole::plugin);
  ASSERT_TRUE(find_actor_kind("irradiance"));
  EXPECT_EQ(find_actor_kind("irradiance")->role, ActorRole::lightop);
  EXPECT_FALSE(find_actor_kind("teapot"));
  const std::string list = actor_kind_list();
  EXPECT_EQ(list.rfind("renderer, multiplexer, radiosity_node, geometry, ", 0), 0u) << list;
  EXPECT_NE(list.find("photonmap"), std::string::npos) << list;
  EXPECT_EQ(list.find("exec"), std::string::npos) << "a plug-in is a program, never hosted by `lightfarm actor`";
}

TEST(ActorKinds, ScenesAreLoadedByRenderersAndBuiltInLightOpsOnly) {
  auto loads = [](std::string kind, Value::Map runtime = {}) {
    ActorSpec a;
    a.kind = std::move(kind);
    a.runtime = std::move(runtime);
    return a.loads_scene();
  };
  EXPECT_TRUE(loads("renderer"));
  EXPECT_TRUE(loads("direct"));
  EXPECT_FALSE(loads("multiplexer"));
  EXPECT_FALSE(loads("radiosity_node"));
  EXPECT_FALSE(loads("geometry"));  // its own part only
  EXPECT_FALSE(loads("exec", {{"cmd", Value::Array{"./mine"}}}));
  ActorSpec plugin;
  plugin.kind = "exec";
  plugin.runtime = {{"cmd", Value::Array{"./mine"}}};
  EXPECT_EQ(plugin.role(), ActorRole::plugin);
  EXPECT_FALSE(plugin.is_renderer());
}

}  // namespace
}  // namespace lf
