#pragma once
// Runs the real lightfarm binary as a child process and inspects what it leaves behind. Every run gets a unique
// tag in its environment; actors inherit it, so leftover_processes() finds any process of that farm still alive.
// No test framework here: the chaos soak (bench/) uses it too; tests/farm_harness.hpp adds the fixture.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace lf::test {

namespace fs = std::filesystem;

struct RunResult {
  int status = -1;  // exit status, or 128+signal
  std::string out, err;
  std::string tag;
};

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline std::string unique_tag() {
  static int n = 0;
  return "lftest-" + std::to_string(::getpid()) + "-" + std::to_string(n++);
}

// The process state letter of `pid` from /proc ('T' stopped, 'Z' zombie), '?' when it is gone.
inline char process_state(pid_t pid) {
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const auto close = stat.rfind(')');  // the command name may hold spaces and parentheses
  return close == std::string::npos || close + 2 >= stat.size() ? '?' : stat[close + 2];
}

// PIDs of live (non-zombie) processes whose environment carries LIGHTFARM_TEST_TAG=tag.
inline std::vector<pid_t> leftover_processes(const std::string& tag) {
  std::vector<pid_t> found;
  const std::string needle = "LIGHTFARM_TEST_TAG=" + tag;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string env = read_file(entry.path() / "environ");
    if (env.find(needle + '\0') == std::string::npos && env.find(needle) == std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stoi(name));
    if (process_state(pid) == 'Z') continue;
    found.push_back(pid);
  }
  return found;
}

// Waits up to `seconds` for the farm's processes to disappear; returns what is still there.
inline std::vector<pid_t> wait_no_leftovers(const std::string& tag, double seconds = 3.0) {
  auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  std::vector<pid_t> left;
  do {
    left = leftover_processes(tag);
    if (left.empty()) return left;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (std::chrono::steady_clock::now() < deadline);
  return left;
}

// PIDs of this farm's actor processes named `name` (from their command line).
inline std::vector<pid_t> actor_pids(const std::string& tag, const std::string& name) {
  std::vector<pid_t> out;
  for (pid_t pid : leftover_processes(tag)) {
    std::string cmd = read_file("/proc/" + std::to_string(pid) + "/cmdline");
    if (cmd.find(std::string("--name") + '\0' + name + '\0') != std::string::npos) out.push_back(pid);
  }
  return out;
}

class Farm {
 public:
  // Starts `lightfarm args...` with extra environment entries ("K=V").
  Farm(const std::vector<std::string>& args, const std::vector<std::string>& env_extra = {}) {
    tag_ = unique_tag();
    dir_ = fs::temp_directory_path() / tag_;
    fs::create_directories(dir_);
    std::vector<std::string> argv{LIGHTFARM_BINARY};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<std::string> env;
    for (char** e = environ; *e; ++e) env.emplace_back(*e);
    env.push_back("LIGHTFARM_TEST_TAG=" + tag_);
    env.push_back("LIGHTFARM_CACHE=" + (dir_ / "cache").string());  // shipped scenes: this farm's own cache
    env.insert(env.end(), env_extra.begin(), env_extra.end());
    std::vector<char*> cargv, cenv;
    for (auto& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    for (auto& e : env) cenv.push_back(e.data());
    cenv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, (dir_ / "out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, (dir_ / "err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&pid_, LIGHTFARM_BINARY, &fa, nullptr, cargv.data(), cenv.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Farm() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      int st;
      ::waitpid(pid_, &st, 0);
    }
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  pid_t pid() const { return pid_; }
  const std::string& tag() const { return tag_; }
  std::string err_so_far() const { return read_file(dir_ / "err"); }

  // Waits for the director to exit (killing it after `timeout_s`).
  RunResult wait(double timeout_s = 120) {
    RunResult r;
    r.tag = tag_;
    auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    int st = 0;
    while (true) {
      pid_t w = ::waitpid(pid_, &st, WNOHANG);
      if (w == pid_) break;
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &st, 0);
        r.err = "TIMEOUT\n";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    reaped_ = true;
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    r.out = read_file(dir_ / "out");
    r.err += read_file(dir_ / "err");
    return r;
  }

  // Polls until pred() or timeout; true if pred held.
  static bool eventually(const std::function<bool()>& pred, double seconds) {
    auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < deadline) {
      if (pred()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return pred();
  }

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
  std::string tag_;
  fs::path dir_;
};

inline RunResult run_lightfarm(const std::vector<std::string>& args, const std::vector<std::string>& env = {}) {
  Farm f(args, env);
  return f.wait();
}

}  // namespace lf::test
