#pragma once
// Shared by the benchmarks: run the real lightfarm binary on a script and read back its --stats-json figures.
#include <sched.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <thread>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

#include "core/value.hpp"

namespace bench {

// A benchmark's command line, checked before it starts anything long (some run for an hour): every argument is one
// of `flags`, each followed by its value, or of `switches`, alone. --help (or -h) prints `usage` and exits 0;
// anything else, or a flag without its value, says what is wrong, prints `usage` and exits 2.
inline void check_command_line(int argc, char** argv, const char* usage, std::initializer_list<const char*> flags,
                               std::initializer_list<const char*> switches = {}) {
  auto among = [](const std::string& a, std::initializer_list<const char*> names) {
    return std::any_of(names.begin(), names.end(), [&](const char* n) { return a == n; });
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: %s\n", usage);
      std::exit(0);
    }
    if (among(a, switches)) continue;
    const char* wrong = !among(a, flags) ? "unknown argument" : i + 1 >= argc ? "needs a value" : nullptr;
    if (wrong) {
      std::fprintf(stderr, "%s: '%s' %s\nusage: %s\n", argv[0], a.c_str(), wrong, usage);
      std::exit(2);
    }
    ++i;
  }
}

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The middle value; of an even count, the mean of the two middle ones (not the upper, which made a median of two
// runs their maximum).
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t half = v.size() / 2;
  return v.size() % 2 ? v[half] : 0.5 * (v[half - 1] + v[half]);
}

// Wall seconds `fn` takes.
template <class Fn>
double seconds_of(Fn&& fn) {
  const auto t0 = Clock::now();
  fn();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// min / median / max of repeated runs, as the benches print and write them.
struct Spread {
  double min = 0, median = 0, max = 0;
  lf::Value to_value() const { return lf::Value::Map{{"min", min}, {"median", median}, {"max", max}}; }
};
inline Spread spread(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? Spread{} : Spread{v.front(), bench::median(v), v.back()};
}

// The number after "key": in a JSON text (the director's stats are flat enough for this).
inline double json_number(const std::string& text, const std::string& key) {
  auto pos = text.find("\"" + key + "\"");
  if (pos == std::string::npos) return -1;
  pos = text.find(':', pos);
  return std::strtod(text.c_str() + pos + 1, nullptr);
}

// The object after "key": in a JSON text, braces included (the director's are flat: no object inside).
inline std::string object_of(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\"");
  if (at == std::string::npos) return {};
  const size_t open = text.find('{', at);
  return text.substr(open, text.find('}', open) - open + 1);
}

// A stage's wall seconds from --stats-json: its phases_seconds entry, not phases_director_cpu_seconds' of the same
// name (which comes first in the text); -1 when there is none.
inline double phase_seconds(const std::string& stats, const std::string& stage) {
  return json_number(object_of(stats, "phases_seconds"), stage);
}

// Every number after "key": in a JSON text, in order (one per actor for per-actor figures).
inline std::vector<double> json_numbers(const std::string& text, const std::string& key) {
  std::vector<double> out;
  const std::string quoted = "\"" + key + "\"";
  for (size_t pos = text.find(quoted); pos != std::string::npos; pos = text.find(quoted, pos + 1))
    out.push_back(std::strtod(text.c_str() + text.find(':', pos) + 1, nullptr));
  return out;
}

// The numbers of the array after "key": in a JSON text (e.g. the radiosity ring's "iteration_seconds").
inline std::vector<double> json_array(const std::string& text, const std::string& key) {
  std::vector<double> out;
  size_t at = text.find("\"" + key + "\"");
  if (at == std::string::npos) return out;
  at = text.find('[', at);
  const size_t end = text.find(']', at);
  const char* p = text.c_str() + at + 1;
  while (p < text.c_str() + end) {
    char* next = nullptr;
    const double v = std::strtod(p, &next);
    if (next == p) {
      ++p;
      continue;
    }
    out.push_back(v);
    p = next;
  }
  return out;
}

// Every string after "key": in a JSON text, in order (one per actor for per-actor figures such as "kind").
inline std::vector<std::string> json_strings(const std::string& text, const std::string& key) {
  std::vector<std::string> out;
  const std::string quoted = "\"" + key + "\"";
  for (size_t pos = text.find(quoted); pos != std::string::npos; pos = text.find(quoted, pos + 1)) {
    const size_t open = text.find('"', text.find(':', pos) + 1);
    out.push_back(text.substr(open + 1, text.find('"', open + 1) - open - 1));
  }
  return out;
}

