// Farms across hosts: hosts are network namespaces on this machine with their own sshd
// (tests/rig/hosts.sh; needs root). Prints, for each figure, min/median/max over --runs, and writes
// bench-hosts.json:
//   launch to first tile, 12 actors (8 replicas, 3 renderers, the multiplexer) over 3 ssh hosts, over a Slurm
//   allocation of the same 3 hosts (job steps), and all local
//   starting 12 and 48 processes in that allocation as one job step each (SlurmLauncher's way) vs one step per node
//   the same 12 actors on Lost Empire (225k triangles, shipped once, then cached), over ssh and local
//   render throughput of the pool network (2 renderers + 3 direct replicas) across 3 ssh hosts vs all local
//   render throughput with CURVE vs security = "none" across the 3 hosts (every link between hosts encrypted), for
//   the `direct` pool and for a `pathtrace` pool, and on one machine (same-host links are IPC either way)
// Usage: build/bench/hosts_bench [--runs N] [--json FILE]
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "bench/bench_util.hpp"
#include "core/value.hpp"

namespace {

const std::string kRig = std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/hosts.sh";
std::string g_rig;

const std::string kSlurmRig = std::string(LIGHTFARM_SOURCE_DIR) + "/tests/rig/slurm.sh";

void rig_down() {
  if (g_rig.empty()) return;
  std::system((kSlurmRig + " down " + g_rig + " 2>/dev/null").c_str());
  std::system((kRig + " down " + g_rig).c_str());
}

// first_tile_seconds of `lightfarm run script` inside `salloc -N nodes` on the rig's Slurm cluster.
double first_tile_in_allocation(const std::string& script, int nodes) {
  const std::string stats = g_rig + "/slurm-stats.json";
  const std::string cmd = "SLURM_CONF=" + g_rig + "/slurm.conf salloc --quiet -N " + std::to_string(nodes) + " " +
                          LIGHTFARM_BINARY + " run " + script + " --quiet --output " + g_rig + "/slurm.exr --stats-json " +
                          stats;
  if (std::system(cmd.c_str()) != 0) {
    std::fprintf(stderr, "hosts_bench: the farm under salloc failed\n");
    std::exit(1);
  }
  std::ifstream in(stats);
  std::stringstream text;
  text << in.rdbuf();
  return bench::json_number(text.str(), "first_tile_seconds");
}

// Seconds to start `processes` processes over the allocation's 3 nodes as one job step each and as one step per
// node (bench/slurm_steps.sh), or {-1, -1} if it failed.
std::pair<double, double> step_launch(int processes) {
  const std::string out = g_rig + "/steps.txt";
  const std::string cmd = "SLURM_CONF=" + g_rig + "/slurm.conf salloc --quiet -N 3 " + LIGHTFARM_SOURCE_DIR +
                          "/bench/slurm_steps.sh " + std::to_string(processes) + " > " + out;
  if (std::system(cmd.c_str()) != 0) return {-1, -1};
  std::ifstream in(out);
  std::string a, b;
  double per_actor = -1, per_node = -1;
  in >> a >> per_actor >> b >> per_node;
  return {per_actor, per_node};
}


}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/hosts_bench [--runs N] [--json FILE]",
                            {"--runs", "--json"});
  int runs = 5;
  std::string json_path = "bench-hosts.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  g_rig = (bench::fs::temp_directory_path() / ("lightfarm-bench-rig-" + std::to_string(::getpid()))).string();
  std::atexit(rig_down);
  const int rc = std::system((kRig + " up " + g_rig + " 3 > /dev/null").c_str());
  if (rc != 0) {
    std::fprintf(stderr, "hosts_bench: cannot make namespace hosts (needs root; %s)\n", kRig.c_str());
    return 1;
  }
  const bool slurm = std::system((kSlurmRig + " up " + g_rig + " > /dev/null 2>&1").c_str()) == 0;
  if (!slurm) std::fprintf(stderr, "hosts_bench: no Slurm cluster on the rig (tests/rig/slurm.sh); skipping its figure\n");
  std::ifstream hosts_file(g_rig + "/hosts");
  std::string hosts_lua, name, addr;
  while (hosts_file >> name >> addr)
    hosts_lua += "local " + name + " = host \"" + name + "\" { launcher = \"ssh\", address = \"" + addr +
                 "\", ssh_config = \"" + g_rig + "/ssh_config\" }\n";
  const std::string head = "scene { builtin = \"cornell\" }\nfarm { security = param(\"security\", \"curve\") }\n";
  auto script = [&](const std::string& file, const std::string& image, const std::string& pool_hosts,
                    const std::string& renderer_hosts, int replicas, int renderers, bool remote) {
    return bench::temp_script(
        file, head + (remote ? hosts_lua : "") + image + "local d = multiplexer { lightop \"direct\" {}, replicas = " +
                  std::to_string(replicas) + pool_hosts + " }\nrenderers { count = " + std::to_string(renderers) +
                  ", lighting = d" + renderer_hosts + " }\n");
  };
  const std::string tiny = "image { width = 64, height = 64, spp = 1, tile = 16 }\n";
  // About 6 s of rendering: at 2 s (32 spp) the ratios below ranged over 0.81-0.93 in 5 runs on this noisy machine.
  const std::string frame = "image { width = 512, height = 512, spp = 96 }\n";
  const auto launch_remote = script("launch-remote.lua", tiny, ", host = { h1, h2, h3 }", ", host = { h1, h2, h3 }", 8, 3, true);
  const auto launch_local = script("launch-local.lua", tiny, "", "", 8, 3, false);
  const auto pool_remote = script("pool-remote.lua", frame, ", host = { h1, h2, h3 }", ", host = { h2, h3 }", 3, 2, true);
  const auto pool_local = script("pool-local.lua", frame, "", "", 3, 2, false);
  // The same pool across hosts serving a heavier op (path tracing: at depth 12 ~3x the work per sample of `direct`
  // on the Cornell box, 1.0 vs 2.8 M samples/s in farm_bench): CURVE's cost per byte is the same, its share is not.
  const auto heavy_remote = bench::temp_script(
      "heavy-remote.lua", head + hosts_lua + "image { width = 384, height = 384, spp = 48 }\n"
                          "local d = multiplexer { lightop \"pathtrace\" {}, replicas = 3, host = { h1, h2, h3 } }\n"
                          "renderers { count = 2, lighting = d, host = { h2, h3 } }\n");
  const auto launch_slurm = bench::temp_script(
      "launch-slurm.lua", head + tiny + "local nodes = slurm_hosts()\n"
                                        "local d = multiplexer { lightop \"direct\" {}, replicas = 8, host = nodes }\n"
                                        "renderers { count = 3, lighting = d, host = nodes }\n");

  // A real interior (Lost Empire, 225k triangles, ../shared/scenes): the director parses it, the hosts get it once.
  const std::string big_obj = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/lost_empire/lost_empire.obj";
  const bool have_big = bench::fs::exists(big_obj);
  const std::string big_head = "scene { file = \"" + big_obj + "\" }\ncamera { eye = {-25, 28, 55}, at = {0, 8, 0}, fov = 60 }\n"
                               "light { point = {0, 40, 0}, intensity = {4000, 3600, 3000} }\n"
                               "farm { security = param(\"security\", \"curve\") }\n";
  const auto big_remote = bench::temp_script(
      "big-remote.lua", big_head + hosts_lua + tiny +
                            "local d = multiplexer { lightop \"direct\" {}, replicas = 8, host = { h1, h2, h3 } }\n"
                            "renderers { count = 3, lighting = d, host = { h1, h2, h3 } }\n");
  const auto big_local = bench::temp_script(
      "big-local.lua", big_head + tiny + "local d = multiplexer { lightop \"direct\" {}, replicas = 8 }\n"
                                         "renderers { count = 3, lighting = d }\n");
  if (have_big) {
    // The first farm ships the scene to each host; the figures below are with it cached, as every later farm is.
    const auto first = bench::run_farm(big_remote, {});
    std::printf("Lost Empire: %.0f bytes shipped to each host by the first farm (first tile %.3f s)\n",
                first.number("h1"), first.number("first_tile_seconds"));
  }

  std::map<std::string, std::vector<double>> v;
  for (int r = 0; r < runs; ++r) {
    // Interleaved, so that a noisy moment hits both sides of a ratio.
    v["first_tile_remote"].push_back(bench::run_farm(launch_remote, {}).number("first_tile_seconds"));
    v["first_tile_local"].push_back(bench::run_farm(launch_local, {}).number("first_tile_seconds"));
    if (slurm) {
      v["first_tile_slurm"].push_back(first_tile_in_allocation(launch_slurm, 3));
      for (int processes : {12, 48}) {
        const auto [per_actor, per_node] = step_launch(processes);
        const std::string n = std::to_string(processes);
        v["slurm_start_" + n + "_as_steps_per_actor"].push_back(per_actor);
        v["slurm_start_" + n + "_as_one_step_per_node"].push_back(per_node);
      }
    }
    if (have_big) {
      v["big_first_tile_remote"].push_back(bench::run_farm(big_remote, {}).number("first_tile_seconds"));
      v["big_first_tile_local"].push_back(bench::run_farm(big_local, {}).number("first_tile_seconds"));
    }
    // Each group of farms runs in one order in even runs and in the reverse order in odd ones, so that a drift of
    // this machine's speed within a group (it has one: a ratio of two identical setups read 0.89-0.97) does not
    // lean every ratio the same way.
    auto throughput = [](const std::string& script, const std::string& security) {
      return [script, security] { return bench::run_farm(script, {"security=" + security}).number("render_samples_per_second"); };
    };
    auto in_turn = [r](std::vector<std::function<double()>> farms) {
      std::vector<double> out(farms.size());
      for (size_t k = 0; k < farms.size(); ++k) {
        const size_t i = r % 2 ? farms.size() - 1 - k : k;
        out[i] = farms[i]();
      }
      return out;
    };
    const auto four = in_turn({throughput(pool_remote, "curve"), throughput(pool_local, "curve"),
                               throughput(pool_remote, "none"), throughput(pool_local, "none")});
    const double remote = four[0], local = four[1], remote_plain = four[2], local_plain = four[3];
    v["throughput_remote_over_local"].push_back(remote / local);
    // The same without CURVE on either side: what spreading over hosts costs apart from encryption.
    v["throughput_remote_over_local_none"].push_back(remote_plain / local_plain);
    // What CURVE costs where it is used: every link between hosts is encrypted.
    v["throughput_curve_over_none_across_hosts"].push_back(remote / remote_plain);
    const auto heavy = in_turn({throughput(heavy_remote, "curve"), throughput(heavy_remote, "none")});
    v["throughput_curve_over_none_across_hosts_pathtrace"].push_back(heavy[0] / heavy[1]);
    // On one host CURVE guards only the links to the director (actors talk over IPC): this ratio should read 1, and
    // how far it strays is this machine's noise.
    const auto on_one_host = in_turn({throughput(pool_local, "curve"), throughput(pool_local, "none")});
    const double curve = on_one_host[0], none = on_one_host[1];
    v["throughput_curve_over_none"].push_back(curve / none);
    v["samples_per_second_local_curve"].push_back(curve);
    v["samples_per_second_local_none"].push_back(none);
    std::fprintf(stderr, "run %d/%d done\n", r + 1, runs);
  }
  std::printf("lightfarm hosts benchmark: 3 namespace hosts over ssh (veth + bridge on one 2-core machine), %d runs\n",
              runs);
  std::printf("%-46s %9s %9s %9s\n", "figure", "min", "median", "max");
  lf::Value::Map doc;
  for (const char* key : {"first_tile_remote", "first_tile_slurm", "first_tile_local",
                          "slurm_start_12_as_steps_per_actor", "slurm_start_12_as_one_step_per_node",
                          "slurm_start_48_as_steps_per_actor", "slurm_start_48_as_one_step_per_node", "big_first_tile_remote",
                          "big_first_tile_local", "throughput_remote_over_local", "throughput_remote_over_local_none",
                          "throughput_curve_over_none_across_hosts", "throughput_curve_over_none_across_hosts_pathtrace",
                          "throughput_curve_over_none", "samples_per_second_local_curve",
                          "samples_per_second_local_none"}) {
    if (v[key].empty()) continue;
    const bench::Spread s = bench::spread(v[key]);
    std::printf("%-46s %9.3f %9.3f %9.3f\n", key, s.min, s.median, s.max);
    doc[key] = s.to_value();
  }
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
