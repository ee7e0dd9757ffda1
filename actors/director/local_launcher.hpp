#pragma once
// LocalLauncher: fork/exec on this machine. Children stay in the director's process group (Ctrl-C on a terminal
// reaches them all) and get PR_SET_PDEATHSIG=SIGKILL, so even a director killed with SIGKILL leaves nothing
// running. Every child is reaped.
#include <map>
#include <set>

#include "actors/director/launcher.hpp"

namespace lf {

class LocalLauncher final : public Launcher {
 public:
  LocalLauncher();
  ~LocalLauncher() override;  // stops whatever is still running
  LocalLauncher(const LocalLauncher&) = delete;
  LocalLauncher& operator=(const LocalLauncher&) = delete;

  std::string name() const override { return "local"; }
  Result<Shipped> ship(const std::string& bytes, const std::string& hash) override;
  Result<pid_t> start(const LaunchRequest& request) override;
  std::optional<ExitReport> reap_one() override;
  void kill(pid_t pid, int signal) override;
  void stop_all(std::chrono::milliseconds grace) override;

 private:
  void forget(pid_t pid);

  std::string exe_;
  std::set<pid_t> children_;
  std::map<pid_t, int> held_stdin_;  // write ends of held stdin pipes
};

// The path of the running lightfarm binary.
std::string self_executable();

}  // namespace lf
