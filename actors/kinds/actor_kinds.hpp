#pragma once
// Every actor kind a `lightfarm actor --kind K` process can host, by name: "renderer", and each LightOp kind
// (wrapped by the LightOp wrapper).
#include <memory>
#include <string>

#include "actors/runtime/runtime.hpp"
#include "farm/actor_kinds.hpp"

namespace lf {

// The Actor of each role in farm/actor_kinds.hpp; nullptr for an unknown kind (actor_kind_list() names the known).
std::unique_ptr<Actor> make_actor(const std::string& kind);

}  // namespace lf
