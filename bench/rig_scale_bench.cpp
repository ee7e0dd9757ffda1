// A farm of many hosts on the test rig: N network-namespace hosts (tests/rig/hosts.sh; needs root), each with its
// own sshd, one pool of `direct` replicas and many renderers spread over them, CURVE on. Every host shares this
// machine's cores, so the figures say what the farm's own machinery costs as hosts and actors grow, not how fast
// 64 real machines would render. Per run: the exit status, each stage's seconds and the director's CPU in it,
// launch to first tile, the director's CPU share while rendering, actors lost (missed heartbeats included), render
// throughput against the same actors all on this machine (IPC, no ssh), and bytes of scene shipped.
// With --all-to-all, also the farm whose renderers each connect to every replica (subset = 0).
// Usage: build/bench/rig_scale_bench [--hosts 64] [--renderers 192] [--replicas 64] [--size 256] [--spp 8]
//                                    [--runs 1] [--all-to-all] [--json FILE]
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "bench/bench_util.hpp"
#include "core/value.hpp"

namespace {

const std::string kRig = std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/hosts.sh";
std::string g_rig;

void rig_down() {
  if (!g_rig.empty()) std::system((kRig + " down " + g_rig).c_str());
}

struct Run {
  int status = -1;
  std::string stats, err;
  double wall = 0;
};

// `lightfarm run script`, its stderr kept (a farm that fails here is a figure, not the end of the bench).
Run run_farm(const std::string& script, const std::vector<std::string>& sets) {
  const std::string stats = g_rig + "/stats.json", err = g_rig + "/stderr.txt";
  std::remove(stats.c_str());
  std::vector<std::string> args{LIGHTFARM_BINARY, "run", script, "--output", g_rig + "/out.exr", "--restart",
                                "--stats-json", stats};
  for (const auto& s : sets) args.insert(args.end(), {"--set", s});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDERR_FILENO);
    ::dup2(fd, STDOUT_FILENO);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  Run r;
  ::waitpid(pid, &r.status, 0);
  r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.status = WIFEXITED(r.status) ? WEXITSTATUS(r.status) : 128 + WTERMSIG(r.status);
  std::stringstream s, e;
  s << std::ifstream(stats).rdbuf();
  e << std::ifstream(err).rdbuf();
  r.stats = s.str();
  r.err = e.str();
  return r;
}

