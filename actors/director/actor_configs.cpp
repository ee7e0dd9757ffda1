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
  for (int in : a.inputs)
    config.inputs.push_back({spec.actors[static_cast<size_t>(in)].name, endpoint_of(in), window,
                             key_of ? key_of(in) : std::string()});
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
