#pragma once
// Every connection an actor asks on, in one table: its lighting inputs (a single actor's connection, or the
// replicas of a pool it dispatches to itself), a partitioned scene's geometry actors, and the other replicas of its
// own pool when they share their setup. Each row holds the peer's name, the window CONFIG gave it, its group and
// its RequestClient; PEER_MOVED replaces a row's client. Sockets are made by the Connector the runtime gives
// (with the actor's name and CURVE keys), so the table is tested with any.
#include <deque>
#include <functional>
#include <utility>
#include <memory>
#include <string>
#include <vector>

#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/pool_client.hpp"
#include "transport/client.hpp"

namespace lf {

class Connections {
 public:
  enum class Group { lighting, geometry, pool_peer };
  struct Row {
    std::string name;
    size_t window = 4;
    Group group = Group::lighting;
    std::unique_ptr<wire::RequestClient> client;
  };
  // An input of the lighting network as the actor sees it.
  struct LightingInput {
    std::string name;
    size_t row = SIZE_MAX;             // a single actor's connection
    std::unique_ptr<PoolClient> pool;  // or a pool dispatched here
    bool lean = false;                 // it takes normals and materials from the scene
    bool holds_parts = false;          // some replica holds a scene part itself
    std::optional<AnswerEnds> answers;  // where its answer can be other than zero (CONFIG inputs[i].answers_at)
    // A pool's replicas beyond its subset (CONFIG pool.subset), in CONFIG's order: one is connected in place of
    // each replica of the subset that is lost.
    std::deque<InputSpec> spares;
  };
  using Connector = std::function<Result<std::unique_ptr<wire::RequestClient>>(
      const std::string& name, const std::string& endpoint, const std::string& key, size_t window)>;

  explicit Connections(Connector connect) : connect_(std::move(connect)) {}

  // Connects everything CONFIG names. `own_bind`: where this actor listens, to tell which replicas share its host
  // (their traffic is not counted as crossing the network by the pool's scheduler).
  Status connect_config(const ActorConfig& config, const std::string& own_bind);
  // PEER_MOVED: the row named `name` connects to `endpoint` now (its old socket closes, and with it whatever was
  // outstanding there). False for a name that is not in the table (nothing changes); an error for a connection
  // that cannot be made.
  Result<bool> reconnect(const std::string& name, const std::string& endpoint, const std::string& key);
  // PEER_DOWN: replica `name` of a pool input is gone. Its pool sends its work to the others, and the input's next
  // spare is connected in its place (a spare that is lost is only forgotten). The input it belonged to, or nullptr
  // when it is no pool's replica.
  LightingInput* replica_lost(const std::string& name);

  std::vector<LightingInput>& lighting() { return lighting_; }
  const std::vector<LightingInput>& lighting() const { return lighting_; }
  std::vector<Row>& rows() { return rows_; }
  // The k-th row of a group, in CONFIG's order.
  size_t count(Group group) const { return by_group_[static_cast<size_t>(group)].size(); }
  Row& in_group(Group group, size_t k) { return rows_[by_group_[static_cast<size_t>(group)].at(k)]; }
  // Whether rows were added or replaced since the last call (the poller is then made again).
  bool take_changed() { return std::exchange(changed_, false); }

 private:
  Result<size_t> add(Group group, const InputSpec& in);

  Connector connect_;
  std::vector<Row> rows_;
  std::vector<size_t> by_group_[3];  // rows of each Group, in order
  std::vector<LightingInput> lighting_;
  bool changed_ = false;
  std::string own_bind_;  // where this actor listens (replicas there are not remote)
};

}  // namespace lf
