#include "actors/kinds/actor_kinds.hpp"

#include "actors/runtime/lightop_actor.hpp"
#include "actors/kinds/geometry_actor.hpp"
#include "actors/kinds/multiplexer_actor.hpp"
#include "actors/kinds/renderer_actor.hpp"
#include "actors/kinds/ring_node_actor.hpp"
#include "actors/kinds/slowdown.hpp"
#include "farm/farm_spec.hpp"
#include "render/lightop_registry.hpp"

namespace lf {

std::unique_ptr<Actor> make_actor(const std::string& kind) {
  if (kind == kRendererKind) return make_renderer_actor();
  if (kind == kMultiplexerKind) return make_multiplexer_actor();
  if (kind == kRingNodeKind) return make_ring_node_actor();
  if (kind == kGeometryKind) return make_geometry_actor();
  // Only LightOps can be pool replicas, the only actors a debug slowdown applies to.
  return with_debug_slowdown(make_lightop_actor(kind));
}

std::string actor_kind_list() {
  return std::string(kRendererKind) + ", " + kMultiplexerKind + ", " + kRingNodeKind + ", " + kGeometryKind + ", " +
         lightop_kind_list();
}

}  // namespace lf
