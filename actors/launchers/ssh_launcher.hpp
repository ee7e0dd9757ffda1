#pragma once
// SshLauncher: starts a host's actors with the real OpenSSH client, in batch mode (never a password prompt), over
// one multiplexed connection per host (ControlMaster), so that many actors on a host cost one handshake.
//
// prepare() connects and checks the host within a bounded time: an unreachable host, a refused key or a missing
// remote binary is an error naming the host with ssh's own words. The first start() then opens one more session,
//   ssh HOST exec LIGHTFARM host-launcher
// and every actor of the host is started through it (actors/launchers/host_launcher.hpp): one session per host, not
// one per actor. When the session's stdin reaches EOF (the director is gone, or the session was cut and ssh gave
// up), the host launcher sends its actors SIGTERM and then SIGKILL: a remote actor never outlives its farm.
#include <string>

#include "actors/launchers/host_launcher.hpp"
#include "actors/launchers/local_launcher.hpp"

namespace lf {

class SshLauncher final : public SessionLauncher {
 public:
  explicit SshLauncher(HostSpec host);
  ~SshLauncher() override;

  std::string name() const override { return "ssh"; }
  Status prepare() override { return connect(true); }
  Status open_session() override;
  Result<Shipped> ship(const std::string& bytes, const std::string& hash) override;
  Result<pid_t> start(const LaunchRequest& request) override;
  void stop_all(std::chrono::milliseconds grace) override;

  // The ssh command line up to the remote command (for tests and messages).
  std::vector<std::string> ssh_command() const;

 private:
  Status connect(bool need_lightfarm);
  std::vector<std::string> host_launcher_command() const;
  std::string target() const;

  HostSpec host_;
  std::string lightfarm_;    // the binary to run on the host
  std::string control_dir_;  // holds the control socket
  bool connected_ = false;
  bool checked_lightfarm_ = false;
};

}  // namespace lf
