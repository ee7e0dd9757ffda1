#pragma once
// Every actor kind a `lightfarm actor --kind K` process can host, by name: "renderer", and each LightOp kind
// (wrapped by the LightOp wrapper).
#include <memory>
#include <string>

#include "actors/runtime/runtime.hpp"

namespace lf {

std::unique_ptr<Actor> make_actor(const std::string& kind);  // nullptr for an unknown kind
std::string actor_kind_list();

}  // namespace lf
