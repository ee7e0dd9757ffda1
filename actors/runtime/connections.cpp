#include "actors/runtime/connections.hpp"

#include <algorithm>

namespace lf {
namespace {

std::string host_of(const std::string& endpoint) {
  const size_t start = endpoint.find("://"), colon = endpoint.rfind(':');
  return start == std::string::npos || colon <= start ? endpoint : endpoint.substr(start + 3, colon - start - 3);
}

// A replica is on this host when it is reached over IPC, or at the address this actor listens on itself.
bool same_host(const std::string& endpoint, const std::string& own_bind) {
  return endpoint.rfind("ipc://", 0) == 0 || endpoint.rfind("inproc://", 0) == 0 || host_of(endpoint) == host_of(own_bind);
}

}  // namespace

Result<size_t> Connections::add(Group group, const InputSpec& in) {
  auto client = connect_(in.name, in.endpoint, in.key, static_cast<size_t>(in.window));
  if (!client) return client.error();
  rows_.push_back(Row{in.name, static_cast<size_t>(in.window), group, std::move(*client)});
  by_group_[static_cast<size_t>(group)].push_back(rows_.size() - 1);
  changed_ = true;
  return rows_.size() - 1;
}

Status Connections::connect_config(const ActorConfig& config, const std::string& own_bind) {
  own_bind_ = own_bind;
  for (const auto& in : config.inputs) {
    LightingInput input;
    input.name = in.name;
    input.answers = in.answers;
    if (!in.is_pool()) {
      auto row = add(Group::lighting, in);
      if (!row) return row.error();
      input.row = *row;
      input.lean = in.lean;
    } else {
      input.lean = std::all_of(in.replicas.begin(), in.replicas.end(), [](const InputSpec& r) { return r.lean; });
      // A partitioned pool's points must reach the replica holding their part: it connects to all.
      const bool parts = std::any_of(in.replicas.begin(), in.replicas.end(), [](const InputSpec& r) { return r.part >= 0; });
      const size_t subset = in.subset > 0 && !parts ? static_cast<size_t>(in.subset) : in.replicas.size();
      std::vector<PoolClient::Replica> replicas;
      for (const auto& replica : in.replicas) {
        if (replicas.size() >= subset) {
          input.spares.push_back(replica);
          continue;
        }
        auto row = add(Group::lighting, replica);
        if (!row) return row.error();
        replicas.push_back({replica.name, rows_[*row].client.get(), !same_host(replica.endpoint, own_bind_), replica.part});
        input.holds_parts = input.holds_parts || replica.part >= 0;
      }
      const PoolOptions options =
          pool_options(in.strategy, in.split, in.replicas.front().window, in.seed, static_cast<size_t>(in.window));
      input.pool = std::make_unique<PoolClient>(in.name, std::move(replicas), options);
    }
    lighting_.push_back(std::move(input));
  }
  for (const auto& in : config.geometry)
    if (auto row = add(Group::geometry, in); !row) return row.error();
  if (config.pool)
    for (const auto& in : config.pool->peers)
      if (auto row = add(Group::pool_peer, in); !row) return row.error();
  return Ok{};
}

Connections::LightingInput* Connections::replica_lost(const std::string& name) {
  for (auto& in : lighting_) {
    if (!in.pool) continue;
    auto spare = std::find_if(in.spares.begin(), in.spares.end(), [&](const InputSpec& s) { return s.name == name; });
    if (spare != in.spares.end()) {
      in.spares.erase(spare);
      return &in;
    }
    if (!in.pool->lost(name)) continue;
    while (!in.spares.empty()) {
      InputSpec next = std::move(in.spares.front());
      in.spares.pop_front();
      auto row = add(Group::lighting, next);
      if (!row) continue;  // an endpoint that cannot be connected: the next spare
      in.pool->add({next.name, rows_[*row].client.get(), !same_host(next.endpoint, own_bind_), next.part});
      break;
    }
    return &in;
  }
  return nullptr;
}

Result<bool> Connections::reconnect(const std::string& name, const std::string& endpoint, const std::string& key) {
  auto row = std::find_if(rows_.begin(), rows_.end(), [&](const Row& r) { return r.name == name; });
  if (row == rows_.end()) return false;
  auto client = connect_(name, endpoint, key, row->window);
  if (!client) return client.error();
  row->client = std::move(*client);
  changed_ = true;
  return true;
}

}  // namespace lf
