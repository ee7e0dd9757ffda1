#pragma once
// The kinds of actor a farm holds, in one table: what a kind is called (in scripts' graphs, CONFIG, the actor
// table and `lightfarm actor --kind`), the role it plays, and whether its process loads the farm's scene. The
// farm's own kinds are listed here; every LightOp kind (render/lightops/lightop_registry.hpp) is an actor kind of role
// lightop. actors/kinds/actor_kinds.cpp makes the Actor of each role.
#include <optional>
#include <string>
#include <string_view>

namespace lf {

enum class ActorRole {
  renderer,     // traces camera rays and asks the lighting network; takes tiles from the director
  multiplexer,  // a pool as one process, for plug-in clients and pools of pools
  ring_node,    // one node of the radiosity ring
  geometry,     // holds one part of a partitioned scene and traces rays through it
  plugin,       // a program of its own that speaks the protocol (lightop.exec)
  lightop,      // a built-in LightOp in the LightOp wrapper
};

struct ActorKind {
  const char* name;
  ActorRole role;
  // Its process loads the farm's scene and builds its BVH: what a host agent can share among a host's actors. (A
  // geometry actor builds a BVH of its own part only.)
  bool loads_scene;
};

inline constexpr ActorKind kRenderer{"renderer", ActorRole::renderer, true};
inline constexpr ActorKind kMultiplexer{"multiplexer", ActorRole::multiplexer, false};
inline constexpr ActorKind kRingNode{"radiosity_node", ActorRole::ring_node, false};
inline constexpr ActorKind kGeometry{"geometry", ActorRole::geometry, false};
inline constexpr ActorKind kPlugin{"exec", ActorRole::plugin, false};

// The kind called `name`: one of the farm's own, or a LightOp kind; nullopt for any other name.
std::optional<ActorKind> find_actor_kind(std::string_view name);
// Every kind's name, for messages: the farm's own, then the LightOp kinds.
std::string actor_kind_list();

}  // namespace lf
