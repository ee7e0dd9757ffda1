#pragma once
// SlurmLauncher: inside an allocation (salloc, sbatch), starts a host's actors through one job step on that node,
// `srun --overlap ... lightfarm host-launcher` (actors/launchers/host_launcher.hpp), which starts each actor as the
// director asks on the step's stdin and stops them all when that stdin ends. The first use checks the allocation and
// that lightfarm is on the node.
#include <string>

#include "actors/launchers/host_launcher.hpp"
#include "actors/launchers/local_launcher.hpp"

namespace lf {

class SlurmLauncher final : public SessionLauncher {
 public:
  explicit SlurmLauncher(HostSpec host);
  ~SlurmLauncher() override { stop_all(std::chrono::milliseconds(0)); }

  std::string name() const override { return "slurm"; }
  Status prepare() override;
  Result<Shipped> ship(const std::string& bytes, const std::string& hash) override;
  Result<pid_t> start(const LaunchRequest& request) override;

 private:
  std::vector<std::string> srun() const;

  HostSpec host_;
  std::string lightfarm_;
  std::string job_;
  bool prepared_ = false;
};

}  // namespace lf
