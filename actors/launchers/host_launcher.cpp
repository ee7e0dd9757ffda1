#include "actors/launchers/host_launcher.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <thread>

#include "actors/launchers/local_launcher.hpp"
#include "actors/runtime/process.hpp"
#include "core/log.hpp"

namespace lf {

std::string host_line(const std::vector<std::string>& fields) {
  std::string out;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i) out += '\t';
    for (char c : fields[i]) {
      if (c == '\\') out += "\\\\";
      else if (c == '\t') out += "\\t";
      else if (c == '\n') out += "\\n";
      else out += c;
    }
  }
  return out + '\n';
}

std::vector<std::string> split_host_line(const std::string& line) {
  std::vector<std::string> fields(1);
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '\t') {
      fields.emplace_back();
    } else if (c == '\\' && i + 1 < line.size()) {
      const char e = line[++i];
      fields.back() += e == 't' ? '\t' : e == 'n' ? '\n' : e;
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

namespace {

bool write_all(int fd, const std::string& text) {
  for (size_t done = 0; done < text.size();) {
    const ssize_t w = ::write(fd, text.data() + done, text.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0 && errno == EAGAIN) {
      pollfd p{fd, POLLOUT, 0};
      ::poll(&p, 1, 100);
      continue;
    }
    if (w <= 0) return false;
    done += static_cast<size_t>(w);
  }
  return true;
}

// Complete lines from `fd` (non-blocking) appended to `lines`; false at EOF or a read error.
bool read_lines(int fd, std::string& partial, std::vector<std::string>& lines) {
  char buf[65536];
  while (true) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) break;
    if (n <= 0) return false;
    partial.append(buf, static_cast<size_t>(n));
  }
  for (size_t nl; (nl = partial.find('\n')) != std::string::npos;) {
    lines.push_back(partial.substr(0, nl));
    partial.erase(0, nl + 1);
  }
  return true;
}

std::optional<int64_t> number(const std::string& s) {
  if (s.empty() || s.size() > 18 || s.find_first_not_of("-0123456789") != std::string::npos) return std::nullopt;
  return std::stoll(s);
}

// Handles stand for pids in the director: unique in this process, and above any pid Linux hands out (2^22).
std::atomic<pid_t> g_next_handle{pid_t{1} << 30};

}  // namespace

int run_host_launcher() {
  // The events go to the stdout this process was given; what its actors print goes to its stderr instead.
  const int events = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 3);
  if (events < 0) return 2;
  ::dup2(STDERR_FILENO, STDOUT_FILENO);
  std::signal(SIGPIPE, SIG_IGN);
  install_stop_signals();
  ::fcntl(STDIN_FILENO, F_SETFL, ::fcntl(STDIN_FILENO, F_GETFL) | O_NONBLOCK);
  set_log_name("host-launcher");

  LocalLauncher launcher;
  std::map<pid_t, std::string> id_of;  // actor pid -> the director's id for it
  std::map<std::string, pid_t> pid_of;
  std::string partial;
  bool director_there = true;
  bool started_any = false;
  auto last_heard = std::chrono::steady_clock::now();
  while (director_there && !stop_requested()) {
    pollfd p{STDIN_FILENO, POLLIN, 0};
    ::poll(&p, 1, 50);
    std::vector<std::string> lines;
    director_there = read_lines(STDIN_FILENO, partial, lines);
    if (!lines.empty()) last_heard = std::chrono::steady_clock::now();
    if (started_any && std::chrono::steady_clock::now() - last_heard > std::chrono::duration<double>(kHostSilenceSeconds)) {
      log_warn("the director has said nothing for " + std::to_string(static_cast<int>(kHostSilenceSeconds)) +
               " s (its link may be cut): stopping this host's actors");
      break;
    }
    for (const auto& line : lines) {
      const auto f = split_host_line(line);
      if (f[0] == "ping") continue;  // the director is there
      if (f[0] == "start" && f.size() >= 7) {
        started_any = true;
        LaunchRequest r;
        r.cwd = f[2];
        r.stdin_text = f[3];
        r.hold_stdin = f[4] == "1";
        r.self = f[5] == "1";
        r.argv.assign(f.begin() + 6, f.end());
        auto pid = launcher.start(r);
        if (pid) {
          id_of[*pid] = f[1];
          pid_of[f[1]] = *pid;
          director_there = write_all(events, host_line({"started", f[1], std::to_string(*pid)}));
        } else {
          director_there = write_all(events, host_line({"failed", f[1], pid.error().message}));
        }
      } else if (f[0] == "kill" && f.size() == 3) {
        const auto sig = number(f[2]);
        if (auto it = pid_of.find(f[1]); it != pid_of.end() && sig && *sig > 0 && *sig < NSIG)
          launcher.kill(it->second, static_cast<int>(*sig));
      } else {
        log_warn("ignored a line it does not understand: " + line.substr(0, 80));
      }
    }
    while (auto e = launcher.reap_one()) {
      auto it = id_of.find(e->pid);
      if (it == id_of.end()) continue;
      if (!write_all(events, host_line({"exited", it->second, std::to_string(e->status)}))) director_there = false;
      pid_of.erase(it->second);
      id_of.erase(it);
    }
  }
  // The director is gone (or the session was cut): nothing started here outlives it.
  launcher.stop_all(std::chrono::milliseconds(0));
  return 0;
}

