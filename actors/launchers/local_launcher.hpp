#pragma once
// LocalLauncher: fork/exec on this machine. Each child is the leader of its own process group, signalled and killed
// as a group, so whatever an actor starts dies with it; it gets PR_SET_PDEATHSIG=SIGKILL, so even a director killed
// with SIGKILL leaves no actor running. Every child is reaped.
#include <map>
#include <set>

#include "actors/launchers/launcher.hpp"

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
  void pause_all(bool stop) override;
  void stop_all(std::chrono::milliseconds grace) override;

 private:
  void forget(pid_t pid);

  std::string exe_;
  std::set<pid_t> children_;
  std::map<pid_t, int> held_stdin_;  // write ends of held stdin pipes
};

// Kills and reaps every child of this process (a child subreaper) that no launcher started: what actors left
// behind outside their process groups. Call when no launcher has children left.
void kill_orphans();

// The path of the running lightfarm binary.
std::string self_executable();

}  // namespace lf
