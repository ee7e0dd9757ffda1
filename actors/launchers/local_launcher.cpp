#include "actors/launchers/local_launcher.hpp"
#include "actors/launchers/slurm_launcher.hpp"
#include "actors/launchers/ssh_launcher.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <thread>

namespace lf {

std::string self_executable() {
  std::error_code ec;
  auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("lightfarm") : p.string();
}

std::string ExitReport::describe() const {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return "was killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  return "stopped (status " + std::to_string(status) + ")";
}

LocalLauncher::LocalLauncher() : exe_(self_executable()) {}

LocalLauncher::~LocalLauncher() { stop_all(std::chrono::milliseconds(0)); }

Result<pid_t> LocalLauncher::start(const LaunchRequest& options) {
  std::vector<std::string> args = options.argv;
  if (options.self) args[0] = exe_;
  std::vector<char*> cargv;
  for (auto& a : args) cargv.push_back(a.data());
  cargv.push_back(nullptr);

  int lifeline[2] = {-1, -1};
  const bool stdin_pipe = options.hold_stdin || !options.stdin_text.empty();
  if (stdin_pipe && ::pipe2(lifeline, O_CLOEXEC) != 0) return make_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t parent = ::getpid();
  // vfork, not fork: the director stays suspended only until the child has called exec, so starting an actor costs
  // no copy of the director's page tables and no wait for the scheduler to run a fresh child on cores the actors
  // already started keep busy (fork + wait for exec took 6-140 ms per actor, growing with each started actor).
  // The child shares our memory until exec, so it only makes system calls, and signals are blocked across it: a
  // handler must never run in the child (posix_spawn does the same).
  sigset_t all, old;
  sigfillset(&all);
  ::pthread_sigmask(SIG_SETMASK, &all, &old);
  volatile int exec_error = 0;
  const pid_t pid = ::vfork();
  if (pid == 0) {
    for (int sig = 1; sig < NSIG; ++sig) {  // the director's handlers are not the actor's
      struct sigaction sa;
      if (sig == SIGKILL || sig == SIGSTOP || ::sigaction(sig, nullptr, &sa) != 0) continue;
      if (sa.sa_handler != SIG_IGN && sa.sa_handler != SIG_DFL) {
        sa.sa_handler = SIG_DFL;
        sa.sa_flags = 0;
        ::sigaction(sig, &sa, nullptr);
      }
    }
    if (lifeline[0] >= 0) ::dup2(lifeline[0], STDIN_FILENO);  // dup2 clears O_CLOEXEC on the copy
    ::setpgid(0, 0);  // a process group of its own: whatever the actor starts is killed with it
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(126);  // the director died between vfork and prctl
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    if (!options.cwd.empty() && ::chdir(options.cwd.c_str()) != 0) {
      exec_error = errno;
      ::_exit(127);
    }
    if (options.self) ::execv(cargv[0], cargv.data());
    else ::execvp(cargv[0], cargv.data());
    exec_error = errno;
    ::_exit(127);
  }
  const int spawn_errno = errno;
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  if (pid < 0) {
    for (int fd : {lifeline[0], lifeline[1]})
      if (fd >= 0) ::close(fd);
    return make_error(std::string("vfork: ") + std::strerror(spawn_errno));
  }
  if (lifeline[0] >= 0) ::close(lifeline[0]);
  if (exec_error != 0) {
    int status;
    ::waitpid(pid, &status, 0);
    if (lifeline[1] >= 0) ::close(lifeline[1]);
    return make_error("cannot run " + args[0] + ": " + std::strerror(exec_error));
  }
  ::setpgid(pid, pid);  // also here: whichever runs first, the group exists before anyone signals it
  children_.insert(pid);
  if (lifeline[1] >= 0) {
    // A few hundred bytes: the pipe holds them, so this never blocks.
    for (size_t done = 0; done < options.stdin_text.size();) {
      const ssize_t w = ::write(lifeline[1], options.stdin_text.data() + done, options.stdin_text.size() - done);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) break;
      done += static_cast<size_t>(w);
    }
    if (options.hold_stdin) held_stdin_[pid] = lifeline[1];
    else ::close(lifeline[1]);
  }
  return pid;
}

void LocalLauncher::forget(pid_t pid) {
  children_.erase(pid);
  if (auto it = held_stdin_.find(pid); it != held_stdin_.end()) {
    ::close(it->second);
    held_stdin_.erase(it);
  }
}

void LocalLauncher::kill(pid_t pid, int signal) {
  if (children_.count(pid)) ::kill(-pid, signal);  // the whole group
}

void LocalLauncher::pause_all(bool stop) {
  for (pid_t pid : children_) ::kill(-pid, stop ? SIGSTOP : SIGCONT);
}

std::optional<ExitReport> LocalLauncher::reap_one() {
  for (pid_t pid : children_) {
    int status = 0;
    pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) {
      forget(pid);
      ::kill(-pid, SIGKILL);  // what it started and left behind goes with it
      return ExitReport{pid, status};
    }
  }
  return std::nullopt;
}

void kill_orphans() {
  // With the director a child subreaper, anything an actor started that left its group (setsid, a double fork)
  // was reparented here: kill and reap every child this process did not launch itself.
  const std::string me = std::to_string(::getpid());
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream status(entry.path() / "status");
    std::string line;
    while (std::getline(status, line))
      if (line.rfind("PPid:", 0) == 0) {
        if (line.substr(line.find_first_not_of(" \t", 5)) == me) ::kill(static_cast<pid_t>(std::stol(name)), SIGKILL);
        break;
      }
  }
  while (::waitpid(-1, nullptr, WNOHANG) > 0) {
  }
}

