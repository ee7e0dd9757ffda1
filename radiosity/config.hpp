#pragma once
// Everything a radiosity ring is configured with, read from the script's `radiosity { ... }` table. The script
// checks it, every node and the director read the same table, and so build the same mesh, BSP and shares.
#include <string>

#include "core/params.hpp"
#include "radiosity/bsp.hpp"
#include "radiosity/ring.hpp"

namespace lf::radiosity {

struct RingConfig {
  RingLayout layout;
  RingSettings ring;
  SolverSettings solver;
  MeshSettings mesh;
  bool static_balance = false;
  bool dynamic_balance = false;
  std::string ply;  // where to write the solution; empty: nowhere
  int checkpoint_every = 10;  // iterations between the nodes' checkpoints at the director; 0: none (a lost node
                              // restarts the solve from the beginning)
  std::string balance_name() const;
};

// Throws ParamError on a bad or unknown parameter (the caller reports unused ones).
RingConfig read_ring_config(const ParamTable& params);

// The ring's shared view of the scene: the mesh (split for static balancing), who computes each patch, and the
// global BSP. Deterministic, so every process that builds it gets the same.
struct RingPlan {
  Mesh mesh;
  std::vector<int> owner;  // node of each patch
  GlobalBsp bsp;
  std::vector<uint32_t> patches_of(int node) const;
};
Result<RingPlan> plan_ring(const Scene& scene, const RingConfig& config);

}  // namespace lf::radiosity
