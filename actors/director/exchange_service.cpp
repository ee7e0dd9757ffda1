#include "actors/director/exchange_service.hpp"

namespace lf {

ExchangeService::ExchangeService(Pools pools) : pools_(std::move(pools)) {}

const std::string* ExchangeService::pool_of(const std::string& actor, size_t* index) const {
  for (const auto& [pool, replicas] : pools_)
    for (size_t i = 0; i < replicas.size(); ++i)
      if (replicas[i] == actor) {
        *index = i;
        return &pool;
      }
  return nullptr;
}

void ExchangeService::expect(const std::string& key) { expected_.insert(key); }

void ExchangeService::publish(const std::string& key, std::string blob, Outbox& out) {
  expected_.insert(key);
  const std::string& stored = published_[key] = std::move(blob);
  auto [first, last] = waiting_fetches_.equal_range(key);
  for (auto it = first; it != last; ++it) out.reply(it->second.first, it->second.second, map_of("blob", Bytes{stored}));
  waiting_fetches_.erase(first, last);
}

Status ExchangeService::on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) {
  if (op == wire::Op::fetch) {
    const Value* key = body.find("key");
    const std::string name = key && key->is_string() ? key->as_string() : std::string("?");
    if (!expected_.count(name)) {
      out.refuse(actor, id, ErrorCode::not_found,
                 "this farm publishes no '" + name + "' (a radiosity LightOp needs radiosity { ... } in the script)");
      return Ok{};
    }
    if (auto it = published_.find(name); it != published_.end()) {
      out.reply(actor, id, map_of("blob", Bytes{it->second}));
    } else {
      waiting_fetches_.emplace(name, std::make_pair(actor, id));
    }
    return Ok{};
  }
  Value* part = body.find("part");
  if (!part || !part->is_bytes()) {
    out.refuse(actor, id, ErrorCode::bad_request, "all_gather needs a part");
    return Ok{};
  }
  // Shares can be tens of MB (a photon map): they are moved, never copied, on their way through here. A replica
  // that says `keep` holds its own part already and gets nil in its place: for two replicas, half the bytes back.
  Value mine = std::move(*part);
  const Value* keep = body.find("keep");
  const bool keeps = keep && keep->is_bool() && keep->as_bool();
  size_t at = 0;
  const std::string* pool = pool_of(actor, &at);
  if (!pool) {  // not in a pool: its own part is everything
    Value::Array only;
    only.push_back(keeps ? Value() : std::move(mine));
    out.reply(actor, id, map_of("parts", std::move(only)));
    return Ok{};
  }
  const auto& replicas = pools_.at(*pool);
  for (const auto& r : replicas)
    if (lost_.count(r))
      return make_error("replica '" + r + "' of '" + *pool +
                        "' was lost before the pool shared its setup; its share cannot be redone");
  Gather& g = gathers_[*pool];
  const size_t n = replicas.size();
  g.parts.resize(n);
  g.askers.resize(n);
  g.keeps.resize(n);
  g.parts[at] = std::move(mine);
  g.askers[at] = id;
  g.keeps[at] = keeps;
  for (const auto& p : g.parts)
    if (p.is_nil()) return Ok{};
  Gather done = std::move(g);
  gathers_.erase(*pool);
  // Part i goes to every replica but a keeping i; its last reader takes it, the others a copy.
  std::vector<size_t> last_reader(n, 0);
  for (size_t r = 0; r < n; ++r)
    for (size_t i = 0; i < n; ++i)
      if (i != r || !done.keeps[r]) last_reader[i] = r;
  for (size_t r = 0; r < n; ++r) {
    Value::Array parts(n);
    for (size_t i = 0; i < n; ++i) {
      if (i == r && done.keeps[r]) continue;  // nil: the asker's own
      parts[i] = last_reader[i] == r ? std::move(done.parts[i]) : done.parts[i];
    }
    out.reply(replicas[r], done.askers[r], map_of("parts", std::move(parts)));
  }
  return Ok{};
}

Status ExchangeService::on_lost(const std::string& actor, const std::string& why, Outbox&) {
  lost_.insert(actor);
  size_t at = 0;
  const std::string* pool = pool_of(actor, &at);
  if (pool && gathers_.count(*pool))
    return make_error("replica '" + actor + "' " + why + " while '" + *pool +
                      "' was sharing its setup; its share cannot be redone");
  return Ok{};
}

}  // namespace lf