void LocalLauncher::stop_all(std::chrono::milliseconds grace) {
  using Clock = std::chrono::steady_clock;
  auto wait_until = [&](Clock::time_point deadline) {
    while (!children_.empty()) {
      while (reap_one()) {
      }
      if (children_.empty() || Clock::now() >= deadline) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  };
  wait_until(Clock::now() + grace);
  for (pid_t pid : children_) ::kill(-pid, SIGTERM);
  wait_until(Clock::now() + std::chrono::milliseconds(1500));
  for (pid_t pid : children_) ::kill(-pid, SIGKILL);
  for (pid_t pid : children_) {
    int status;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  children_.clear();
  for (auto& [pid, fd] : held_stdin_) ::close(fd);
  held_stdin_.clear();
}

std::string local_cache_dir() {
  if (const char* c = std::getenv("LIGHTFARM_CACHE"); c && *c) return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/lightfarm";
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : "/tmp") + "/.cache/lightfarm";
}

Result<Launcher::Shipped> LocalLauncher::ship(const std::string& bytes, const std::string& hash) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(local_cache_dir()) / "scenes";
  const fs::path file = dir / (hash + ".lfscene");
  std::error_code ec;
  if (fs::is_regular_file(file, ec) && fs::file_size(file, ec) == bytes.size()) return Shipped{file.string(), 0};
  fs::create_directories(dir, ec);
  if (ec) return make_error("cannot make the scene cache '" + dir.string() + "': " + ec.message());
  // Written under a name of this process and call, then renamed: a farm never reads a half-written scene, and
  // hosts shipped to at once (the director's threads) that share this cache never write one file together.
  static std::atomic<uint64_t> writes{0};
  const fs::path partial = dir / (hash + ".partial." + std::to_string(::getpid()) + "." + std::to_string(writes++));
  {
    std::ofstream out(partial, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) {
      fs::remove(partial, ec);
      return make_error("cannot write the scene cache '" + partial.string() + "'");
    }
  }
  fs::rename(partial, file, ec);
  if (ec) return make_error("cannot write the scene cache '" + file.string() + "': " + ec.message());
  return Shipped{file.string(), 0};  // written here, nothing crossed a network
}

Result<std::unique_ptr<Launcher>> make_launcher(const HostSpec& host) {
  if (host.launcher == "local") return std::unique_ptr<Launcher>(std::make_unique<LocalLauncher>());
  if (host.launcher == "ssh") return std::unique_ptr<Launcher>(std::make_unique<SshLauncher>(host));
  if (host.launcher == "slurm") return std::unique_ptr<Launcher>(std::make_unique<SlurmLauncher>(host));
  return make_error("host '" + host.name + "': launcher '" + host.launcher + "' is not available in this build");
}

void Launchers::set(const std::string& host, std::unique_ptr<Launcher> launcher) { by_host_[host] = std::move(launcher); }

Result<Launcher*> Launchers::for_host(const HostSpec& host) {
  auto it = by_host_.find(host.name);
  if (it != by_host_.end()) return it->second.get();
  auto made = make_launcher(host);
  if (!made) return made.error();
  return (by_host_[host.name] = std::move(*made)).get();
}

Status Launchers::prepare(const std::vector<const HostSpec*>& hosts) {
  std::vector<Launcher*> launchers;
  for (const HostSpec* h : hosts) {
    auto l = for_host(*h);
    if (!l) return l.error();
    if (std::find(launchers.begin(), launchers.end(), *l) == launchers.end()) launchers.push_back(*l);
  }
  std::vector<Status> results(launchers.size(), Status(Ok{}));
  std::vector<std::thread> threads;
  for (size_t i = 0; i < launchers.size(); ++i)
    threads.emplace_back([&, i] { results[i] = launchers[i]->prepare(); });
  for (auto& t : threads) t.join();
  for (const auto& r : results)
    if (!r) return r;
  return Ok{};
}

Result<pid_t> Launchers::start(const HostSpec& host, const LaunchRequest& request) {
  auto launcher = for_host(host);
  if (!launcher) return launcher.error();
  auto pid = (*launcher)->start(request);
  if (pid) owner_[*pid] = started_by_[*pid] = *launcher;
  return pid;
}

std::string Launchers::where(pid_t pid) const {
  auto it = started_by_.find(pid);
  return it != started_by_.end() ? it->second->where(pid) : "pid " + std::to_string(pid);
}

pid_t Launchers::host_pid(pid_t pid) const {
  auto it = started_by_.find(pid);
  return it != started_by_.end() ? it->second->host_pid(pid) : pid;
}

std::optional<ExitReport> Launchers::reap_one() {
  for (auto& [host, launcher] : by_host_)
    if (auto r = launcher->reap_one()) {
      owner_.erase(r->pid);
      return r;
    }
  return std::nullopt;
}

void Launchers::kill(pid_t pid, int signal) {
  if (auto it = owner_.find(pid); it != owner_.end()) it->second->kill(pid, signal);
}

void Launchers::pause_all(bool stop) {
  for (auto& [host, launcher] : by_host_) launcher->pause_all(stop);
}

bool Launchers::any_remote() const {
  for (const auto& [host, launcher] : by_host_)
    if (launcher->name() != "local") return true;
  return false;
}

void Launchers::stop_all(std::chrono::milliseconds grace) {
  for (auto& [host, launcher] : by_host_) launcher->stop_all(grace);
  owner_.clear();
}

}  // namespace lf
