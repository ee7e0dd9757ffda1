#pragma once
// The hosts of the Slurm allocation this process runs in (salloc, sbatch): one per node, in the allocation's
// order, launcher "slurm", address the node's NodeAddr. Asks Slurm itself (`scontrol show hostnames`, `scontrol
// show node`), so a compressed node list like gpu[1-4,7] expands exactly as Slurm means it.
#include <vector>

#include "core/result.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

Result<std::vector<HostSpec>> slurm_allocation_hosts();

}  // namespace lf
