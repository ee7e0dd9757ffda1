// A farm of many hosts on the test rig: N network-namespace hosts (tests/rig/hosts.sh; needs root), each with its
// own sshd, one pool of `direct` replicas and many renderers spread over them, CURVE on. Every host shares this
// machine's cores, so the figures say what the farm's own machinery costs as hosts and actors grow, not how fast
// 64 real machines would render. Per run: the exit status, each stage's seconds and the director's CPU in it,
// launch to first tile, the director's CPU share while rendering, actors lost (missed heartbeats included), render
// throughput against the same actors all on this machine (IPC, no ssh), and bytes of scene shipped.
// With --all-to-all, also the farm whose renderers each connect to every replica (subset = 0).
// With --slurm-nodes K (default 16; 0: none), slurmd runs on the first K hosts under one slurmctld
// (tests/rig/slurm.sh) and the same actors run inside `salloc -N K`, placed by slurm_hosts().
// With --ring L (default 64; 0: none), a radiosity ring of L nodes over L hosts solves the built-in room's first
// --ring-iterations shots (default 6), beside a ring of 8 over 8 hosts: time per shot of the long ring against the
// short one (both share this machine's two cores, so this is the ring's own cost as it grows, not a speed-up).
// Usage: build/bench/rig_scale_bench [--hosts 64] [--renderers 192] [--replicas 64] [--size 256] [--spp 8]
//                                    [--runs 1] [--all-to-all] [--slurm-nodes 16] [--ring 64]
//                                    [--ring-iterations 6] [--json FILE]
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
const std::string kSlurm = std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/slurm.sh";
std::string g_rig;

void rig_down() {
  if (g_rig.empty()) return;
  std::system((kSlurm + " down " + g_rig + " > /dev/null 2>&1").c_str());
  std::system((kRig + " down " + g_rig).c_str());
}

struct Run {
  int status = -1;
  std::string stats, err;
  double wall = 0;
};

