#pragma once
// What the director sends each actor in CONFIG, as a plain function of the farm and the actors' endpoints, so that
// what an actor is told (its inputs and their windows, its place in a pool, its debug knobs) is tested without
// processes (actor_configs.test.cpp).
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "actors/director/deployment.hpp"
#include "actors/director/supervisor.hpp"
#include "actors/runtime/actor_config.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

// `endpoint_of(i)`: the data endpoint actor i said in its HELLO; `key_of(i)` (for a CURVE farm): its public key;
// `pool`: the actor's pool (FarmSpec::pools), if known: a farm's every CONFIG looking it up was quadratic;
// `answers`: where each actor's answer can be other than zero (answer_ends), told to its askers; null: not told.
ActorConfig config_for(const FarmSpec& spec, int actor, const std::function<std::string(int)>& endpoint_of,
                       const std::function<std::string(int)>& key_of = {}, std::optional<int> pool = std::nullopt,
                       const std::vector<std::optional<AnswerEnds>>* answers = nullptr);

// CONFIG as the director sends it: config_for() over the actor table (where each actor said it listens, who is
// lost) and the deployment (scene caches, a partitioned scene's parts, CURVE keys).
class ConfigBuilder {
 public:
  using ActorTable = std::map<std::string, ActorRecord>;
  ConfigBuilder(const FarmSpec& spec, const Deployment& deployment)
      : spec_(spec), d_(deployment), pools_(spec.pools()) {}
  // What actor `a` is told; inputs lost before it was configured are left out (they may never have said where
  // they listen).
  ActorConfig build(const ActorRecord& a, const ActorTable& actors) const;
  // A restarted actor listens somewhere new: the PEER_MOVED body for each configured actor that has it as an input.
  std::vector<std::pair<std::string, Value>> peer_moved(const ActorRecord& moved, const ActorTable& actors) const;
  // Where `receiver` reaches `input`, and the key to check it by: inputs on the same host over their IPC socket,
  // without CURVE (the 0700 folder keeps other users out, and a process of the same user could read the keys
  // anyway); only an actor that offers such a socket itself is known to connect to one. Otherwise TCP.
  std::pair<std::string, std::string> endpoint_for(const ActorRecord& receiver, const ActorRecord& input) const;

 private:
  void add_parts(const ActorRecord& a, const ActorTable& actors, ActorConfig& config) const;
  void add_pool_peers(const ActorRecord& a, const ActorTable& actors, ActorConfig& config) const;
  int64_t colocated_part(const std::string& name) const;

  const FarmSpec& spec_;
  const Deployment& d_;
  std::vector<int> pools_;  // each actor's pool (FarmSpec::pools)
};

}  // namespace lf