// The object after "key": in the stats text (the director's stats hold each per-stage map once).
size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  int hosts = 64, renderers = 192, replicas = 64, size = 256, spp = 8, runs = 1;
  bool all_to_all = false;
  std::string json_path = "bench-rig-scale.json";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return i + 1 < argc ? std::atoi(argv[++i]) : 0; };
    if (a == "--hosts") hosts = next();
    else if (a == "--renderers") renderers = next();
    else if (a == "--replicas") replicas = next();
    else if (a == "--size") size = next();
    else if (a == "--spp") spp = next();
    else if (a == "--runs") runs = next();
    else if (a == "--all-to-all") all_to_all = true;
    else if (a == "--json" && i + 1 < argc) json_path = argv[++i];
  }
  g_rig = (bench::fs::temp_directory_path() / ("lightfarm-bench-rig-scale-" + std::to_string(::getpid()))).string();
  std::atexit(rig_down);
  const auto up = std::chrono::steady_clock::now();
  if (std::system((kRig + " up " + g_rig + " " + std::to_string(hosts) + " > /dev/null").c_str()) != 0) {
    std::fprintf(stderr, "rig_scale_bench: cannot make %d namespace hosts (needs root; %s)\n", hosts, kRig.c_str());
    return 1;
  }
  std::printf("rig: %d hosts up in %.1f s\n", hosts,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - up).count());
  std::ifstream hosts_file(g_rig + "/hosts");
  std::string hosts_lua, host_list, name, addr;
  while (hosts_file >> name >> addr) {
    hosts_lua += "local " + name + " = host \"" + name + "\" { launcher = \"ssh\", address = \"" + addr +
                 "\", ssh_config = \"" + g_rig + "/ssh_config\" }\n";
    host_list += (host_list.empty() ? "" : ", ") + name;
  }
  const std::string head = "scene { file = \"" + bench::shared_scene("cornell_box_mcguire/CornellBox-Original.obj") +
                           "\" }\ncamera { eye = {-0.01, 2.5, 4.276}, at = {-0.01, 0.995, -0.025}, fov = 45 }\n"
                           "farm { light_paths = \"partial\" }\nimage { width = " + std::to_string(size) +
                           ", height = " + std::to_string(size) + ", spp = " + std::to_string(spp) + " }\n";
  auto script = [&](const std::string& file, bool remote) {
    const std::string on = remote ? ", host = { " + host_list + " }" : "";
    return bench::temp_script(file, head + (remote ? hosts_lua : "") + "local d = multiplexer { lightop \"direct\" {}, "
                                         "replicas = " + std::to_string(replicas) + ", subset = param(\"subset\", -1)" +
                                         on + " }\nrenderers { count = " + std::to_string(renderers) +
                                         ", lighting = d" + on + " }\n");
  };
  const std::string remote = script("rig-scale-remote.lua", true), local = script("rig-scale-local.lua", false);
  std::printf("%d renderers + %d direct replicas over %d hosts, CornellBox-Original %dx%d, %d spp, CURVE\n\n", renderers,
              replicas, hosts, size, size, spp);

  struct Layout {
    std::string label, script;
    std::vector<std::string> sets;
  };
  std::vector<Layout> layouts{{"hosts", remote, {}}, {"local", local, {}}};
  if (all_to_all) layouts.push_back({"hosts all-to-all", remote, {"subset=0"}});
  const char* stages[] = {"prepare", "launch", "hello", "configure", "setup", "render", "finish"};
  std::printf("%-17s %3s %7s %7s %7s %7s %7s %7s %9s %8s %7s %5s %6s\n", "layout", "rc", "prepare", "launch", "hello",
              "config", "setup", "render", "1st tile", "Msamp/s", "dir cpu", "lost", "beats");
  lf::Value::Array rows;
  std::map<std::string, std::vector<double>> throughput;
  for (int r = 0; r < runs; ++r)
    for (const Layout& l : layouts) {  // interleaved: a noisy moment hits every layout of a run
      const Run run = run_farm(l.script, l.sets);
      const std::string phases = bench::object_of(run.stats, "phases_seconds");
      const std::string director = bench::object_of(run.stats, "phases_director_cpu_seconds");
      lf::Value::Map row{{"layout", l.label}, {"run", r}, {"exit", run.status}, {"wall_seconds", run.wall}};
      lf::Value::Map stage_seconds, stage_cpu;
      for (const char* s : stages) {
        stage_seconds[s] = bench::json_number(phases, s);
        stage_cpu[s] = bench::json_number(director, s);
      }
      const double render = bench::json_number(phases, "render");
      const double director_share = render > 0 ? bench::json_number(director, "render") / render : -1;
      const double msps = run.status == 0 ? bench::json_number(run.stats, "render_samples_per_second") / 1e6 : 0;
      // Actors the director counted lost, and actors that stopped because the director went quiet.
      const size_t lost = count(run.err, "stopped answering") + count(run.err, "exited with status") +
                          count(run.err, "was killed by signal");
      const size_t silent = count(run.err, "the director has been silent");
      row["stage_seconds"] = stage_seconds;
      row["director_cpu_seconds"] = stage_cpu;
      row["first_tile_seconds"] = bench::json_number(run.stats, "first_tile_seconds");
      row["director_cpu_share_rendering"] = director_share;
      row["render_msamples_per_second"] = msps;
      row["actors_lost"] = static_cast<int64_t>(lost);
      row["actors_that_heard_nothing"] = static_cast<int64_t>(silent);
      row["scene_bytes_shipped"] = bench::json_number(bench::object_of(run.stats, "bytes_shipped"), "h1");
      std::printf("%-17s %3d", l.label.c_str(), run.status);
      for (const char* s : {"prepare", "launch", "hello", "configure", "setup", "render"})
        std::printf(" %7.2f", bench::json_number(phases, s));
      std::printf(" %9.2f %8.3f %7.3f %5zu %6zu\n", bench::json_number(run.stats, "first_tile_seconds"), msps,
                  director_share, lost, silent);
      std::fflush(stdout);
      if (run.status == 0) throughput[l.label].push_back(msps);
      rows.push_back(std::move(row));
    }
  lf::Value::Map summary;
  if (!throughput["hosts"].empty() && !throughput["local"].empty()) {
    std::vector<double> ratios;
    for (size_t i = 0; i < std::min(throughput["hosts"].size(), throughput["local"].size()); ++i)
      ratios.push_back(throughput["hosts"][i] / throughput["local"][i]);
    const auto s = bench::spread(ratios);
    std::printf("\nrender throughput, hosts / local: median %.3f (%.3f-%.3f over %zu runs)\n", s.median, s.min, s.max,
                ratios.size());
    summary["throughput_hosts_over_local"] = s.to_value();
  }
  const lf::Value doc = lf::Value::Map{{"hosts", hosts}, {"renderers", renderers}, {"replicas", replicas},
                                       {"size", size}, {"spp", spp}, {"runs", std::move(rows)},
                                       {"summary", std::move(summary)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
