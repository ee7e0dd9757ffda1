#include "actors/kinds/actor_kinds.hpp"

#include "actors/runtime/lightop_actor.hpp"
#include "actors/kinds/geometry_actor.hpp"
#include "actors/kinds/multiplexer_actor.hpp"
#include "actors/kinds/renderer_actor.hpp"
#include "actors/kinds/ring_node_actor.hpp"
#include "actors/kinds/slowdown.hpp"
#include "farm/farm_spec.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf {

std::unique_ptr<Actor> make_actor(const std::string& kind) {
  const auto k = find_actor_kind(kind);
  if (!k) return nullptr;
  switch (k->role) {
    case ActorRole::renderer: return make_renderer_actor();
    case ActorRole::multiplexer: return make_multiplexer_actor();
    case ActorRole::ring_node: return make_ring_node_actor();
    case ActorRole::geometry: return make_geometry_actor();
    case ActorRole::plugin: return nullptr;  // a program of its own, never hosted here
    // Only LightOps can be pool replicas, the only actors a debug slowdown applies to.
    case ActorRole::lightop: return with_debug_slowdown(make_lightop_actor(kind));
  }
  return nullptr;
}

}  // namespace lf