// The sum of a figure in the details of the actors of kind `kind` (e.g. every pathtrace replica's "traced_rays"),
// 0 where an actor has none. An actor's keys are sorted, so its "detail" lies between the previous actor's "kind"
// and its own.
inline double sum_detail_over_kind(const std::string& stats, const std::string& kind, const std::string& key) {
  double sum = 0;
  const std::string quoted_kind = "\"kind\"", quoted = "\"" + key + "\"";
  size_t from = 0;
  for (size_t at = stats.find(quoted_kind); at != std::string::npos; from = at, at = stats.find(quoted_kind, at + 1)) {
    const size_t open = stats.find('"', stats.find(':', at) + 1);
    if (stats.substr(open + 1, stats.find('"', open + 1) - open - 1) != kind) continue;
    const size_t k = stats.find(quoted, from);
    if (k != std::string::npos && k < at) sum += std::strtod(stats.c_str() + stats.find(':', k) + 1, nullptr);
  }
  return sum;
}

// The sum of per-actor figure `key` over the actors of kind `kind` (e.g. the bytes every geometry actor received).
inline double sum_over_kind(const std::string& stats, const std::string& kind, const std::string& key) {
  const auto kinds = json_strings(stats, "kind");
  const auto values = json_numbers(stats, key);
  double sum = 0;
  for (size_t a = 0; a < kinds.size() && a < values.size(); ++a)
    if (kinds[a] == kind) sum += values[a];
  return sum;
}

struct FarmRun {
  std::string stats;              // the --stats-json text
  double wall_seconds = 0;
  double cpu_seconds = 0;         // every process of the farm
  // The largest sum, over samples every 50 ms, of the proportional set sizes of every process the director
  // started and their descendants (actors, host agents, their stand-ins, ssh clients): what the farm's actors
  // hold on this machine, shared pages counted once.
  double peak_actors_pss_bytes = 0;
  // With `sample_cpu`: (seconds since the start, CPU-seconds of the director and every live descendant) every
  // 500 ms, to find the CPU the farm used within a stage. Each sample reads every process's stat in /proc, about
  // 1 ms of CPU with 65 processes: 0.1 % of two cores, which the farm's idle share would count as its own.
  std::vector<std::pair<double, double>> cpu_samples;
  double number(const std::string& key) const { return json_number(stats, key); }
  double phase(const std::string& stage) const { return phase_seconds(stats, stage); }
};

// Every live process from /proc: its children and its user + system CPU-seconds.
struct ProcessTable {
  std::map<pid_t, std::vector<pid_t>> children;
  std::map<pid_t, double> cpu_seconds;
  // `root`'s descendants, not `root` itself.
  std::vector<pid_t> descendants(pid_t root) const {
    std::vector<pid_t> out, todo{root};
    while (!todo.empty()) {
      const pid_t pid = todo.back();
      todo.pop_back();
      if (pid != root) out.push_back(pid);
      if (auto it = children.find(pid); it != children.end()) todo.insert(todo.end(), it->second.begin(), it->second.end());
    }
    return out;
  }
};
inline ProcessTable read_process_table() {
  ProcessTable t;
  std::error_code ec;
  const double tick = static_cast<double>(::sysconf(_SC_CLK_TCK));
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(e.path() / "stat");
    std::string stat((std::istreambuf_iterator<char>(in)), {});
    const auto close = stat.rfind(')');  // the command name may hold spaces; fields resume after it
    if (close == std::string::npos) continue;
    std::istringstream fields(stat.substr(close + 2));
    std::string field;
    long ppid = 0;
    if (!(fields >> field >> ppid)) continue;  // state, ppid
    for (int i = 5; i <= 13; ++i) fields >> field;  // pgrp .. cmajflt
    unsigned long long utime = 0, stime = 0;
    fields >> utime >> stime;
    const pid_t pid = static_cast<pid_t>(std::stol(name));
    t.children[static_cast<pid_t>(ppid)].push_back(pid);
    t.cpu_seconds[pid] = static_cast<double>(utime + stime) / tick;
  }
  return t;
}

// The user + system CPU-seconds of `root` and every live descendant (a browser's process tree).
inline double tree_cpu_seconds(pid_t root) {
  const ProcessTable t = read_process_table();
  double total = t.cpu_seconds.count(root) ? t.cpu_seconds.at(root) : 0.0;
  for (pid_t pid : t.descendants(root)) total += t.cpu_seconds.at(pid);
  return total;
}

