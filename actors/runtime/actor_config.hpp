#pragma once
// CONFIG's body (docs/PROTOCOL.md), typed: the director builds an ActorConfig and sends to_value(); the runtime
// decodes it once with from_value(), which checks every field, and hands the actor this struct. Actors read their
// algorithm parameters from `params` with their own ParamTable definitions.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "core/specs.hpp"
#include "core/value.hpp"
#include "render/shading/light_paths.hpp"

namespace lf {

struct InputSpec {
  std::string name;      // the input actor's name
  std::string endpoint;  // its data socket
  int64_t window = 4;    // requests this actor keeps in flight to it
  std::string key;       // its CURVE public key (Z85), when the farm speaks CURVE
  // A pool this actor dispatches to itself (CONFIG inputs[i].pool, docs/PROTOCOL.md): its live replicas, each
  // connected like an input with its own window, and how to choose among them. `endpoint` and `key` are then empty,
  // and `window` bounds this actor's requests to the pool as a whole.
  std::vector<InputSpec> replicas;
  std::string strategy;  // round_robin | least_loaded | random; empty: a single actor, not a pool
  int64_t split = 0;     // split shade requests larger than this across replicas (0: never)
  int64_t seed = 0;      // for strategy random
  // Replicas of a pool to connect to at once: the first `subset` of `replicas`; the rest are spares, connected in
  // order as those are lost (CONFIG inputs[i].pool.subset). 0: all.
  int64_t subset = 0;
  // The input takes a shade request's `nrm` and `m` from the scene when it carries `tri` (a built-in LightOp): the
  // asker may leave them out (CONFIG inputs[i].lean). A pool is lean when all its replicas are.
  bool lean = false;
  // Where the input's answer can be other than zero (CONFIG inputs[i].answers_at: the lobes, and L for emission,
  // that end the paths it counts): the runtime asks it only about points whose materials those reach. nullopt: the
  // farm does not know (a plug-in), and every point is asked about.
  std::optional<AnswerEnds> answers;
  // A pool's replica that holds a part of a partitioned scene itself (CONFIG replicas[j].part; partition
  // { colocate = true }): the points that lie in that part go to it. -1: none.
  int64_t part = -1;
  bool is_pool() const { return !strategy.empty(); }
};

// A replica's place in its pool: all_gather answers in replica order.
struct PoolPlace {
  std::string name;  // the pool (its multiplexer's name)
  int64_t index = 0;
  int64_t count = 1;
  // The other replicas (replica order, this one left out) of a pool whose op shares its setup: the replicas send
  // each other their parts directly (op pool_part) instead of through the director. Empty: through the director.
  std::vector<InputSpec> peers;
};

struct ActorConfig {
  Value::Map params;  // the actor's parameters from the script
  SceneSpec scene;
  CameraSpec camera;
  // A job whose first frame changes materials (frames { materials }): its changes over the shipped scene, which the
  // actor makes before it sets up (FrameSpec::materials; later frames' come with PHASE frame). Empty: none.
  Value::Array frame_materials;
  // A job's first frame's number, whose view `camera` is: what shade requests name that view by (frames in flight).
  std::optional<int> frame;
  ImageSpec image;
  std::vector<InputSpec> inputs;  // in script order
  Value::Map runtime;             // how it was started: {cmd, cwd} for lightop.exec actors; informational
  Value::Map debug;               // test knobs: {slowdown = factor} (actors/kinds/slowdown.hpp)
  std::optional<PoolPlace> pool;  // set for a pool's replica
  double heartbeat_timeout = 10.0;
  double request_timeout = 120.0;
  // A partitioned scene (partition { parts = N }): an actor that traces through the parts gets their actors (part
  // order) and boxes; a geometry actor gets its own part's triangles.
  std::vector<InputSpec> geometry;
  std::vector<float> part_boxes;         // 6 per part: lo x y z, hi x y z
  std::vector<uint32_t> part_triangles;  // scene triangle ids, ascending
  // A LightOp that holds a part itself (partition { colocate = true }): which one (its triangles are then in
  // part_triangles), so that its rays in that part are traced in this process. -1: none.
  int64_t local_part = -1;

  Value to_value() const;
  // Every field checked; an error names the field.
  static Result<ActorConfig> from_value(const Value& body);
};

}  // namespace lf
