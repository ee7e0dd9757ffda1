#pragma once
// Launchers start actor processes on a host, learn when they exit, and kill them. The director holds one per host
// (Launchers), chosen by the host's `launcher` in the script; `local` (fork/exec here) is the first. A new launcher
// (ssh, slurm) implements Launcher and is named in make_launcher(); nothing else in the director changes.
//
// Every launcher starts a process on this machine for each actor (the actor itself, or the ssh/srun client that
// carries it), so a local pid identifies a launched actor across all launchers.
#include <sys/types.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

struct ExitReport {
  pid_t pid = 0;
  int status = 0;  // as from waitpid
  // "exited with status 3" / "was killed by signal 9 (Killed)"
  std::string describe() const;
};

struct LaunchRequest {
  std::vector<std::string> argv;  // argv[0] is replaced by this lightfarm binary when `self`
  bool self = true;               // run this lightfarm binary; false: run argv[0], looked up on PATH
  std::string cwd;                // working directory of the actor, if set
  // The child's stdin is a pipe this launcher holds open until the child is reaped: it reads EOF the moment the
  // director is gone, whatever killed it (ssh forwards that EOF to the remote actor's lifeline).
  bool hold_stdin = false;
  // Written to the child's stdin first (the farm's keys): never on a command line or in the environment.
  std::string stdin_text;
};

class Launcher {
 public:
  virtual ~Launcher() = default;
  virtual std::string name() const = 0;
  // Gets ready to start actors (an ssh connection and a check of the host); called for every host at once before
  // any actor starts, so hosts connect in parallel. An error names the host.
  virtual Status prepare() { return Ok{}; }
  // Called on the director's own thread once this host is prepared, before the scene is shipped: a launcher whose
  // actors start through one session per host opens it now (a child started from prepare's threads would be
  // killed with its thread: PR_SET_PDEATHSIG follows the thread, not the process).
  virtual Status open_session() { return Ok{}; }
  // Puts `bytes` (a scene, named by its content hash) in the host's cache unless it is there already; returns its
  // path on the host and how many bytes crossed to it (0 when cached).
  struct Shipped {
    std::string path;
    uint64_t bytes_sent = 0;
  };
  virtual Result<Shipped> ship(const std::string& bytes, const std::string& hash) = 0;
  // Starts the actor; an error says why it could not start (missing program, ...).
  virtual Result<pid_t> start(const LaunchRequest& request) = 0;
  // An actor that has exited, if any (never blocks).
  virtual std::optional<ExitReport> reap_one() = 0;
  virtual void kill(pid_t pid, int signal) = 0;
  // The actor's process as its host knows it ("pid 4711", "pid 4711 on h1"), for messages and tables: a remote
  // launcher's pids here are handles (actors/launchers/host_launcher.hpp).
  virtual std::string where(pid_t pid) const { return "pid " + std::to_string(pid); }
  // Its pid on its host (0 while not yet known).
  virtual pid_t host_pid(pid_t pid) const { return pid; }
  // Waits up to `grace` for actors to exit, then SIGTERM, then SIGKILL; reaps them all.
  virtual void stop_all(std::chrono::milliseconds grace) = 0;
  // Ctrl-Z: stops (`stop`) or continues every actor this launcher can pause. Remote actors cannot be (stopping
  // their ssh client or srun would not reach them), so by default nothing happens.
  virtual void pause_all(bool /*stop*/) {}
};

// Where this machine caches shipped scenes: $LIGHTFARM_CACHE, else $XDG_CACHE_HOME/lightfarm, else
// ~/.cache/lightfarm; scenes live in its `scenes/` folder as HASH.lfscene.
std::string local_cache_dir();

// The launcher a host's `launcher` names; an error for one this build does not have.
Result<std::unique_ptr<Launcher>> make_launcher(const HostSpec& host);

// One launcher per host, made on first use.
class Launchers {
 public:
  // Installs `launcher` for `host` (tests give fakes).
  void set(const std::string& host, std::unique_ptr<Launcher> launcher);
  Result<Launcher*> for_host(const HostSpec& host);
  // Makes the launcher of each of `hosts` and prepares them all at once; the first error, if any.
  Status prepare(const std::vector<const HostSpec*>& hosts);
  Result<pid_t> start(const HostSpec& host, const LaunchRequest& request);
  std::optional<ExitReport> reap_one();
  void kill(pid_t pid, int signal);
  // As Launcher::where and host_pid, for any pid a launcher started (also after it exited).
  std::string where(pid_t pid) const;
  pid_t host_pid(pid_t pid) const;
  void stop_all(std::chrono::milliseconds grace);
  void pause_all(bool stop);
  // Whether any launcher is not this machine's (its actors keep running while the director is stopped).
  bool any_remote() const;

 private:
  std::map<std::string, std::unique_ptr<Launcher>> by_host_;
  std::map<pid_t, Launcher*> owner_;
  std::map<pid_t, Launcher*> started_by_;  // every pid ever started, for where() after its exit
};

}  // namespace lf
