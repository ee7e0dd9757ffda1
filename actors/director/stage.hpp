#pragma once
// The director's stages, in order, with the names its timing table prints. The wire phases (configure, setup,
// render, finish) are stages too; launch and hello happen before any actor can be told anything.
#include <optional>
#include <string_view>

#include "transport/protocol.hpp"

namespace lf {

enum class Stage { prepare, launch, hello, configure, setup, render, finish };

inline std::string_view stage_name(Stage s) {
  switch (s) {
    case Stage::prepare: return "prepare";
    case Stage::launch: return "launch";
    case Stage::hello: return "hello";
    case Stage::configure: return wire::phase_name(wire::Phase::configure);
    case Stage::setup: return wire::phase_name(wire::Phase::setup);
    case Stage::render: return wire::phase_name(wire::Phase::render);
    case Stage::finish: return wire::phase_name(wire::Phase::finish);
  }
  return "?";
}

// Before configuration an actor's death is a start-up problem; after it, a failure during a named phase.
constexpr bool starting_up(Stage s) { return s <= Stage::configure; }

}  // namespace lf