// The summed PSS of every descendant of `root` (not `root` itself), from /proc.
inline double descendants_pss_bytes(pid_t root) {
  double total = 0;
  for (pid_t pid : read_process_table().descendants(root)) {
    std::ifstream rollup("/proc/" + std::to_string(pid) + "/smaps_rollup");
    std::string key;
    double kb = 0;
    while (rollup >> key) {
      if (key == "Pss:" && rollup >> kb) {
        total += kb * 1024;
        break;
      }
      rollup.ignore(1 << 20, '\n');
    }
  }
  return total;
}

// The CPUs this process may run on, as "0,1".
inline std::string allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::string out;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return "0";
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &set)) out += (out.empty() ? "" : ",") + std::to_string(c);
  return out;
}

// Runs `lightfarm run script --set ...`; exits the benchmark if the farm fails. The image goes to `output` if
// given (the caller keeps it), else to a temporary file.
// With `sample_memory`, also peak_actors_pss_bytes (a thread reads /proc every 50 ms while the farm runs).
// With `cpus` ("0" or "0,1"), the farm and every process it starts run only on those CPUs (the affinity is
// inherited).
inline FarmRun run_farm(const std::string& script, const std::vector<std::string>& sets, const std::string& output = {},
                        bool sample_memory = false, const std::string& cpus = {}, bool sample_cpu = false) {
  const fs::path tmp = fs::temp_directory_path() / ("lightfarm-bench-" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const std::string image = output.empty() ? (tmp / "bench.exr").string() : output;
  std::vector<std::string> args{LIGHTFARM_BINARY, "run", script, "--quiet", "--output", image,
                                "--stats-json", (tmp / "stats.json").string()};
  for (const auto& s : sets) {
    args.push_back("--set");
    args.push_back(s);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  struct rusage before {};
  getrusage(RUSAGE_CHILDREN, &before);
  auto t0 = Clock::now();
  pid_t pid = fork();
  if (pid == 0) {
    if (!cpus.empty()) {
      cpu_set_t set;
      CPU_ZERO(&set);
      std::stringstream list(cpus);
      for (std::string c; std::getline(list, c, ',');) CPU_SET(std::stoi(c), &set);
      if (sched_setaffinity(0, sizeof set, &set) != 0) _exit(126);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  std::atomic<bool> running{true};
  double peak_pss = 0;
  std::vector<std::pair<double, double>> cpu_samples;
  std::thread sampler([&] {
    while ((sample_memory || sample_cpu) && running) {
      if (sample_memory) peak_pss = std::max(peak_pss, descendants_pss_bytes(pid));
      if (sample_cpu) cpu_samples.emplace_back(std::chrono::duration<double>(Clock::now() - t0).count(), tree_cpu_seconds(pid));
      std::this_thread::sleep_for(std::chrono::milliseconds(sample_cpu ? 500 : 50));
    }
  });
  int status = 0;
  waitpid(pid, &status, 0);
  running = false;
  sampler.join();
  FarmRun r;
  r.peak_actors_pss_bytes = peak_pss;
  r.cpu_samples = std::move(cpu_samples);
  r.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  struct rusage after {};
  getrusage(RUSAGE_CHILDREN, &after);
  auto secs = [](const timeval& t) { return t.tv_sec + t.tv_usec / 1e6; };
  r.cpu_seconds = secs(after.ru_utime) + secs(after.ru_stime) - secs(before.ru_utime) - secs(before.ru_stime);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "farm run failed: %s\n", script.c_str());
    std::exit(1);
  }
  std::stringstream ss;
  ss << std::ifstream(tmp / "stats.json").rdbuf();
  r.stats = ss.str();
  fs::remove_all(tmp);
  return r;
}

// `relative` under ../shared/scenes, or empty (with a line saying there is nothing to measure) when it is not there.
inline std::string shared_scene(const std::string& relative) {
  const std::string path = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/" + relative;
  if (fs::exists(path)) return path;
  std::printf("no %s: nothing to measure\n", path.c_str());
  return {};
}

// Writes a script to a temporary file and returns its path.
inline std::string temp_script(const std::string& name, const std::string& text) {
  fs::path p = fs::temp_directory_path() / ("lightfarm-bench-" + std::to_string(::getpid()) + "-" + name);
  std::ofstream(p) << text;
  return p.string();
}

}  // namespace bench
