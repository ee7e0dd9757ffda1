#include "actors/director/exchange_service.hpp"

namespace lf {

void ExchangeService::expect(const std::string& key) { expected_.insert(key); }

void ExchangeService::publish(const std::string& key, std::string blob, Outbox& out) {
  expected_.insert(key);
  const std::string& stored = published_[key] = std::move(blob);
  auto [first, last] = waiting_fetches_.equal_range(key);
  for (auto it = first; it != last; ++it) out.reply(it->second.first, it->second.second, map_of("blob", Bytes{stored}));
  waiting_fetches_.erase(first, last);
}

Status ExchangeService::on_request(const std::string& actor, wire::Op, uint64_t id, Value body, Outbox& out) {
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

}  // namespace lf
