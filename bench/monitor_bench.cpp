// The live monitor's cost: render time of examples/cornell.lua without `--monitor`, with it and one
// headless Chromium attached to the live page (started before the farm; plus an SSE client on /events), and with it and the SSE client alone
// (what the monitor costs apart from a browser on the same 2 cores); interleaved, `--runs` of each, the median
// ratios and their spread. Beside wall time, CPU: the farm's own (director + actors, from their STATS) without and
// with the monitor and browser, and the browser's process tree's while the frame ran, in cores. On a 2-core machine
// the browser's cores come out of the render; the farm's CPU ratio is what the monitor itself costs. And the update
// latency: from the moment a tile reached the director to the preview event's arrival at the SSE client, for the
// newest tile of each event (landed_ms) and the oldest (first_landed_ms: up to the one-second update period longer).
// At two frame lengths: ~10 s (a browser attaching inside each frame) and ~1 min (watching, per second).
//
//   build/bench/monitor_bench [--json FILE] [--runs N] [--spp N] [--long-runs N] [--long-spp N]
#include <httplib.h>
#include <signal.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <regex>
#include <thread>

#include "bench/bench_util.hpp"
#include "core/value.hpp"

extern char** environ;

namespace {

int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

pid_t spawn(std::vector<std::string> args, const std::string& err_file) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

struct Watched {
  double render_seconds = 0;
  double farm_cpu_seconds = 0;     // the director and every actor (their STATS), the monitor's work included
  double browser_cpu_seconds = 0;  // the browser's process tree while the farm ran
  std::vector<double> latencies_ms;        // from the newest tile in each preview event
  std::vector<double> first_latencies_ms;  // from the oldest: the longest any tile waited to be seen
};

// A free TCP port on loopback (bound and released: the farm binds it a moment later).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// One farm run; with `watch`, a monitor and an SSE client measuring latency, and with `browser` also a headless
// Chromium on the live page. The browser is started first and is attached, as a person's would be: it waits on a
// local page that opens the monitor as soon as it answers, so its own start-up (about a CPU-second) is over before
// the frame starts and is not charged to the monitor.
Watched run(const std::string& script, const std::vector<std::string>& sets, bool watch, bool with_browser) {
  const auto dir = bench::fs::temp_directory_path() / ("lightfarm-monitor-bench-" + std::to_string(::getpid()));
  bench::fs::create_directories(dir);
  std::vector<std::string> args{LIGHTFARM_BINARY, "run", script, "--quiet", "--output", (dir / "out.exr").string(),
                                "--stats-json", (dir / "stats.json").string()};
  for (const auto& s : sets) args.insert(args.end(), {"--set", s});
  pid_t browser = -1;
  if (with_browser) {
    const std::string port = std::to_string(free_port()), live = "http://127.0.0.1:" + port + "/";
    std::ofstream(dir / "wait.html")
        << "<!doctype html><script>function look() { fetch('" << live << "api/state', {mode: 'no-cors'})"
        << ".then(() => { location.href = '" << live << "'; }, () => setTimeout(look, 50)); } look();</script>\n";
    browser = spawn({"chromium", "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
                     "--disable-background-networking", "--disable-component-update", "--disable-sync",
                     "--disable-quic", "--remote-debugging-port=0", "--user-data-dir=" + (dir / "chromium").string(),
                     "file://" + (dir / "wait.html").string()},
                    (dir / "chromium.err").string());
    std::this_thread::sleep_for(std::chrono::seconds(4));  // started, and only polling
    args.insert(args.end(), {"--monitor", port});
  } else if (watch) {
    args.insert(args.end(), {"--monitor", "0"});
  }
  const std::string err = (dir / "err").string();
  Watched w;
  const double browser_cpu_before = browser > 0 ? bench::tree_cpu_seconds(browser) : 0;
  const pid_t farm = spawn(args, err);
  std::thread client;
  std::atomic<bool> done{false};
  if (watch) {
    std::string url;
    for (int i = 0; i < 2000 && url.empty(); ++i) {
      std::ifstream in(err);
      std::string text((std::istreambuf_iterator<char>(in)), {});
      std::smatch m;
      if (std::regex_search(text, m, std::regex("monitor: (http://127.0.0.1:([0-9]+)/)"))) url = m[1];
      else std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (url.empty()) {
      std::fprintf(stderr, "the farm printed no monitor address\n");
      std::exit(1);
    }
    const int port = std::stoi(std::regex_replace(url, std::regex(".*:([0-9]+)/$"), "$1"));
    client = std::thread([&w, &done, port] {
      httplib::Client c("127.0.0.1", port);
      c.set_read_timeout(600, 0);
      std::string buffer;
      c.Get("/events", [&](const char* data, size_t n) {
        const int64_t arrived = now_ms();
        buffer.append(data, n);
        size_t end;
        while ((end = buffer.find("\n\n")) != std::string::npos) {
          const std::string event = buffer.substr(0, end);
          buffer.erase(0, end + 2);
          if (event.rfind("event: preview", 0) != 0) continue;
          const double landed = bench::json_number(event, "landed_ms");
          const double first = bench::json_number(event, "first_landed_ms");
          if (landed > 0) w.latencies_ms.push_back(static_cast<double>(arrived) - landed);
          if (first > 0) w.first_latencies_ms.push_back(static_cast<double>(arrived) - first);
        }
        return !done.load();
      });
    });
  }
  int status = 0;
  waitpid(farm, &status, 0);
  done = true;
  if (client.joinable()) client.join();
  if (browser > 0) w.browser_cpu_seconds = bench::tree_cpu_seconds(browser) - browser_cpu_before;
  if (browser > 0) {
    ::kill(browser, SIGTERM);
    waitpid(browser, nullptr, 0);
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "farm run failed: %s\n", script.c_str());
    std::exit(1);
  }
  std::stringstream ss;
  ss << std::ifstream(dir / "stats.json").rdbuf();
  w.render_seconds = bench::phase_seconds(ss.str(), "render");
  w.farm_cpu_seconds = bench::json_number(ss.str(), "actors_cpu_seconds") + bench::json_number(ss.str(), "director_cpu_seconds");
  // The browser's helper processes may still be writing its profile for a moment after it exited.
  std::error_code ec;
  for (int i = 0; i < 50; ++i, std::this_thread::sleep_for(std::chrono::milliseconds(100)))
    if (bench::fs::remove_all(dir, ec), !ec) break;
  return w;
}

// Without and with the monitor and a browser, interleaved, at one frame length: render-time and farm-CPU ratios and
// the browser's cores, one per run.
struct Paired {
  std::vector<double> ratios, cpu_ratios, browser_cores;
};

void add(Paired& p, const Watched& plain, const Watched& watched) {
  p.ratios.push_back(plain.render_seconds / watched.render_seconds);
  p.cpu_ratios.push_back(plain.farm_cpu_seconds / watched.farm_cpu_seconds);
  p.browser_cores.push_back(watched.browser_cpu_seconds / watched.render_seconds);
}

lf::Value paired_value(const Paired& p) {
  return lf::Value::Map{{"ratio", bench::spread(p.ratios).to_value()},
                        {"farm_cpu_ratio", bench::spread(p.cpu_ratios).to_value()},
                        {"browser_cores", bench::spread(p.browser_cores).to_value()}};
}

void print_paired(const char* label, const Paired& p) {
  const auto ratio = bench::spread(p.ratios), cpu = bench::spread(p.cpu_ratios),
             cores = bench::spread(p.browser_cores);
  std::printf("%s, render time without / with the monitor and a browser: median %.3f (min %.3f, max %.3f; goal >= "
              "0.98)\n", label, ratio.median, ratio.min, ratio.max);
  std::printf("%s, farm CPU-seconds (director + actors) without / with: median %.3f (min %.3f, max %.3f)\n", label,
              cpu.median, cpu.min, cpu.max);
  std::printf("%s, the browser's CPU while the farm ran, in cores: median %.3f (min %.3f, max %.3f) of the machine's "
              "2\n", label, cores.median, cores.min, cores.max);
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/monitor_bench [--json FILE] [--runs N] [--spp N] [--long-runs N]"
                            " [--long-spp N]",
                            {"--json", "--runs", "--spp", "--long-runs", "--long-spp"});
  std::string json_path = "bench-monitor.json";
  int runs = 5, spp = 160, long_runs = 3, long_spp = 800;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--spp") spp = std::atoi(argv[i + 1]);
    else if (a == "--long-runs") long_runs = std::atoi(argv[i + 1]);
    else if (a == "--long-spp") long_spp = std::atoi(argv[i + 1]);
  }
  if (std::system("command -v chromium > /dev/null 2>&1") != 0) {
    std::printf("no chromium: nothing to measure\n");
    return 0;
  }
  const std::string script = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/cornell.lua";
  // Two frame lengths. About 10 s: a browser attaches once per frame here, and attaching (its page load and a new
  // renderer process) costs ~0.3 CPU-s, so this is what watching a short frame costs. About a minute (--long-spp;
  // what the monitor is for: frames of minutes to hours): what watching costs per second of rendering. The
  // monitor with an SSE client and no browser is measured at the short length only.
  auto sets_for = [](int n) { return std::vector<std::string>{"width=512", "height=512", "spp=" + std::to_string(n)}; };
  Paired short_frames, long_frames;
  std::vector<double> server_ratios, latencies, first_latencies;
  for (int r = 0; r < runs; ++r) {
    const Watched a = run(script, sets_for(spp), false, false), b = run(script, sets_for(spp), true, true),
                  c = run(script, sets_for(spp), true, false);
    add(short_frames, a, b);
    server_ratios.push_back(a.render_seconds / c.render_seconds);
    latencies.insert(latencies.end(), b.latencies_ms.begin(), b.latencies_ms.end());
    first_latencies.insert(first_latencies.end(), b.first_latencies_ms.begin(), b.first_latencies_ms.end());
    std::printf("short run %d: render %.3f s without, %.3f s with the monitor and a browser, %.3f s with the monitor "
                "and an SSE client only\n", r + 1, a.render_seconds, b.render_seconds, c.render_seconds);
  }
  for (int r = 0; r < long_runs; ++r) {
    const Watched a = run(script, sets_for(long_spp), false, false), b = run(script, sets_for(long_spp), true, true);
    add(long_frames, a, b);
    std::printf("long run %d: render %.3f s without, %.3f s with the monitor and a browser\n", r + 1,
                a.render_seconds, b.render_seconds);
  }
  const auto server = bench::spread(server_ratios);
  const auto latency = bench::spread(latencies), first_latency = bench::spread(first_latencies);
  std::printf("\n");
  if (runs > 0) {
    print_paired(("short frames (" + std::to_string(spp) + " spp, the browser attaching in each)").c_str(),
                 short_frames);
    std::printf("short frames, render time without / with the monitor and an SSE client (no browser): median %.3f "
                "(min %.3f, max %.3f)\n", server.median, server.min, server.max);
    std::printf("tile landed -> preview event at the client, newest tile of each event: median %.0f ms (min %.0f, "
                "max %.0f) over %zu events\n", latency.median, latency.min, latency.max, latencies.size());
    std::printf("tile landed -> preview event at the client, oldest tile of each event: median %.0f ms (min %.0f, "
                "max %.0f) over %zu events\n", first_latency.median, first_latency.min, first_latency.max,
                first_latencies.size());
  }
  if (long_runs > 0)
    print_paired(("long frames (" + std::to_string(long_spp) + " spp)").c_str(), long_frames);
  lf::Value doc = lf::Value::Map{
      {"benchmark", "monitor"},
      {"scene", "cornell 512x512"},
      {"short_frames", lf::Value::Map{{"spp", static_cast<int64_t>(spp)}, {"runs", static_cast<int64_t>(runs)},
                                      {"with_browser", paired_value(short_frames)},
                                      {"ratio_without_browser", server.to_value()}}},
      {"long_frames", lf::Value::Map{{"spp", static_cast<int64_t>(long_spp)}, {"runs", static_cast<int64_t>(long_runs)},
                                     {"with_browser", paired_value(long_frames)}}},
      {"latency_ms", latency.to_value()},
      {"latency_events", static_cast<int64_t>(latencies.size())},
      {"latency_oldest_tile_ms", first_latency.to_value()}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
