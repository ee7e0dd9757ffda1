#pragma once
#include <memory>

#include "actors/runtime.hpp"

namespace lf {

// Hosts one LightOp of the given kind (see lightop_actor.cpp for the contract).
std::unique_ptr<Actor> make_lightop_actor(const std::string& kind);

}  // namespace lf
