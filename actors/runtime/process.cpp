#include "actors/runtime/process.hpp"

#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <fstream>
#include <sstream>

namespace lf {

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;
volatile std::sig_atomic_t g_resumed = 0;
volatile std::sig_atomic_t g_suspend_requested = 0;
void on_signal(int sig) { g_stop_signal = sig; }
void on_continue(int) { g_resumed = 1; }
void on_terminal_stop(int) { g_suspend_requested = 1; }
}  // namespace

void install_stop_signals() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking poll returns EINTR and the loop sees the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);
  sa.sa_handler = on_continue;
  sigaction(SIGCONT, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

void install_suspend_signal() {
  struct sigaction sa {};
  sa.sa_handler = on_terminal_stop;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTSTP, &sa, nullptr);
}

bool stop_requested() { return g_stop_signal != 0; }
bool take_resumed() { return g_resumed != 0 && (g_resumed = 0, true); }
bool take_suspend_request() { return g_suspend_requested != 0 && (g_suspend_requested = 0, true); }

// A farm of 100,000 actors is 4.1 MB of public keys.
constexpr size_t kMaxKeysLineBytes = 8u << 20;

Result<wire::FarmKeys> read_farm_keys_from_stdin() {
  // Read in blocks: the line holds every actor's public key (41 bytes each), and a byte at a time that was a
  // system call per byte in every actor, quadratic in the farm's size (256 actors: 2.7 million reads). Launchers
  // write nothing after the line (the pipe then only carries EOF), so nothing is lost by reading past it.
  std::string line;
  char block[16384];
  while (line.find('\n') == std::string::npos && line.size() < kMaxKeysLineBytes) {
    const ssize_t n = ::read(STDIN_FILENO, block, sizeof block);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    line.append(block, static_cast<size_t>(n));
  }
  if (const size_t end = line.find('\n'); end != std::string::npos) line.resize(end);
  else if (line.size() >= kMaxKeysLineBytes) return make_error("--curve: the keys line on standard input is too long");
  if (line.empty()) return make_error("--curve: no keys on standard input");
  return wire::FarmKeys::from_line(line);
}
int stop_signal() { return g_stop_signal; }

namespace {
pid_t g_started_as = 0;  // 0: this process
}  // namespace

void count_start_from(pid_t pid) { g_started_as = pid; }

// Seconds since this process (or the one count_start_from named) was started (its start time in /proc, 10 ms
// resolution); 0 where unknown.
double seconds_since_process_start() {
  std::ifstream in(g_started_as > 0 ? "/proc/" + std::to_string(g_started_as) + "/stat" : std::string("/proc/self/stat"));
  std::string stat((std::istreambuf_iterator<char>(in)), {});
  const auto close = stat.rfind(')');  // the command name may hold spaces; fields resume after it
  if (close == std::string::npos) return 0;
  std::istringstream fields(stat.substr(close + 2));
  std::string field;
  for (int i = 3; i < 22 && fields >> field; ++i) {
  }
  unsigned long long start_ticks = 0;
  if (!(fields >> start_ticks)) return 0;
  timespec now {};
  ::clock_gettime(CLOCK_BOOTTIME, &now);
  return static_cast<double>(now.tv_sec) + now.tv_nsec * 1e-9 -
         static_cast<double>(start_ticks) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// This process's proportional set size: pages shared with other processes (a mapped scene image, libraries)
// count by their share, so the sum over a host's actors is what the farm takes there. 0 where unknown.
uint64_t proportional_set_bytes() {
  std::ifstream in("/proc/self/smaps_rollup");
  std::string key;
  uint64_t kb = 0;
  while (in >> key) {
    if (key == "Pss:" && in >> kb) return kb * 1024;
    in.ignore(1 << 20, '\n');
  }
  return 0;
}

// CPU time of this whole process (every thread: the loop, ZeroMQ's I/O threads, the heartbeat, a LightOp's
// workers), user and system, so that benchmarks can say what a farm burns beside its wall time.
double process_cpu_seconds() {
  struct rusage usage {};
  if (::getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  auto secs = [](const timeval& t) { return static_cast<double>(t.tv_sec) + t.tv_usec * 1e-6; };
  return secs(usage.ru_utime) + secs(usage.ru_stime);
}

}  // namespace lf
