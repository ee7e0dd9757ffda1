#include "actors/director/ssh_launcher.hpp"

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

namespace {

using Clock = std::chrono::steady_clock;

// Hands the actor the first line of stdin (its keys, or an empty line), starts it in the background and watches
// the rest of stdin: EOF means the director is gone. (A background job of a non-interactive shell reads /dev/null
// unless told otherwise, hence fd 3.)
constexpr const char* kLifeline =
    "cd \"$0\" || exit 127; exec 3<&0; IFS= read -r k <&3; printf '%s\\n' \"$k\" | \"$@\" 3<&- & p=$!; "
    "(cat <&3 >/dev/null 2>&1; kill -TERM $p 2>/dev/null && { sleep 2; kill -KILL $p 2>/dev/null; }) "
    ">/dev/null 2>&1 & exec 3<&-; wait $p";

struct Captured {
  int status = -1;  // as from waitpid; -1: timed out (the child was killed)
  std::string output;
};

// Runs argv with stdout and stderr captured, `input` on its stdin (else /dev/null), for at most `seconds`.
Captured run_captured(const std::vector<std::string>& argv, double seconds, const std::string* input = nullptr) {
  Captured c;
  int out[2], in[2] = {-1, -1};
  if (::pipe2(out, O_CLOEXEC) != 0) return c;
  if (input && ::pipe2(in, O_CLOEXEC) != 0) return c;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out[1], STDOUT_FILENO);
    ::dup2(out[1], STDERR_FILENO);
    if (input) {
      ::dup2(in[0], STDIN_FILENO);
    } else {
      const int null = ::open("/dev/null", O_RDONLY);
      if (null >= 0) ::dup2(null, STDIN_FILENO);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  ::close(out[1]);
  std::thread writer;
  if (input) {
    ::close(in[0]);
    // A writer of its own, so that a large scene and the child's output never wait on each other.
    writer = std::thread([fd = in[1], input] {
      for (size_t done = 0; done < input->size();) {
        const ssize_t w = ::write(fd, input->data() + done, input->size() - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) break;
        done += static_cast<size_t>(w);
      }
      ::close(fd);
    });
  }
  ::fcntl(out[0], F_SETFL, O_NONBLOCK);
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  char buf[4096];
  bool exited = false;
  while (true) {
    ssize_t n;
    while ((n = ::read(out[0], buf, sizeof buf)) > 0) c.output.append(buf, static_cast<size_t>(n));
    if (!exited && ::waitpid(pid, &c.status, WNOHANG) == pid) exited = true;
    // A ControlPersist master inherits the pipe, so EOF may never come: the child's exit is enough.
    if (exited) break;
    if (Clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
      c.status = -1;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ssize_t n;
  while ((n = ::read(out[0], buf, sizeof buf)) > 0) c.output.append(buf, static_cast<size_t>(n));
  ::close(out[0]);
  if (writer.joinable()) writer.join();  // the child is gone: its end of the pipe is closed, the write returned
  return c;
}

std::string last_line(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const auto nl = text.rfind('\n');
  return nl == std::string::npos ? text : text.substr(nl + 1);
}

}  // namespace

std::string shell_quote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

SshLauncher::SshLauncher(HostSpec host) : host_(std::move(host)) {
  lightfarm_ = host_.lightfarm.empty() ? self_executable() : host_.lightfarm;
  char dir[] = "/tmp/lightfarm-ssh-XXXXXX";
  if (::mkdtemp(dir)) control_dir_ = dir;
}

SshLauncher::~SshLauncher() {
  stop_all(std::chrono::milliseconds(0));
  if (!control_dir_.empty()) {
    std::error_code ec;
    std::filesystem::remove_all(control_dir_, ec);
  }
}

std::string SshLauncher::target() const { return host_.user.empty() ? host_.address : host_.user + "@" + host_.address; }

std::vector<std::string> SshLauncher::ssh_command() const {
  std::vector<std::string> argv{"ssh"};
  if (!host_.ssh_config.empty()) argv.insert(argv.end(), {"-F", host_.ssh_config});
  if (host_.port > 0) argv.insert(argv.end(), {"-p", std::to_string(host_.port)});
  for (const char* option : {"BatchMode=yes", "ConnectTimeout=5", "ControlMaster=auto", "ControlPersist=10",
                             "ServerAliveInterval=5", "ServerAliveCountMax=3"})
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

Result<pid_t> SshLauncher::start(const LaunchRequest& request) {
  if (auto st = connect(request.self); !st) return st.error();
  std::vector<std::string> remote = request.argv;
  if (request.self) remote[0] = lightfarm_;
  std::string command = "sh -c " + shell_quote(kLifeline) + " " + shell_quote(request.cwd.empty() ? "." : request.cwd);
  for (const auto& a : remote) command += " " + shell_quote(a);
  LaunchRequest client;
  client.argv = ssh_command();
  client.argv.push_back(command);
  client.self = false;
  client.hold_stdin = true;
  client.stdin_text = request.stdin_text.empty() ? "\n" : request.stdin_text;  // the lifeline reads one line first
  return clients_.start(client);
}

Result<Launcher::Shipped> SshLauncher::ship(const std::string& bytes, const std::string& hash) {
  if (auto st = connect(false); !st) return st.error();
  // The host's cache, by the same rule as this machine's (local_cache_dir), in the host's own environment.
  const std::string where = "d=\"${LIGHTFARM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/lightfarm}/scenes\"; f=\"$d/" +
                            hash + ".lfscene\"; ";
  const std::string who = "host '" + host_.name + "'";
  auto argv = ssh_command();
  argv.push_back(where + "if [ -f \"$f\" ] && [ \"$(wc -c < \"$f\")\" -eq " + std::to_string(bytes.size()) +
                 " ]; then echo \"have $f\"; else echo \"need $f\"; fi");
  const Captured check = run_captured(argv, 15.0);
  const auto have = check.output.find("have ");
  if (have != std::string::npos) return Shipped{last_line(check.output.substr(have + 5)), 0};
  if (check.output.find("need ") == std::string::npos)
    return make_error(who + ": cannot look into its scene cache: " + last_line(check.output));
  argv.back() = where + "mkdir -p \"$d\" && cat > \"$f.partial.$$\" && mv -f \"$f.partial.$$\" \"$f\" && echo \"got $f\"";
  const Captured sent = run_captured(argv, 600.0, &bytes);
  const auto got = sent.output.find("got ");
  if (got == std::string::npos) return make_error(who + ": cannot ship the scene: " + last_line(sent.output));
  return Shipped{last_line(sent.output.substr(got + 4)), bytes.size()};
}

void SshLauncher::stop_all(std::chrono::milliseconds grace) {
  clients_.stop_all(grace);
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
