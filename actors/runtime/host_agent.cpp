#include "actors/runtime/host_agent.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/signalfd.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>
#include <vector>

#include "actors/runtime/runtime.hpp"
#include "core/log.hpp"
#include "render/scene/loaded_scene.hpp"

namespace lf {

namespace {

constexpr char kMagic[4] = {'L', 'F', 'A', '1'};
constexpr int kPassedFds = 5;  // stdin, stdout, stderr, lifeline (read end), status pipe (write end)

sockaddr_un abstract_address(const std::string& name, socklen_t& length) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  const size_t n = std::min(name.size(), sizeof a.sun_path - 1);
  std::memcpy(a.sun_path + 1, name.data(), n);  // sun_path[0] == 0: the abstract namespace, nothing on disk
  length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + n);
  return a;
}

bool write_all(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t w = ::send(fd, p, size, MSG_NOSIGNAL);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    size -= static_cast<size_t>(w);
  }
  return true;
}

// Reads exactly `size` bytes; false on EOF or error.
bool read_all(int fd, void* data, size_t size) {
  char* p = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t r = ::read(fd, p, size);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    size -= static_cast<size_t>(r);
  }
  return true;
}

int threads_of_this_process() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "Threads:") {
      int n = 0;
      status >> n;
      return n;
    }
    status.ignore(1 << 16, '\n');
  }
  return -1;
}

// One stub's request, as received.
struct Request {
  pid_t stub = 0, stub_group = 0;
  std::vector<std::string> argv;
  int fds[kPassedFds] = {-1, -1, -1, -1, -1};
  void close_fds() {
    for (int& fd : fds)
      if (fd >= 0) ::close(std::exchange(fd, -1));
  }
};

// Receives a request on a freshly accepted connection (the stub sends it at once; a second is plenty).
bool receive_request(int conn, Request& r) {
  timeval timeout{1, 0};
  ::setsockopt(conn, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<char> buffer(64 * 1024);
  iovec io{buffer.data(), buffer.size()};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(int) * kPassedFds)];
  msghdr msg{};
  msg.msg_iov = &io;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  ssize_t n;
  do {
    n = ::recvmsg(conn, &msg, MSG_CMSG_CLOEXEC);
  } while (n < 0 && errno == EINTR);
  if (n <= 0) return false;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c))
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
      const size_t count = (c->cmsg_len - CMSG_LEN(0)) / sizeof(int);
      for (size_t i = 0; i < count; ++i) {
        int fd;
        std::memcpy(&fd, CMSG_DATA(c) + i * sizeof(int), sizeof fd);
        if (i < kPassedFds) r.fds[i] = fd;
        else ::close(fd);
      }
    }
  const bool all_fds = r.fds[kPassedFds - 1] >= 0;
  if (!all_fds || (msg.msg_flags & (MSG_TRUNC | MSG_CTRUNC)) || n < 12 || std::memcmp(buffer.data(), kMagic, 4) != 0)
    return false;
  uint32_t stub, group;
  std::memcpy(&stub, buffer.data() + 4, 4);
  std::memcpy(&group, buffer.data() + 8, 4);
  r.stub = static_cast<pid_t>(stub);
  r.stub_group = static_cast<pid_t>(group);
  for (size_t at = 12; at < static_cast<size_t>(n);) {
    const void* end = std::memchr(buffer.data() + at, '\0', static_cast<size_t>(n) - at);
    if (!end) return false;
    const size_t len = static_cast<const char*>(end) - (buffer.data() + at);
    r.argv.emplace_back(buffer.data() + at, len);
    at += len + 1;
  }
  return r.argv.size() >= 2 && r.argv[1] == "actor";
}

// In the forked child: becomes the actor the stub stands in for. Never returns.
[[noreturn]] void become_actor(Request& r, const std::vector<int>& agent_fds,
                               const std::function<int(int, char**)>& actor_main) {
  for (int fd : agent_fds) ::close(fd);
  for (int target = 0; target < 3; ++target) ::dup2(r.fds[target], target);  // dup2 clears CLOEXEC on the copy
  for (int i = 0; i < 3; ++i) ::close(r.fds[i]);
  const int lifeline = r.fds[3], status = r.fds[4];
  // In the stub's process group where the session allows (a local farm): the director signals and pauses the
  // group it launched. Across ssh the stub lives in another session; the lifeline covers that.
  if (::setpgid(0, r.stub_group) != 0) ::setpgid(0, 0);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGCHLD, SIGPIPE}) ::sigaction(sig, &dfl, nullptr);
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  count_start_from(r.stub);
  // Named after the actor in ps and /proc/PID/comm (its command line is still the agent's).
  for (size_t i = 0; i + 1 < r.argv.size(); ++i)
    if (r.argv[i] == "--name") ::prctl(PR_SET_NAME, r.argv[i + 1].substr(0, 15).c_str());
  // The stub gone (killed, even by SIGKILL) is this actor gone: a thread waits for the lifeline's EOF.
  std::thread([lifeline] {
    sigset_t all;
    sigfillset(&all);
    ::pthread_sigmask(SIG_BLOCK, &all, nullptr);
    char c;
    for (;;) {
      const ssize_t n = ::read(lifeline, &c, 1);
      if (n == 0 || (n < 0 && errno != EINTR)) break;
    }
    ::kill(::getpid(), SIGKILL);
  }).detach();
  std::vector<char*> args;
  for (auto& a : r.argv) args.push_back(a.data());
  args.push_back(nullptr);
  int code = 1;
  try {
    code = actor_main(static_cast<int>(r.argv.size()), args.data());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "lightfarm: error: out of memory\n");
  }
  std::fflush(nullptr);
  const int32_t c32 = code;
  ssize_t ignored = ::write(status, &c32, sizeof c32);
  (void)ignored;
  // _exit: the agent's static objects (its scene, Embree's device) belong to the agent, not to this actor.
  ::_exit(code);
}

}  // namespace

