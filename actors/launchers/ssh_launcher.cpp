#include "actors/launchers/ssh_launcher.hpp"
#include "actors/launchers/remote_shell.hpp"
#include "core/private_dir.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <thread>

namespace lf {

SshLauncher::SshLauncher(HostSpec host) : host_(std::move(host)) {
  lightfarm_ = host_.lightfarm.empty() ? self_executable() : host_.lightfarm;
  control_dir_ = make_private_dir("ssh");
}

SshLauncher::~SshLauncher() {
  stop_all(std::chrono::milliseconds(0));
  if (!control_dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(control_dir_, ec);
  }
}

// A host the user's ssh config names (ssh_name) is reached by that name, so its Host block (key, user, proxy)
// applies; else by the address its actors listen on.
std::string SshLauncher::target() const {
  const std::string& where = host_.ssh_name.empty() ? host_.address : host_.ssh_name;
  return host_.user.empty() ? where : host_.user + "@" + where;
}

std::vector<std::string> SshLauncher::ssh_command() const {
  std::vector<std::string> argv{"ssh"};
  if (!host_.ssh_config.empty()) argv.insert(argv.end(), {"-F", host_.ssh_config});
  if (host_.port > 0) argv.insert(argv.end(), {"-p", std::to_string(host_.port)});
  // KexAlgorithms: curve25519 first, ahead of OpenSSH 9's default sntrup761 hybrid, whose key exchange cost the ssh
  // client ~70 ms more CPU per connection here (~0.1 s of a 3-host launch); the others stay allowed. The link
  // carries start commands and one farm's keys (docs/decisions.md).
  for (const char* option : {"BatchMode=yes", "ConnectTimeout=5", "ControlMaster=auto", "ControlPersist=5",
                             "ServerAliveInterval=5", "ServerAliveCountMax=3", "KexAlgorithms=^curve25519-sha256"})
    argv.insert(argv.end(), {"-o", option});
  argv.insert(argv.end(), {"-o", "ControlPath=" + control_dir_ + "/%C", "-T", target()});
  return argv;
}

Status SshLauncher::connect(bool need_lightfarm) {
  if (connected_ && (checked_lightfarm_ || !need_lightfarm)) return Ok{};
  if (control_dir_.empty()) return make_error("host '" + host_.name + "': cannot make a folder for ssh's control socket");
  auto argv = ssh_command();
  argv.push_back(need_lightfarm ? "test -x " + shell_quote(lightfarm_) + " && echo lightfarm-ok" : "echo lightfarm-ok");
  const Captured c = run_captured(argv, 15.0);
  const std::string who = "host '" + host_.name + "' (" + target() + ")";
  if (!c.ran) return make_error(who + ": " + c.output);
  if (c.status == -1) return make_error(who + ": ssh did not connect within 15 s");
  if (WIFEXITED(c.status) && WEXITSTATUS(c.status) == 255)
    return make_error(who + ": ssh failed: " + last_line(c.output));
  if (c.output.find("lightfarm-ok") == std::string::npos) {
    if (need_lightfarm)
      return make_error(who + ": no lightfarm executable at '" + lightfarm_ +
                        "' there (install it, or set host { lightfarm = \"/path/to/lightfarm\" })");
    return make_error(who + ": ssh ran, but the host's shell did not answer: " + last_line(c.output));
  }
  connected_ = true;
  checked_lightfarm_ = checked_lightfarm_ || need_lightfarm;
  return Ok{};
}

std::vector<std::string> SshLauncher::host_launcher_command() const {
  // The huge-page setting this director runs with (cli/main.cpp), given to the host launcher and so to every
  // actor it starts, so that none runs itself a second time to set it: ssh passes no environment.
  std::string command = "exec";
  if (const char* t = std::getenv("GLIBC_TUNABLES"); t && std::strstr(t, "glibc.malloc.hugetlb=1"))
    command += " env GLIBC_TUNABLES=glibc.malloc.hugetlb=1";
  command.append(" ").append(shell_quote(lightfarm_)).append(" host-launcher");
  auto argv = ssh_command();
  argv.push_back(command);
  return argv;
}

Status SshLauncher::open_session() {
  if (auto st = connect(true); !st) return st;
  return begin_session(host_.name, [this] { return host_launcher_command(); });
}

Result<pid_t> SshLauncher::start(const LaunchRequest& request) {
  if (auto st = connect(true); !st) return st.error();
  return start_through(host_.name, [this] { return host_launcher_command(); }, request);
}

Result<Launcher::Shipped> SshLauncher::ship(const std::string& bytes, const std::string& hash) {
  if (auto st = connect(false); !st) return st.error();
  return ship_through(ssh_command(), "host '" + host_.name + "'", bytes, hash);
}

void SshLauncher::stop_all(std::chrono::milliseconds grace) {
  SessionLauncher::stop_all(grace);
  // The master connection outlives its sessions by ControlPersist; end it now (also after a failed check, which
  // may have opened it), so that nothing of the farm stays on the host.
  std::error_code ec;
  if (!control_dir_.empty() && !std::filesystem::is_empty(control_dir_, ec) && !ec) {
    auto argv = ssh_command();
    argv.insert(argv.end() - 2, {"-O", "exit"});  // before -T and the target
    run_captured(argv, 5.0);
  }
  connected_ = false;
  checked_lightfarm_ = false;
}

}  // namespace lf
