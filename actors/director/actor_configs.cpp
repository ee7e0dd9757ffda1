#include "actors/director/actor_configs.hpp"

#include <algorithm>

#include "farm/kind_params.hpp"

namespace lf {

ActorConfig config_for(const FarmSpec& spec, int actor, const std::function<std::string(int)>& endpoint_of,
                       const std::function<std::string(int)>& key_of) {
  const ActorSpec& a = spec.actors[static_cast<size_t>(actor)];
  ActorConfig config;
  config.params = a.params;
  config.scene = spec.scene;
  config.camera = spec.camera;
  config.image = spec.image;
  const int64_t window = input_window(a);
  // A built-in LightOp holds the farm's scene: asked about points on its triangles, it needs no normals or
  // materials (CONFIG inputs[i].lean). Plug-ins and multiplexer processes get whole requests.
  auto lean = [&](int i) {
    const ActorSpec& input = spec.actors[static_cast<size_t>(i)];
    return input.loads_scene() && !input.is_renderer() && !input.is_multiplexer();
  };
  for (int in : a.inputs) {
    const ActorSpec& input = spec.actors[static_cast<size_t>(in)];
    if (!input.dispatched_by_clients) {
      config.inputs.push_back({input.name, endpoint_of(in), window, key_of ? key_of(in) : std::string()});
      config.inputs.back().lean = lean(in);
      continue;
    }
    // A pool this actor dispatches to itself: its replicas, each with the pool's window.
    const MultiplexerParams pool = MultiplexerParams::read(ParamTable(input.params, input.name));
    InputSpec spec_in{input.name, "", window, ""};
    spec_in.strategy = pool.strategy;
    spec_in.split = pool.split;
    spec_in.seed = pool.seed;
    for (int r : input.inputs) {
      spec_in.replicas.push_back({spec.actors[static_cast<size_t>(r)].name, endpoint_of(r), pool.window,
                                  key_of ? key_of(r) : std::string()});
      spec_in.replicas.back().lean = lean(r);
    }
    config.inputs.push_back(std::move(spec_in));
  }
  config.runtime = a.runtime;
  config.debug = a.debug;
  config.heartbeat_timeout = spec.heartbeat_timeout;
  config.request_timeout = spec.request_timeout;
  if (const int pool = spec.pool_of(actor); pool >= 0) {
    const auto& replicas = spec.actors[static_cast<size_t>(pool)].inputs;
    const auto at = std::find(replicas.begin(), replicas.end(), actor) - replicas.begin();
    config.pool = PoolPlace{spec.actors[static_cast<size_t>(pool)].name, at, static_cast<int64_t>(replicas.size())};
  }
  return config;
}

}  // namespace lf
