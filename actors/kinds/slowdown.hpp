#pragma once
// A test knob, apart from every production path: `multiplexer { slowdown = {f0, f1, ...} }` makes replica i rest
// (fi - 1) x t after each turn of work that took t seconds, emulating a slower host without taking a core from the
// others (benchmarks of load balancing, tests that need a long frame). The director passes it in CONFIG's `debug`
// map; an actor whose CONFIG has none runs exactly as it would unwrapped.
#include <memory>

#include "actors/runtime/runtime.hpp"

namespace lf {

std::unique_ptr<Actor> with_debug_slowdown(std::unique_ptr<Actor> actor);

}  // namespace lf