HostSession::HostSession(std::string host, std::vector<std::string> transport)
    : host_(std::move(host)), transport_(std::move(transport)) {}

HostSession::~HostSession() { stop_all(std::chrono::milliseconds(0)); }

Status HostSession::open() {
  if (pid_ > 0) return Ok{};
  int in[2], out[2];
  if (::pipe2(in, O_CLOEXEC) != 0) return make_error(std::string("pipe: ") + std::strerror(errno));
  if (::pipe2(out, O_CLOEXEC) != 0) {
    ::close(in[0]);
    ::close(in[1]);
    return make_error(std::string("pipe: ") + std::strerror(errno));
  }
  std::vector<char*> argv;
  for (auto& a : transport_) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(in[0], STDIN_FILENO);
    ::dup2(out[1], STDOUT_FILENO);
    ::setpgid(0, 0);  // the director's Ctrl-C is the director's to pass on
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(126);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGCHLD, SIGTSTP}) std::signal(sig, SIG_DFL);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(in[0]);
  ::close(out[1]);
  if (pid < 0) {
    ::close(in[1]);
    ::close(out[0]);
    return make_error(std::string("fork: ") + std::strerror(errno));
  }
  ::setpgid(pid, pid);
  ::fcntl(out[0], F_SETFL, ::fcntl(out[0], F_GETFL) | O_NONBLOCK);
  ::fcntl(in[1], F_SETFL, ::fcntl(in[1], F_GETFL) | O_NONBLOCK);
  pid_ = pid;
  to_host_ = in[1];
  from_host_ = out[0];
  return Ok{};
}

// write_all on a pipe whose reader may be gone (ssh exits when a host's network is cut) without the SIGPIPE that
// would end the director: blocked in this thread while writing, and a pending one taken back before unblocking.
bool write_without_sigpipe(int fd, const std::string& text) {
  sigset_t pipe_only, old;
  sigemptyset(&pipe_only);
  sigaddset(&pipe_only, SIGPIPE);
  ::pthread_sigmask(SIG_BLOCK, &pipe_only, &old);
  const bool ok = write_all(fd, text);
  if (!ok) {
    const timespec none{0, 0};
    while (::sigtimedwait(&pipe_only, nullptr, &none) == SIGPIPE) {
    }
  }
  ::pthread_sigmask(SIG_SETMASK, &old, nullptr);
  return ok;
}

void HostSession::send_line(const std::vector<std::string>& fields) {
  if (to_host_ >= 0 && !write_without_sigpipe(to_host_, host_line(fields))) {
    ::close(to_host_);
    to_host_ = -1;  // the session is ending; its end reports the actors
  }
}

Result<pid_t> HostSession::start(const LaunchRequest& request) {
  if (auto st = open(); !st) return make_error("host '" + host_ + "': cannot start its session: " + st.error().message);
  if (to_host_ < 0) return make_error("host '" + host_ + "': its session has ended");
  const int64_t id = next_id_++;
  std::vector<std::string> fields{"start", std::to_string(id), request.cwd.empty() ? "." : request.cwd,
                                  request.stdin_text, request.hold_stdin ? "1" : "0", request.self ? "1" : "0"};
  fields.insert(fields.end(), request.argv.begin(), request.argv.end());
  send_line(fields);
  const pid_t handle = g_next_handle++;
  live_[handle] = id;
  handle_of_[id] = handle;
  return handle;
}

