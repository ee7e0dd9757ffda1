#pragma once
// The exchange: what actors fetch from the director during setup. Serves
//   fetch {key: str} -> {blob: bin}   once something publishes `key` (publish()); ERROR not_found when nothing by
//                                     that name will be
// (A pool's replicas share their setup parts with each other directly: REQUEST pool_part, actors/runtime.)
#include <map>
#include <set>
#include <string>

#include "actors/director/service.hpp"

namespace lf {

class ExchangeService final : public Service {
 public:
  std::vector<wire::Op> ops() const override { return {wire::Op::fetch}; }
  Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) override;

  // `key` will be published: fetches of it wait instead of being refused.
  void expect(const std::string& key);
  // The blob for `key`; waiting fetches are answered now.
  void publish(const std::string& key, std::string blob, Outbox& out);

 private:
  std::set<std::string> expected_;
  std::map<std::string, std::string> published_;
  std::multimap<std::string, std::pair<std::string, uint64_t>> waiting_fetches_;  // key -> (actor, id)
};

}  // namespace lf
