#include "actors/director/actor_configs.hpp"

#include <algorithm>

#include "actors/codecs/control_codec.hpp"
#include "farm/builders.hpp"
#include "farm/kind_params.hpp"
#include "farm/light_path_check.hpp"
#include "farm/pool_subset.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf {

ActorConfig config_for(const FarmSpec& spec, int actor, const std::function<std::string(int)>& endpoint_of,
                       const std::function<std::string(int)>& key_of, std::optional<int> pool_index,
                       const std::vector<std::optional<AnswerEnds>>* answers) {
  const ActorSpec& a = spec.actors[static_cast<size_t>(actor)];
  ActorConfig config;
  config.params = a.params;
  config.scene = spec.scene;
  config.camera = spec.camera;
  // Set up as the job's first frame (spec.camera is its camera): with its materials too.
  if (!spec.frames.empty()) config.frame_materials = spec.frames.front().materials, config.frame = spec.frames.front().number;
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
      if (answers) config.inputs.back().answers = (*answers)[static_cast<size_t>(in)];
      continue;
    }
    // A pool this actor dispatches to itself: its replicas, each with the pool's window.
    const MultiplexerParams pool = MultiplexerParams::read(ParamTable(input.params, input.name));
    InputSpec spec_in{input.name, "", window, ""};
    spec_in.strategy = pool.strategy;
    spec_in.split = pool.split;
    spec_in.seed = pool.seed;
    // Its subset first, then its spares (farm/pool_subset.hpp): this actor's place among the pool's clients.
    int64_t clients = 0, client = 0;
    for (const ActorSpec& other : spec.actors)
      if (std::find(other.inputs.begin(), other.inputs.end(), in) != other.inputs.end()) {
        if (&other == &a) client = clients;
        ++clients;
      }
    const auto replicas = static_cast<int64_t>(input.inputs.size());
    const int64_t subset = pool_subset(pool.subset, replicas, clients, window);
    spec_in.subset = subset < replicas ? subset : 0;
    std::vector<int64_t> order = pool_order(replicas, spec_in.subset, client);
    std::vector<bool> near;
    for (int r : input.inputs) near.push_back(spec.actors[static_cast<size_t>(r)].host == a.host);
    spec_in.subset = add_near_replicas(order, spec_in.subset, near);
    for (int64_t j : order) {
      const int r = input.inputs[static_cast<size_t>(j)];
      spec_in.replicas.push_back({spec.actors[static_cast<size_t>(r)].name, endpoint_of(r), pool.window,
                                  key_of ? key_of(r) : std::string()});
      spec_in.replicas.back().lean = lean(r);
    }
    if (answers) spec_in.answers = (*answers)[static_cast<size_t>(in)];
    config.inputs.push_back(std::move(spec_in));
  }
  config.runtime = a.runtime;
  config.debug = a.debug;
  config.heartbeat_timeout = spec.heartbeat_timeout;
  config.request_timeout = spec.request_timeout;
  if (const int pool = pool_index ? *pool_index : spec.pool_of(actor); pool >= 0) {
    const auto& replicas = spec.actors[static_cast<size_t>(pool)].inputs;
    const auto at = std::find(replicas.begin(), replicas.end(), actor) - replicas.begin();
    config.pool = PoolPlace{spec.actors[static_cast<size_t>(pool)].name, at, static_cast<int64_t>(replicas.size())};
  }
  return config;
}

}  // namespace lf

