#pragma once
#include <memory>

#include "actors/runtime/runtime.hpp"

namespace lf {

std::unique_ptr<Actor> make_geometry_actor();

}  // namespace lf
