#pragma once
// SshLauncher: starts a host's actors with the real OpenSSH client, in batch mode (never a password prompt), over
// one multiplexed connection per host (ControlMaster), so that many actors on a host cost one handshake.
//
// The first start() connects and checks the host within a bounded time: an unreachable host, a refused key or a
// missing remote binary is an error naming the host with ssh's own words. Each actor then runs as
//   ssh HOST sh -c '<lifeline>' CWD PROGRAM ARGS...
// where the lifeline starts the actor and, when the ssh channel's stdin reaches EOF (the director is gone, or
// killed that ssh client), sends it SIGTERM and after 2 s SIGKILL: a remote actor never outlives its farm. The ssh
// client's stdin is a pipe the director holds (LaunchRequest::hold_stdin).
#include <string>

#include "actors/director/local_launcher.hpp"

namespace lf {

class SshLauncher final : public Launcher {
 public:
  explicit SshLauncher(HostSpec host);
  ~SshLauncher() override;

  std::string name() const override { return "ssh"; }
  Status prepare() override { return connect(true); }
  Result<Shipped> ship(const std::string& bytes, const std::string& hash) override;
  Result<pid_t> start(const LaunchRequest& request) override;
  std::optional<ExitReport> reap_one() override { return clients_.reap_one(); }
  void kill(pid_t pid, int signal) override { clients_.kill(pid, signal); }
  void stop_all(std::chrono::milliseconds grace) override;

  // The ssh command line up to the remote command (for tests and messages).
  std::vector<std::string> ssh_command() const;

 private:
  Status connect(bool need_lightfarm);
  std::string target() const;

  HostSpec host_;
  std::string lightfarm_;    // the binary to run on the host
  std::string control_dir_;  // holds the control socket
  LocalLauncher clients_;    // the ssh client processes, one per actor
  bool connected_ = false;
  bool checked_lightfarm_ = false;
};

}  // namespace lf