namespace lf {

std::pair<std::string, std::string> ConfigBuilder::endpoint_for(const ActorRecord& receiver,
                                                                const ActorRecord& input) const {
  if (input.spec->host == receiver.spec->host && !receiver.local_endpoint.empty() && !input.local_endpoint.empty())
    return {input.local_endpoint, ""};
  return {input.endpoint, d_.public_key_of(input.name())};
}

// partition { colocate = true }: the part actor `name` holds itself (farm/builders), once the scene is split.
int64_t ConfigBuilder::colocated_part(const std::string& name) const {
  return d_.parts.empty() ? -1 : lf::colocated_part(spec_, spec_.find(name));
}

ActorConfig ConfigBuilder::build(const ActorRecord& a, const ActorTable& actors) const {
  auto name_of = [&](int i) -> const std::string& { return spec_.actors[static_cast<size_t>(i)].name; };
  auto endpoint_of = [&](int i) { return actors.at(name_of(i)).endpoint; };
  std::function<std::string(int)> key_of;
  if (d_.curve()) key_of = [&](int i) { return d_.public_key_of(name_of(i)); };
  ActorConfig config = config_for(spec_, a.index, endpoint_of, key_of, pools_.at(static_cast<size_t>(a.index)),
                                  d_.answers.empty() ? nullptr : &d_.answers);
  std::vector<InputSpec> inputs;
  for (auto& in : config.inputs) {
    if (actors.at(in.name).lost) continue;
    if (!in.is_pool()) {
      std::tie(in.endpoint, in.key) = endpoint_for(a, actors.at(in.name));
    } else {
      std::vector<InputSpec> live;
      for (auto& r : in.replicas) {
        const ActorRecord& replica = actors.at(r.name);
        if (replica.lost) continue;
        r.part = colocated_part(r.name);
        std::tie(r.endpoint, r.key) = endpoint_for(a, replica);
        live.push_back(std::move(r));
      }
      in.replicas = std::move(live);
    }
    inputs.push_back(std::move(in));
  }
  config.inputs = std::move(inputs);
  if (!d_.scene_bytes.empty()) {
    config.scene.cache = d_.scene_paths.at(a.spec->host);
    config.scene.hash = d_.scene_hash;
  }
  if (!d_.parts.empty()) add_parts(a, actors, config);
  add_pool_peers(a, actors, config);
  return config;
}

// A geometry actor holds its part; a renderer traces its camera rays through the parts, and a LightOp its rays
// (those of its ops that can: direct, pathtrace), holding the part colocated with it itself.
void ConfigBuilder::add_parts(const ActorRecord& a, const ActorTable& actors, ActorConfig& config) const {
  if (a.spec->is_geometry()) {
    config.part_triangles = d_.parts.at(static_cast<size_t>(a.spec->params.at("part").as_int())).triangles;
    return;
  }
  if (!a.spec->loads_scene()) return;
  if (config.pool) {
    config.local_part = colocated_part(a.name());
    if (config.local_part >= 0) config.part_triangles = d_.parts.at(static_cast<size_t>(config.local_part)).triangles;
  }
  for (const auto& g : spec_.actors) {
    if (!g.is_geometry()) continue;
    const auto [endpoint, key] = endpoint_for(a, actors.at(g.name));
    config.geometry.push_back({g.name, endpoint, 4, key});
  }
  for (const ScenePart& p : d_.parts)
    config.part_boxes.insert(config.part_boxes.end(),
                             {p.bounds.lo.x, p.bounds.lo.y, p.bounds.lo.z, p.bounds.hi.x, p.bounds.hi.y, p.bounds.hi.z});
}

// Replicas that share their setup send each other their parts directly: a photon map's tens of MB then cross one
// link (IPC on one host) once, instead of going to the director and out again, decoded and re-encoded.
void ConfigBuilder::add_pool_peers(const ActorRecord& a, const ActorTable& actors, ActorConfig& config) const {
  if (!config.pool || config.pool->count <= 1) return;
  const LightOpKind* kind = find_lightop_kind(a.spec->kind);
  if (!kind || !kind->shares_setup_for(a.spec->params)) return;
  for (int r : spec_.actors[static_cast<size_t>(pools_.at(static_cast<size_t>(a.index)))].inputs) {
    const ActorRecord& sibling = actors.at(spec_.actors[static_cast<size_t>(r)].name);
    if (sibling.name() == a.name()) continue;
    const auto [endpoint, key] = endpoint_for(a, sibling);
    config.pool->peers.push_back({sibling.name(), endpoint, 4, key});
  }
}

std::vector<std::pair<std::string, Value>> ConfigBuilder::peer_moved(const ActorRecord& moved,
                                                                     const ActorTable& actors) const {
  std::vector<std::pair<std::string, Value>> told;
  for (const auto& [name, a] : actors) {
    if (a.lost || !a.configured || a.exited || &a == &moved) continue;
    for (int input : a.spec->inputs) {
      if (input != moved.index) continue;
      const auto [endpoint, key] = endpoint_for(a, moved);
      told.emplace_back(name, control::encode_peer_moved({moved.name(), endpoint, key}));
    }
  }
  return told;
}

}  // namespace lf
