#include "farm/actor_kinds.hpp"

#include "render/lightops/lightop_registry.hpp"

namespace lf {

namespace {
constexpr ActorKind kFarmKinds[] = {kRenderer, kMultiplexer, kRingNode, kGeometry, kPlugin};
}

std::optional<ActorKind> find_actor_kind(std::string_view name) {
  for (const ActorKind& k : kFarmKinds)
    if (name == k.name) return k;
  if (const LightOpKind* op = find_lightop_kind(name)) return ActorKind{op->name.data(), ActorRole::lightop, true};
  return std::nullopt;
}

std::string actor_kind_list() {
  std::string list;
  for (const ActorKind& k : kFarmKinds)
    if (k.role != ActorRole::plugin) list += std::string(k.name) + ", ";
  return list + lightop_kind_list();
}

}  // namespace lf
