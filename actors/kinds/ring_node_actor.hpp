#pragma once
// A radiosity ring node as an actor process (kind "radiosity_node"): wraps radiosity::RingNode, moves its sample
// packets to the other nodes, asks the director for each shooter, and polls other rings for packets when idle.
#include <memory>

#include "actors/runtime/runtime.hpp"

namespace lf {

std::unique_ptr<Actor> make_ring_node_actor();

}  // namespace lf
