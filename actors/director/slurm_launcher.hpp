#pragma once
// SlurmLauncher: inside an allocation (salloc, sbatch), starts a host's actors through one job step on that node,
// `srun --overlap ... lightfarm host-launcher` (actors/director/host_launcher.hpp), which starts each actor as the
// director asks on the step's stdin and stops them all when that stdin ends. The first use checks the allocation and
// that lightfarm is on the node.
#include <string>

#include <memory>

#include "actors/director/host_launcher.hpp"
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
  std::optional<ExitReport> reap_one() override { return session_ ? session_->reap_one() : std::nullopt; }
  void kill(pid_t pid, int signal) override {
    if (session_) session_->kill(pid, signal);
  }
  std::string where(pid_t pid) const override { return session_ ? session_->where(pid) : Launcher::where(pid); }
  pid_t host_pid(pid_t pid) const override { return session_ ? session_->host_pid(pid) : 0; }
  void stop_all(std::chrono::milliseconds grace) override;

 private:
  std::vector<std::string> srun() const;

  HostSpec host_;
  std::string lightfarm_;
  std::string job_;
  bool prepared_ = false;
  std::unique_ptr<HostSession> session_;  // the job step this node's actors are started through
};

}  // namespace lf
