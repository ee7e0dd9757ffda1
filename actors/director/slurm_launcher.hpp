#pragma once
// SlurmLauncher: inside an allocation (salloc, sbatch), starts a host's actors as job steps with srun on that node
// (--overlap: many actors share the node's CPUs; one task each), under the same lifeline as ssh actors, with the
// actor's keys on the step's stdin. The first use checks the allocation and that lightfarm is on the node.
#include <string>

#include "actors/director/local_launcher.hpp"

namespace lf {

class SlurmLauncher final : public Launcher {
 public:
  explicit SlurmLauncher(HostSpec host);
  ~SlurmLauncher() override { stop_all(std::chrono::milliseconds(0)); }

  std::string name() const override { return "slurm"; }
  Status prepare() override;
  Result<Shipped> ship(const std::string& bytes, const std::string& hash) override;
  Result<pid_t> start(const LaunchRequest& request) override;
  std::optional<ExitReport> reap_one() override { return steps_.reap_one(); }
  void kill(pid_t pid, int signal) override { steps_.kill(pid, signal); }
  void stop_all(std::chrono::milliseconds grace) override { steps_.stop_all(grace); }

 private:
  std::vector<std::string> srun() const;

  HostSpec host_;
  std::string lightfarm_;
  std::string job_;
  bool prepared_ = false;
  LocalLauncher steps_;  // the srun processes, one per actor
};

}  // namespace lf
