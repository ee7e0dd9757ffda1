#include "radiosity/config.hpp"

#include <cmath>

namespace lf::radiosity {

std::string RingConfig::balance_name() const {
  if (static_balance && dynamic_balance) return "static+dynamic";
  if (static_balance) return "static";
  if (dynamic_balance) return "dynamic";
  return "none";
}

RingConfig read_ring_config(const ParamTable& p) {
  RingConfig c;
  c.layout.rings = static_cast<int>(p.get_int("rings", 1, 1, 64));
  c.layout.length = static_cast<int>(p.get_int("ring_length", 1, 1, 64));
  if (c.layout.nodes() > 256) throw ParamError(p.owner() + ": rings x ring_length must be at most 256");
  c.ring.samples_per_packet = static_cast<int>(p.get_int("samples_per_packet", 50, 1, 100000));
  c.ring.max_visits = static_cast<int>(p.get_int("max_visits", 0, 0, 64));
  const int64_t m = p.get_int("shooter_samples", 16, 1, 64);
  const int64_t k = static_cast<int64_t>(std::lround(std::sqrt(static_cast<double>(m))));
  if (k * k != m) throw ParamError(p.owner() + ": shooter_samples must be a square number (1, 4, 9, ..., 64)");
  c.solver.shooter_samples = static_cast<int>(m);
  c.solver.subdivide = static_cast<float>(p.get_float("subdivide", 0.0, 0.0, 1e6));
  c.solver.max_depth = static_cast<int>(p.get_int("max_depth", 2, 0, 8));
  c.solver.converge = p.get_float("converge", 0.01, 0.0, 1.0);
  c.solver.max_iterations = static_cast<int>(p.get_int("max_iterations", 1000, 1, 10000000));
  c.mesh.patch_size = static_cast<float>(p.get_float("patch_size", 0.0, 0.0, 1e30));
  c.mesh.element_size = static_cast<float>(p.get_float("element_size", 0.0, 0.0, 1e30));
  const std::string balance = p.get_string("balance", "static+dynamic", {"none", "static", "dynamic", "static+dynamic"});
  c.static_balance = balance == "static" || balance == "static+dynamic";
  c.dynamic_balance = balance == "dynamic" || balance == "static+dynamic";
  c.ply = p.get_string("ply", "");
  c.checkpoint_every = static_cast<int>(p.get_int("checkpoint_every", c.checkpoint_every, 0, 1000000));
  return c;
}

std::vector<uint32_t> RingPlan::patches_of(int node) const {
  std::vector<uint32_t> mine;
  for (uint32_t p = 0; p < owner.size(); ++p)
    if (owner[p] == node) mine.push_back(p);
  return mine;
}

Result<RingPlan> plan_ring(const Scene& scene, const RingConfig& config) {
  auto mesh = build_mesh(scene, config.mesh);
  if (!mesh) return mesh.error();
  RingPlan plan;
  plan.mesh = std::move(*mesh);
  if (config.static_balance) split_for_balance(plan.mesh, config.layout.nodes());
  plan.owner = assign_patches(plan.mesh, config.layout.nodes(), config.static_balance, config.layout.rings);
  plan.bsp = GlobalBsp::build(plan.mesh, config.layout.length, config.static_balance, plan.owner);
  return plan;
}

}  // namespace lf::radiosity