void HostSession::read_events() {
  if (from_host_ < 0) return;
  std::vector<std::string> lines;
  const bool open = read_lines(from_host_, partial_, lines);
  for (const auto& line : lines) {
    const auto f = split_host_line(line);
    const auto id = f.size() >= 2 ? number(f[1]) : std::nullopt;
    auto it = id ? handle_of_.find(*id) : handle_of_.end();
    if (it == handle_of_.end()) continue;  // an actor already counted as gone (SIGKILL), or garbage
    const pid_t handle = it->second;
    if (f[0] == "exited" && f.size() == 3 && number(f[2])) {
      exits_.push_back({handle, static_cast<int>(*number(f[2]))});
    } else if (f[0] == "failed" && f.size() == 3) {
      log_warn("host '" + host_ + "': " + f[2]);
      exits_.push_back({handle, W_EXITCODE(127, 0)});
    } else {
      if (f[0] == "started" && f.size() == 3 && number(f[2])) host_pids_[handle] = static_cast<pid_t>(*number(f[2]));
      continue;
    }
    live_.erase(handle);
    handle_of_.erase(it);
  }
  if (!open) {
    ::close(from_host_);
    from_host_ = -1;
  }
}

void HostSession::transport_ended(int status) {
  pid_ = 0;
  if (to_host_ >= 0) ::close(to_host_);
  to_host_ = -1;
  read_events();  // what it said before it went
  if (from_host_ >= 0) ::close(from_host_);
  from_host_ = -1;
  // Every actor still running there is gone with the session (the host launcher stops them on EOF): as ssh itself
  // would report for a lost connection.
  if (!live_.empty() && host_pids_.empty())
    // Nothing ever started there: most likely a lightfarm on the host that has no host launcher (another build).
    log_error("host '" + host_ + "': its host launcher ended (" + ExitReport{0, status}.describe() +
              ") before it started any actor; is the lightfarm there the same build as this one?");
  else if (!live_.empty())
    log_debug("host '" + host_ + "': its session ended (" + ExitReport{0, status}.describe() + ") with " +
              std::to_string(live_.size()) + " actors on it");
  for (const auto& [handle, id] : live_) exits_.push_back({handle, W_EXITCODE(255, 0)});
  live_.clear();
  handle_of_.clear();
}

std::optional<ExitReport> HostSession::reap_one() {
  // The host launcher stops its actors when the director falls silent; the director's loop calls this many times a
  // second, so a line a second from here says it is there.
  if (to_host_ >= 0 && std::chrono::steady_clock::now() - last_ping_ >= std::chrono::seconds(1)) {
    last_ping_ = std::chrono::steady_clock::now();
    send_line({"ping"});
  }
  if (exits_.empty()) {
    read_events();
    if (pid_ > 0) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) transport_ended(status);
    }
  }
  if (exits_.empty()) return std::nullopt;
  ExitReport r = exits_.front();
  exits_.pop_front();
  return r;
}

void HostSession::kill(pid_t handle, int signal) {
  auto it = live_.find(handle);
  if (it == live_.end()) return;
  send_line({"kill", std::to_string(it->second), std::to_string(signal)});
  if (signal != SIGKILL) return;
  handle_of_.erase(it->second);
  live_.erase(it);
  exits_.push_back({handle, W_EXITCODE(0, SIGKILL)});
}

void HostSession::stop_all(std::chrono::milliseconds grace) {
  using Clock = std::chrono::steady_clock;
  if (pid_ <= 0) return;
  auto settle = [&](Clock::time_point until, bool all_actors) {
    while (pid_ > 0 && Clock::now() < until && (!all_actors || !live_.empty())) {
      while (reap_one()) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  };
  settle(Clock::now() + grace, true);
  for (const auto& [handle, id] : live_) send_line({"kill", std::to_string(id), std::to_string(SIGTERM)});
  // EOF: the host launcher stops what is left (SIGTERM, then SIGKILL after 1.5 s) and leaves.
  if (to_host_ >= 0) ::close(to_host_);
  to_host_ = -1;
  settle(Clock::now() + std::chrono::seconds(4), false);
  if (pid_ > 0) {
    ::kill(-pid_, SIGKILL);
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    transport_ended(status);
  }
  exits_.clear();
}

}  // namespace lf
