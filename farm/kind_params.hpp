#pragma once
// The parameters of the actor kinds the farm provides, defined once: the Lua binding reads a script's table with
// these (an error names the script line), the director sends the result in CONFIG, and the actor reads it back with
// the same function into the same struct. LightOps define theirs in their own classes (render/lightops/lightop_registry.hpp)
// and ring nodes in radiosity/config.hpp.
#include <cstdint>
#include <string>

#include "core/params.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

// renderers { batch = 16384, window = 4, tiles_in_flight = 3, tiles_per_message = 1, mode = "async" }
struct RendererParams {
  int64_t batch = 16384;        // shading points per request
  int64_t window = 4;           // requests in flight to the lighting
  int64_t tiles_in_flight = 3;  // tiles traced ahead while earlier ones are shaded
  // Finished tiles handed to the director in one message, which asks for as many next (at most tiles_in_flight):
  // fewer messages at a director serving thousands of renderers with fast tiles (docs/SCALE.md), at the cost of
  // pixels landing later (the progress bar and preview move by batches). 1: a tile at a time.
  int64_t tiles_per_message = 1;
  // Throws ParamError. mode = "sync" (one point per request, one request and one tile at a time: what packets buy)
  // sets the other four to 1.
  static RendererParams read(const ParamTable& p);
  Value::Map to_map() const;
};

// multiplexer { strategy = "least_loaded", split = 0, window = 4, seed = 0, dispatch = "clients" }
struct MultiplexerParams {
  std::string strategy = "least_loaded";  // round_robin | least_loaded | random
  int64_t split = 0;                      // split requests larger than this across replicas (0: never)
  int64_t window = 4;                     // requests in flight to each replica
  int64_t seed = 0;                       // for strategy = "random"
  // Replicas each client connects to (the rest are spares, connected as those are lost); -1: derived
  // (pool_subset), 0: all.
  int64_t subset = -1;
  // "clients": built-in clients send to the replicas themselves and the pool has no process; "process": every
  // request goes through a multiplexer process (plug-in clients and pools of pools always do).
  std::string dispatch = "clients";
  static MultiplexerParams read(const ParamTable& p);
  Value::Map to_map() const;
};

// How many requests `asker` keeps in flight to each of its inputs: a renderer's and a multiplexer's `window`; 4 for
// LightOps (their batches come from their own requests).
int64_t input_window(const ActorSpec& asker);

}  // namespace lf
