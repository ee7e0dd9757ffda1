#pragma once
// The exchange: what actors share through the director during setup. Serves
//   all_gather {part: bin} -> {parts: [bin, ...]}   every replica of the sender's pool sends its part; once all have,
//                                                    each gets all parts in replica order. An actor outside a pool
//                                                    gets [its own part] at once.
//   fetch      {key: str}  -> {blob: bin}           once something publishes `key` (publish()); ERROR not_found when
//                                                    nothing by that name will be
// A pool replica lost before or while its pool shares cannot have its share redone: the farm stops.
#include <map>
#include <set>
#include <string>
#include <vector>

#include "actors/director/service.hpp"

namespace lf {

class ExchangeService final : public Service {
 public:
  // Pools by name, each with its replicas in replica order.
  using Pools = std::map<std::string, std::vector<std::string>>;
  explicit ExchangeService(Pools pools);
  std::vector<wire::Op> ops() const override { return {wire::Op::all_gather, wire::Op::fetch}; }
  Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) override;
  Status on_lost(const std::string& actor, const std::string& why, Outbox& out) override;

  // `key` will be published: fetches of it wait instead of being refused.
  void expect(const std::string& key);
  // The blob for `key`; waiting fetches are answered now.
  void publish(const std::string& key, std::string blob, Outbox& out);

 private:
  struct Gather {
    std::vector<Value> parts;      // nil until that replica sent its part
    std::vector<uint64_t> askers;  // request ids to answer
    std::vector<bool> keeps;       // whether that replica holds its own part (nil in its answer)
  };
  const std::string* pool_of(const std::string& actor, size_t* index) const;

  Pools pools_;
  std::set<std::string> lost_;
  std::map<std::string, Gather> gathers_;  // by pool
  std::set<std::string> expected_;
  std::map<std::string, std::string> published_;
  std::multimap<std::string, std::pair<std::string, uint64_t>> waiting_fetches_;  // key -> (actor, id)
};

}  // namespace lf
