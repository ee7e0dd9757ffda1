#pragma once
// The ring service: the director's side of a radiosity ring (the "master processor" of Stürzlinger, Schaufler
// and Volkert, "Load Balancing for a Parallel Radiosity Algorithm", §2.2). Serves
//   ring.shooter (codecs/ring_codec.hpp)  every iteration each node reports its best local shooter and unshot power
//                                         once its own packets are all home; when all have, the service picks the
//                                         global shooter (or declares convergence) and answers them all — which is
//                                         also the termination detection, since a node reports only when every
//                                         packet it owns, lent ones included, is back.
//   ring.result                           at the end, each node's leaf elements; with all in, the service writes
//                                         the PLY and publishes the solution as "radiosity" on the exchange, for
//                                         the `radiosity` LightOp.
// A node reporting the wrong iteration, or a malformed report or result, stops the farm.
//
// Recovery: the nodes' reports carry their elements every checkpoint_every iterations, and the service keeps the
// last complete set. A node lost before the solution is in is restarted (needs_restart); the service opens a new
// epoch at once (reports and results of the old one are dropped unanswered) and, once every restarted node has
// rejoined, sends each node ROLLBACK to the checkpoint (or to the start, when there is none yet). The nodes then
// report that iteration again, and the ring goes on from there exactly as it went before.
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "actors/codecs/ring_codec.hpp"
#include "actors/director/exchange_service.hpp"
#include "actors/director/service.hpp"
#include "core/result.hpp"
#include "farm/farm_spec.hpp"
#include "radiosity/config.hpp"

namespace lf {

class RingService final : public Service {
 public:
  // The key the solution is published under (render/lightops/radiosity.cpp fetches it).
  static constexpr const char* kSolutionKey = "radiosity";

  // Finds the farm's ring nodes; inactive when there are none. The solution goes to `exchange`.
  // `live`: a progress line rewritten in place on the terminal; otherwise log lines now and then.
  RingService(const FarmSpec& spec, ExchangeService& exchange, bool quiet, bool live);
  bool active() const { return !nodes_.empty(); }
  // Plans the ring as the nodes do, to turn their elements back into one mesh. An error names the script line.
  Status prepare(const Scene& scene);

  std::vector<wire::Op> ops() const override { return {wire::Op::ring_shooter, wire::Op::ring_result}; }
  Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) override;
  Status on_lost(const std::string& actor, const std::string& why, Outbox& out) override;
  bool needs_restart(const std::string& actor) const override { return index_of(actor) >= 0 && !solved(); }
  Status on_rejoined(const std::string& actor, Outbox& out) override;
  bool phase_complete(wire::Phase phase) const override { return phase != wire::Phase::setup || !active() || solved(); }

  const std::string& ply_path() const { return config_.ply; }
  bool solved() const { return !solution_.empty(); }
  const std::string& solution() const { return solution_; }
  Value report() const;
  // The unshot share of the power after each iteration so far (the monitor draws it falling).
  const std::vector<double>& unshot_fraction() const { return unshot_fraction_; }  // iterations, seconds, unshot fraction, per-iteration figures, recoveries
  uint32_t epoch() const { return epoch_; }

 private:
  int index_of(const std::string& node) const;
  Status on_shooter(const std::string& node, uint64_t id, const Value& body, Outbox& out);
  Status on_result(const std::string& node, uint64_t id, const Value& body, Outbox& out);

  ExchangeService& exchange_;
  bool quiet_;
  bool live_;
  SourceLoc loc_;
  radiosity::RingConfig config_;
  std::unique_ptr<radiosity::RingPlan> plan_;
  std::vector<std::string> nodes_;  // in node order
  struct Asked {
    uint64_t id = 0;
    ring::ShooterReport report;
  };
  std::map<int, Asked> asked_;
  int64_t iteration_ = -1;  // the iteration the nodes are working on
  std::vector<double> iteration_seconds_;
  std::vector<double> unshot_fraction_;
  std::vector<uint32_t> shooters_;
  double started_ = 0, last_ = 0;
  std::map<int, std::vector<radiosity::Element>> results_;
  uint32_t epoch_ = 0;
  struct Checkpoint {
    int64_t iteration = -1;  // -1: none (the start)
    std::map<int, std::vector<radiosity::Element>> elements;  // per node
    uint64_t bytes = 0;      // their size on the wire
  } checkpoint_;
  uint64_t checkpoints_ = 0, checkpoint_bytes_ = 0;
  std::set<int> restarting_;
  struct Recovery {
    std::string node, why;
    int64_t lost_at = 0;      // the iteration the ring was on
    int64_t resumed_from = -1;  // the checkpoint's iteration
  };
  std::vector<Recovery> recoveries_;
  std::string solution_;
  RGB ambient_;
};

}  // namespace lf