// `lightfarm run script`, its stderr kept (a farm that fails here is a figure, not the end of the bench). `prefix`:
// the command it runs under (salloc), first word a path.
Run run_farm(const std::string& script, const std::vector<std::string>& sets, std::vector<std::string> prefix = {}) {
  const std::string stats = g_rig + "/stats.json", err = g_rig + "/stderr.txt";
  std::remove(stats.c_str());
  std::vector<std::string> args = std::move(prefix);
  for (const std::string& a : {std::string(LIGHTFARM_BINARY), std::string("run"), script, std::string("--output"),
                               g_rig + "/out.exr", std::string("--restart"), std::string("--stats-json"), stats})
    args.push_back(a);
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
  int hosts = 64, renderers = 192, replicas = 64, size = 256, spp = 8, runs = 1, slurm_nodes = 16, ring = 64,
      ring_iterations = 6;
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
    else if (a == "--slurm-nodes") slurm_nodes = next();
    else if (a == "--ring") ring = next();
    else if (a == "--ring-iterations") ring_iterations = std::max(1, next());
    else if (a == "--json" && i + 1 < argc) json_path = argv[++i];
  }
  slurm_nodes = std::min(slurm_nodes, hosts);
  ring = std::min(ring, hosts);
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
    std::vector<std::string> sets, prefix;
  };
  std::vector<Layout> layouts{{"hosts", remote, {}, {}}, {"local", local, {}, {}}};
  if (all_to_all) layouts.push_back({"hosts all-to-all", remote, {"subset=0"}, {}});
  if (slurm_nodes > 0) {
    const auto t = std::chrono::steady_clock::now();
    if (std::system((kSlurm + " up " + g_rig + " " + std::to_string(slurm_nodes) + " > " + g_rig + "/slurm.log 2>&1").c_str()) != 0) {
      std::fprintf(stderr, "rig_scale_bench: Slurm did not come up on %d hosts (%s/slurm.log)\n", slurm_nodes, g_rig.c_str());
      return 1;
    }
    std::printf("slurm: slurmd on %d hosts up in %.1f s\n", slurm_nodes,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
    const std::string on = ", host = nodes";
    const std::string slurm = bench::temp_script(
        "rig-scale-slurm.lua", head + "local nodes = slurm_hosts()\nlocal d = multiplexer { lightop \"direct\" {}, replicas = " +
                                   std::to_string(replicas) + on + " }\nrenderers { count = " + std::to_string(renderers) +
                                   ", lighting = d" + on + " }\n");
    layouts.push_back({"slurm " + std::to_string(slurm_nodes) + " nodes", slurm, {},
                       {"/usr/bin/env", "SLURM_CONF=" + g_rig + "/slurm.conf", "salloc", "--quiet", "-N", std::to_string(slurm_nodes)}});
  }
  const char* stages[] = {"prepare", "launch", "hello", "configure", "setup", "render", "finish"};
  std::printf("%-17s %3s %7s %7s %7s %7s %7s %7s %9s %8s %7s %5s %6s\n", "layout", "rc", "prepare", "launch", "hello",
              "config", "setup", "render", "1st tile", "Msamp/s", "dir cpu", "lost", "beats");
  lf::Value::Array rows;
  std::map<std::string, std::vector<double>> throughput;
  for (int r = 0; r < runs; ++r)
    for (const Layout& l : layouts) {  // interleaved: a noisy moment hits every layout of a run
      const Run run = run_farm(l.script, l.sets, l.prefix);
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
  if (ring > 0) {
    // The built-in room's solve on one ring of `length` nodes over as many hosts; two renderers here draw it.
    auto ring_script = [&](int length) {
      std::string on;
      std::istringstream names(host_list);
      for (int i = 0; i < length; ++i) {
        std::string h;
        std::getline(names >> std::ws, h, ',');
        on += (i ? ", " : "") + h;
      }
      return bench::temp_script("rig-scale-ring-" + std::to_string(length) + ".lua",
                                "scene { builtin = \"room\" }\ncamera { eye = {3.0, 1.55, 0.25}, at = {2.7, 0.9, 4.0}, fov = 62 }\n"
                                "image { width = 32, height = 24, spp = 1 }\n" + hosts_lua +
                                "local solution = radiosity { rings = 1, ring_length = " + std::to_string(length) +
                                ", balance = \"static+dynamic\", patch_size = 0.25, element_size = 0.125, shooter_samples = 16, "
                                "samples_per_packet = 50, subdivide = 0.5, max_depth = 2, converge = 0, max_iterations = " +
                                std::to_string(ring_iterations) + ", host = { " + on + " } }\n"
                                "renderers { count = 2, lighting = solution }\n");
    };
    std::printf("\nradiosity ring over rig hosts, built-in room, first %d shots, static+dynamic:\n%-14s %3s %8s %8s %8s %10s %10s %5s\n",
                ring_iterations, "ring", "rc", "launch", "hello", "setup", "shot mean", "shot max", "lost");
    std::map<int, std::vector<double>> shot;
    for (int r = 0; r < runs; ++r)
      for (int length : {8, ring}) {
        const Run run = run_farm(ring_script(length), {});
        const std::string phases = bench::object_of(run.stats, "phases_seconds");
        const std::vector<double> seconds = bench::json_array(run.stats, "iteration_seconds");
        double mean = 0, most = 0;
        for (double v : seconds) mean += v, most = std::max(most, v);
        if (!seconds.empty()) mean /= static_cast<double>(seconds.size());
        const size_t lost = count(run.err, "stopped answering") + count(run.err, "exited with status") +
                            count(run.err, "was killed by signal");
        std::printf("1x%-12d %3d %8.2f %8.2f %8.2f %10.3f %10.3f %5zu\n", length, run.status, bench::json_number(phases, "launch"),
                    bench::json_number(phases, "hello"), bench::json_number(phases, "setup"), mean, most, lost);
        std::fflush(stdout);
        if (run.status == 0 && static_cast<int>(seconds.size()) >= ring_iterations) shot[length].push_back(mean);
        rows.push_back(lf::Value::Map{{"layout", "ring 1x" + std::to_string(length)}, {"run", r}, {"exit", run.status},
                                      {"shot_seconds_mean", mean}, {"shot_seconds_max", most},
                                      {"setup_seconds", bench::json_number(phases, "setup")},
                                      {"actors_lost", static_cast<int64_t>(lost)}});
      }
    if (!shot[ring].empty() && !shot[8].empty()) {
      std::vector<double> ratios;
      for (size_t i = 0; i < std::min(shot[ring].size(), shot[8].size()); ++i) ratios.push_back(shot[ring][i] / shot[8][i]);
      const auto sp = bench::spread(ratios);
      std::printf("time per shot, ring of %d / ring of 8: median %.2f (%.2f-%.2f over %zu runs)\n", ring, sp.median, sp.min,
                  sp.max, ratios.size());
      summary["ring_shot_seconds_long_over_8"] = sp.to_value();
    }
  }
  if (!throughput["hosts"].empty() && !throughput["local"].empty()) {
    std::vector<double> ratios;
    for (size_t i = 0; i < std::min(throughput["hosts"].size(), throughput["local"].size()); ++i)
      ratios.push_back(throughput["hosts"][i] / throughput["local"][i]);
    const auto s = bench::spread(ratios);
    std::printf("\nrender throughput, hosts / local: median %.3f (%.3f-%.3f over %zu runs)\n", s.median, s.min, s.max,
                ratios.size());
    summary["throughput_hosts_over_local"] = s.to_value();
  }
  const std::string slurm_label = "slurm " + std::to_string(slurm_nodes) + " nodes";
  if (!throughput[slurm_label].empty() && !throughput["local"].empty()) {
    std::vector<double> ratios;
    for (size_t i = 0; i < std::min(throughput[slurm_label].size(), throughput["local"].size()); ++i)
      ratios.push_back(throughput[slurm_label][i] / throughput["local"][i]);
    const auto s = bench::spread(ratios);
    std::printf("render throughput, %s / local: median %.3f (%.3f-%.3f over %zu runs)\n", slurm_label.c_str(), s.median,
                s.min, s.max, ratios.size());
    summary["throughput_slurm_over_local"] = s.to_value();
  }
  const lf::Value doc = lf::Value::Map{{"hosts", hosts}, {"renderers", renderers}, {"replicas", replicas},
                                       {"slurm_nodes", slurm_nodes}, {"ring", ring}, {"ring_iterations", ring_iterations},
                                       {"size", size}, {"spp", spp}, {"runs", std::move(rows)},
                                       {"summary", std::move(summary)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
