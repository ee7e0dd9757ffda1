#include "actors/actor_kinds.hpp"

#include "actors/lightop_actor.hpp"
#include "actors/multiplexer_actor.hpp"
#include "actors/renderer_actor.hpp"
#include "actors/ring_node_actor.hpp"
#include "render/lightop_registry.hpp"

namespace lf {

std::unique_ptr<Actor> make_actor(const std::string& kind) {
  if (kind == "renderer") return make_renderer_actor();
  if (kind == "multiplexer") return make_multiplexer_actor();
  if (kind == "radiosity_node") return make_ring_node_actor();
  return make_lightop_actor(kind);
}

std::string actor_kind_list() { return "renderer, multiplexer, radiosity_node, " + lightop_kind_list(); }

}  // namespace lf
