#pragma once
// The director's side of a radiosity ring (seed 003 §2.2, the "master processor"): every iteration each node
// sends its best local shooter and unshot power once its own packets are all home; when all have, the director
// picks the global shooter (or declares convergence) and answers them all — which is also the termination
// detection, since a node reports only when every packet it owns, lent ones included, is back. At the end it
// gathers the element radiosities, writes the PLY and keeps the solution for the `radiosity` LightOp.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/farm_spec.hpp"
#include "core/result.hpp"
#include "radiosity/config.hpp"

namespace lf {

class RingCoordinator {
 public:
  struct Reply {
    std::string node;
    uint64_t id;
    Value body;
  };

  // Finds the farm's ring nodes; inactive when there are none.
  // `live`: a progress line rewritten in place on the terminal; otherwise log lines now and then.
  RingCoordinator(const FarmSpec& spec, bool quiet, bool live);
  bool active() const { return !nodes_.empty(); }
  // Plans the ring as the nodes do, to turn their elements back into one mesh. An error names the script line.
  Status prepare(const Scene& scene);

  Result<std::vector<Reply>> on_shooter(const std::string& node, uint64_t id, const Value& body);
  Result<std::vector<Reply>> on_result(const std::string& node, uint64_t id, const Value& body);
  const std::string& ply_path() const { return config_.ply; }
  bool solved() const { return !solution_.empty(); }
  const std::string& solution() const { return solution_; }
  Value report() const;  // iterations, seconds, unshot fraction, per-iteration figures

 private:
  int index_of(const std::string& node) const;

  bool quiet_;
  bool live_;
  SourceLoc loc_;
  radiosity::RingConfig config_;
  std::unique_ptr<radiosity::RingPlan> plan_;
  std::vector<std::string> nodes_;  // in node order
  struct Asked {
    uint64_t id = 0;
    Value body;
  };
  std::map<int, Asked> asked_;
  int64_t iteration_ = -1;  // the iteration the nodes are working on
  std::vector<double> iteration_seconds_;
  std::vector<double> unshot_fraction_;
  std::vector<uint32_t> shooters_;
  double started_ = 0, last_ = 0;
  std::map<int, std::vector<radiosity::Element>> results_;
  std::string solution_;
  RGB ambient_;
};

}  // namespace lf
