#pragma once
// One session per remote host: the director starts `lightfarm host-launcher` on the host once (over ssh, or as one
// Slurm job step), and asks it to start each of that host's actors, instead of opening an ssh session or a job step
// per actor (here a multiplexed ssh session took ~30 ms, ten one after another 0.30 s, before the shell, lifeline
// and `env` each actor also ran on its host; 48 actors started as job steps took 3.3 s, as one step per node 0.42 s).
//
// The line protocol on the session's stdin and stdout (docs/PROTOCOL.md, "On another host"): one message per line,
// fields separated by TAB, with \\, \t and \n escaped as two characters.
//   director -> host:  start ID CWD STDIN_TEXT HOLD SELF ARGV...   (HOLD, SELF: 0 or 1)
//                      kill ID SIGNAL
//   host -> director:  started ID PID  |  failed ID MESSAGE  |  exited ID WAIT_STATUS
// On the host the actors are started as LocalLauncher starts them here (own process group, killed with the host
// launcher, SIGKILL on its death); their stdout goes to the host launcher's stderr. EOF on its stdin (the director
// is gone, or the session was cut and ended) stops every actor: SIGTERM, then SIGKILL, as the per-actor lifeline did.
//
// On the director's side, HostSession gives each actor a handle that stands for a pid in the director (unique in
// this process and above any real pid), so the Supervisor and Launchers treat remote actors as they treat local ones.
#include <sys/types.h>

#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "actors/launchers/launcher.hpp"

namespace lf {

// The host side: runs until EOF on stdin (or SIGTERM/SIGINT/SIGHUP) and every actor it started is gone, or, once
// it has started one, until the director has said nothing (not even its once-a-second "ping") for
// kHostSilenceSeconds: across a cut link no EOF comes until the link returns (sshd has no keepalive of its own).
int run_host_launcher();
inline constexpr double kHostSilenceSeconds = 15;  // as long as the director's ssh waits (ServerAlive 5 s x 3)

// The director side of one host's session.
class HostSession {
 public:
  // `transport`: the command that runs `lightfarm host-launcher` on the host (ssh ... or srun ...); `host`: its name,
  // for messages.
  HostSession(std::string host, std::vector<std::string> transport);
  ~HostSession();
  HostSession(const HostSession&) = delete;
  HostSession& operator=(const HostSession&) = delete;

  // Starts the session on first use; then asks the host launcher to start the actor. The handle is returned at once:
  // a start that fails on the host arrives as an exit (status 127) and a warning with the host's words.
  Result<pid_t> start(const LaunchRequest& request);
  // Starts the session now (start() does on first use).
  Status begin() { return open(); }
  std::optional<ExitReport> reap_one();
  // SIGKILL counts the actor as gone at once: across a cut network the kill may never arrive, and a killed actor
  // must never be waited on (its late answers are dropped anyway).
  void kill(pid_t handle, int signal);
  // Waits up to `grace` for the actors to exit, then ends the session (the host stops what is left) and waits for
  // the transport to exit, killing it after a few seconds.
  void stop_all(std::chrono::milliseconds grace);
  bool running() const { return pid_ > 0; }
  // The actor's pid on the host, once the host said it (0 before).
  pid_t host_pid(pid_t handle) const {
    auto it = host_pids_.find(handle);
    return it == host_pids_.end() ? 0 : it->second;
  }
  std::string where(pid_t handle) const {
    const pid_t pid = host_pid(handle);
    return (pid ? "pid " + std::to_string(pid) + " " : std::string()) + "on " + host_;
  }

 private:
  Status open();
  void send_line(const std::vector<std::string>& fields);
  void read_events();
  void transport_ended(int status);

  std::string host_;
  std::vector<std::string> transport_;
  pid_t pid_ = 0;  // the transport process (ssh or srun)
  int to_host_ = -1, from_host_ = -1;
  std::string partial_;                 // an unfinished line from the host
  std::map<pid_t, int64_t> live_;        // handle -> the host's id for it
  std::map<int64_t, pid_t> handle_of_;   // the host's id -> handle
  std::deque<ExitReport> exits_;
  std::map<pid_t, pid_t> host_pids_;     // handle -> pid on the host (kept after the exit, for messages)
  int64_t next_id_ = 1;
  std::chrono::steady_clock::time_point last_ping_{};
};

// A launcher whose actors start through one HostSession per host (ssh, slurm): the per-actor calls go to the
// session; a subclass says how to reach the host.
class SessionLauncher : public Launcher {
 public:
  std::optional<ExitReport> reap_one() override { return session_ ? session_->reap_one() : std::nullopt; }
  void kill(pid_t pid, int signal) override {
    if (session_) session_->kill(pid, signal);
  }
  std::string where(pid_t pid) const override { return session_ ? session_->where(pid) : Launcher::where(pid); }
  pid_t host_pid(pid_t pid) const override { return session_ ? session_->host_pid(pid) : 0; }
  void stop_all(std::chrono::milliseconds grace) override {
    if (session_) session_->stop_all(grace);
  }

 protected:
  // Starts the actor through the host's session, opened first (on `host`, with the command `transport()` gives)
  // if it is not yet.
  Result<pid_t> start_through(const std::string& host, const std::function<std::vector<std::string>()>& transport,
                              const LaunchRequest& request) {
    if (!session_) session_ = std::make_unique<HostSession>(host, transport());
    return session_->start(request);
  }
  // Opens the host's session before any actor starts (as soon as the host answered): from then on it keeps ssh's
  // master connection in use, so that shipping the scene and starting actors never find it gone after
  // ControlPersist's 5 idle seconds and connect again.
  Status begin_session(const std::string& host, const std::function<std::vector<std::string>()>& transport) {
    if (!session_) session_ = std::make_unique<HostSession>(host, transport());
    if (auto st = session_->begin(); !st) return make_error("host '" + host + "': cannot start its session: " + st.error().message);
    return Ok{};
  }

 private:
  std::unique_ptr<HostSession> session_;
};

// Line protocol helpers (exposed for tests).
std::string host_line(const std::vector<std::string>& fields);
std::vector<std::string> split_host_line(const std::string& line);

}  // namespace lf