int run_host_agent(const HostAgentOptions& options, const std::function<int(int, char**)>& actor_main) {
  set_log_name("host-agent");
  install_stop_signals();
  const int listener = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  socklen_t length;
  const sockaddr_un address = abstract_address(options.socket, length);
  if (listener < 0 || ::bind(listener, reinterpret_cast<const sockaddr*>(&address), length) != 0 ||
      ::listen(listener, 128) != 0) {
    log_error("host agent: cannot listen on '@" + options.socket + "': " + std::strerror(errno));
    return 1;
  }
  // Listening first: stubs that come while the scene loads wait in the backlog rather than give up.
  bool ready = false;
  if (auto st = preload_shipped_scene(options.scene, options.hash); !st) {
    log_warn("host agent: " + st.error().message + "; its actors load the scene themselves");
  } else if (const int threads = threads_of_this_process(); threads != 1) {
    // fork copies only the calling thread: a helper thread's locks would stay locked in every actor.
    log_warn("host agent: " + std::to_string(threads) + " threads after loading the scene; its actors load the scene themselves");
  } else {
    ready = true;
  }
  std::map<pid_t, int> waiting;  // actor pid -> its stub's connection, for the exit status
  const uid_t me = ::getuid();
  // An actor's exit wakes the loop at once (its stub waits for the status).
  sigset_t child_exits;
  sigemptyset(&child_exits);
  sigaddset(&child_exits, SIGCHLD);
  ::sigprocmask(SIG_BLOCK, &child_exits, nullptr);
  const int exits = ::signalfd(-1, &child_exits, SFD_CLOEXEC | SFD_NONBLOCK);
  // Each actor that has exited: its wait status to its stub.
  auto report_exits = [&] {
    for (int status = 0;;) {
      const pid_t done = ::waitpid(-1, &status, WNOHANG);
      if (done <= 0) break;
      if (auto it = waiting.find(done); it != waiting.end()) {
        const int32_t s32 = status;
        write_all(it->second, &s32, sizeof s32);
        ::close(it->second);
        waiting.erase(it);
      }
    }
  };
  // Waits up to a second for the listener (if any) or an actor's exit; reports exits; true when a stub is waiting.
  auto await_events = [&](int listening) {
    pollfd p[2] = {{exits, POLLIN, 0}, {listening, POLLIN, 0}};
    const int n = ::poll(p, listening >= 0 ? 2 : 1, 1000);
    signalfd_siginfo info;
    while (::read(exits, &info, sizeof info) > 0) {
    }
    report_exits();
    return n > 0 && listening >= 0 && (p[1].revents & POLLIN);
  };
  int answered = 0;  // actors forked, or told to run themselves
  while (!stop_requested() && !(options.actors > 0 && answered >= options.actors && waiting.empty())) {
    if (!await_events(listener)) continue;
    const int conn = ::accept4(listener, nullptr, nullptr, SOCK_CLOEXEC);
    if (conn < 0) continue;
    ucred peer{};
    socklen_t peer_length = sizeof peer;
    Request r;
    if (::getsockopt(conn, SOL_SOCKET, SO_PEERCRED, &peer, &peer_length) != 0 || peer.uid != me ||
        !receive_request(conn, r)) {
      r.close_fds();
      ::close(conn);
      continue;
    }
    // "n": the stand-in runs its actor itself; it still counts as one of those expected.
    auto refuse = [&] {
      write_all(conn, "n", 1);
      r.close_fds();
      ::close(conn);
      ++answered;
    };
    if (!ready) {
      refuse();
      continue;
    }
    std::vector<int> agent_fds{listener, conn, exits};
    for (const auto& [pid, fd] : waiting) agent_fds.push_back(fd);
    const pid_t child = ::fork();
    if (child == 0) become_actor(r, agent_fds, actor_main);
    if (child < 0) {
      refuse();
      continue;
    }
    r.close_fds();
    char reply[5] = {'y'};
    const int32_t c32 = child;
    std::memcpy(reply + 1, &c32, 4);
    write_all(conn, reply, sizeof reply);
    waiting[child] = conn;
    ++answered;
  }
  // Done, or asked to end: no more actors, and the agent leaves after those it forked (under Slurm its job step
  // ends with it and takes every process it started along).
  ::close(listener);
  while (!waiting.empty()) await_events(-1);
  if (exits >= 0) ::close(exits);
  return 0;
}

