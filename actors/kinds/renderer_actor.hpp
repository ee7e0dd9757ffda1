#pragma once
#include <memory>

#include "actors/runtime/runtime.hpp"

namespace lf {

std::unique_ptr<Actor> make_renderer_actor();

}  // namespace lf
