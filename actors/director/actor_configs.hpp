#pragma once
// What the director sends each actor in CONFIG, as a plain function of the farm and the actors' endpoints, so that
// what an actor is told (its inputs and their windows, its place in a pool, its debug knobs) is tested without
// processes (actor_configs.test.cpp).
#include <functional>
#include <string>

#include "actors/runtime/actor_config.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

// `endpoint_of(i)`: the data endpoint actor i said in its HELLO; `key_of(i)` (for a CURVE farm): its public key.
ActorConfig config_for(const FarmSpec& spec, int actor, const std::function<std::string(int)>& endpoint_of,
                       const std::function<std::string(int)>& key_of = {});

}  // namespace lf
