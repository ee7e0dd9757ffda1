#pragma once
#include <memory>

#include "actors/runtime/runtime.hpp"

namespace lf {

struct LightOpKind;

// Hosts one LightOp of the given kind (see lightop_actor.cpp for the contract); nullptr for an unknown name.
std::unique_ptr<Actor> make_lightop_actor(const std::string& kind);
// The same for a kind that is not in the registry (an out-of-tree LightOp, actors/runtime/sdk.hpp).
std::unique_ptr<Actor> make_lightop_actor(const LightOpKind& kind);

}  // namespace lf