namespace {
volatile sig_atomic_t g_forward_to = 0;
void forward_signal(int sig) {
  if (g_forward_to > 0) ::kill(g_forward_to, sig);
}
}  // namespace

std::optional<int> run_through_agent(const std::string& socket, const std::vector<std::string>& argv) {
  socklen_t length;
  const sockaddr_un address = abstract_address(socket, length);
  const int conn = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (conn < 0) return std::nullopt;
  // The agent was started just before this actor; give it a moment to listen.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (::connect(conn, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    if ((errno != ECONNREFUSED && errno != ENOENT && errno != EINTR && errno != EAGAIN) ||
        std::chrono::steady_clock::now() > deadline) {
      ::close(conn);
      return std::nullopt;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  int lifeline[2], status[2];
  if (::pipe2(lifeline, O_CLOEXEC) != 0) {
    ::close(conn);
    return std::nullopt;
  }
  if (::pipe2(status, O_CLOEXEC) != 0) {
    ::close(conn);
    ::close(lifeline[0]);
    ::close(lifeline[1]);
    return std::nullopt;
  }
  std::string payload(kMagic, 4);
  const uint32_t me = static_cast<uint32_t>(::getpid()), group = static_cast<uint32_t>(::getpgrp());
  payload.append(reinterpret_cast<const char*>(&me), 4);
  payload.append(reinterpret_cast<const char*>(&group), 4);
  for (const auto& a : argv) payload.append(a.c_str(), a.size() + 1);
  const int fds[kPassedFds] = {STDIN_FILENO, STDOUT_FILENO, STDERR_FILENO, lifeline[0], status[1]};
  iovec io{payload.data(), payload.size()};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof fds)] = {};
  msghdr msg{};
  msg.msg_iov = &io;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_RIGHTS;
  c->cmsg_len = CMSG_LEN(sizeof fds);
  std::memcpy(CMSG_DATA(c), fds, sizeof fds);
  ssize_t sent;
  do {
    sent = ::sendmsg(conn, &msg, MSG_NOSIGNAL);
  } while (sent < 0 && errno == EINTR);
  ::close(lifeline[0]);
  ::close(status[1]);
  char reply[5];
  auto give_up = [&] {
    ::close(conn);
    ::close(lifeline[1]);
    ::close(status[0]);
    return std::nullopt;
  };
  if (sent != static_cast<ssize_t>(payload.size())) return give_up();
  if (!read_all(conn, reply, 1) || reply[0] != 'y' || !read_all(conn, reply + 1, 4)) return give_up();
  int32_t child;
  std::memcpy(&child, reply + 1, 4);
  // From here on this process stands in for the actor: signals go on to it, its end is this process's end.
  g_forward_to = child;
  struct sigaction sa {};
  sa.sa_handler = forward_signal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) ::sigaction(sig, &sa, nullptr);
  std::optional<int32_t> code, wait_status;
  bool agent_there = true, child_there = true;
  // The agent's wait status is exact (a signal too); the child's own code comes first only when the agent is gone.
  while (!wait_status && (agent_there || child_there)) {
    pollfd p[2] = {{agent_there ? conn : -1, POLLIN, 0}, {child_there ? status[0] : -1, POLLIN, 0}};
    if (::poll(p, 2, -1) < 0) continue;  // EINTR: a forwarded signal
    if (p[0].revents) {
      int32_t s;
      if (read_all(conn, &s, sizeof s)) wait_status = s;
      else agent_there = false;
    }
    if (p[1].revents) {
      int32_t s;
      if (read_all(status[0], &s, sizeof s)) code = s;
      child_there = false;
      if (!agent_there) break;
    }
    if (!child_there && agent_there && !wait_status) {
      // The actor is gone; the agent, if it still runs, is about to say how.
      pollfd q{conn, POLLIN, 0};
      if (::poll(&q, 1, 2000) > 0) {
        int32_t s;
        if (read_all(conn, &s, sizeof s)) wait_status = s;
      }
      break;
    }
  }
  ::close(conn);
  ::close(lifeline[1]);
  ::close(status[0]);
  if (wait_status) return *wait_status;
  if (code) return (*code & 0xff) << 8;  // as waitpid reports an exit with that code
  return SIGKILL;                        // gone without a word, and nobody left to say how: killed
}

}  // namespace lf
