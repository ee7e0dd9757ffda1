#pragma once
// Launchers start actor processes. LocalLauncher: fork/exec on this machine. Children stay in the director's
// process group (Ctrl-C on a terminal reaches them all) and get PR_SET_PDEATHSIG=SIGKILL, so even a director
// killed with SIGKILL leaves nothing running. Every child is reaped.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/result.hpp"

namespace lf {

struct ExitReport {
  pid_t pid = 0;
  int status = 0;  // as from waitpid
  // "exited with status 3" / "was killed by signal 9 (Killed)"
  std::string describe() const;
};

class LocalLauncher {
 public:
  LocalLauncher();
  ~LocalLauncher();  // stops whatever is still running
  LocalLauncher(const LocalLauncher&) = delete;
  LocalLauncher& operator=(const LocalLauncher&) = delete;

  struct Options {
    bool self = true;   // run this lightfarm binary (argv[0] ignored); false: run argv[0], looked up on PATH
    std::string cwd;    // working directory of the child, if set
  };
  Result<pid_t> launch(const std::vector<std::string>& argv, const Options& options);
  Result<pid_t> launch(const std::vector<std::string>& argv) { return launch(argv, Options{}); }
  // A child that has exited, if any (never blocks).
  std::optional<ExitReport> reap_one();
  // Waits up to `grace` for children to exit, then SIGTERM, then SIGKILL; reaps them all.
  void stop_all(std::chrono::milliseconds grace);

 private:
  std::string exe_;
  std::set<pid_t> children_;
};

// The path of the running lightfarm binary.
std::string self_executable();

}  // namespace lf
