// Recovery of a radiosity ring: what checkpoints cost when nothing fails, and what they save when a
// node is lost. On the built-in furnished room (examples/radiosity_room.lua's mesh, 2 x 2 nodes, a fixed number of
// iterations), interleaved, each repeated:
//   - fault-free solves with checkpoint_every = 0 (none), 10 and 1: solve seconds, and each against "none";
//   - solves in which one node is SIGKILLed halfway through (by the fault-free solve time), with checkpoint_every = 0
//     (the ring starts again) and 10 (back to the last checkpoint): solve seconds against the fault-free one, and
//     the iterations the ring had to repeat.
// Every solve's PLY must equal the fault-free one byte for byte (counted as "differing", goal 0).
//
//   build/bench/ring_recovery_bench [--repeats 3] [--iterations 120] [--json bench-ring-recovery.json]
#include <signal.h>

#include <cstring>
#include <map>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "tests/process_harness.hpp"

namespace {

using lf::test::Farm;

struct Solve {
  double seconds = 0;       // the ring service's solve_seconds
  double checkpoint_mb = 0;
  double repeated = 0;      // iterations done twice: lost_at - resumed_from - 1
  bool same = true;         // PLY equal to the reference
  bool ok = false;
};

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/ring_recovery_bench [--repeats 3] [--iterations 120] [--json FILE]",
                            {"--repeats", "--iterations", "--json"});
  int repeats = 3, iterations = 120;
  std::string json_path = "bench-ring-recovery.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--repeats") repeats = std::atoi(argv[i + 1]);
    else if (a == "--iterations") iterations = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  const bench::fs::path dir = bench::fs::temp_directory_path() / ("ring-recovery-" + std::to_string(::getpid()));
  bench::fs::create_directories(dir);
  const std::string script = bench::temp_script(
      "ring-recovery.lua",
      "scene { builtin = \"room\" }\n"
      "camera { eye = {3.0, 1.55, 0.25}, at = {2.7, 0.9, 4.0}, fov = 62 }\n"
      "image { width = 32, height = 24, spp = 1 }\n"
      "renderers { count = 1, lighting = radiosity { rings = 2, ring_length = 2, patch_size = 0.25, "
      "element_size = 0.125, subdivide = 0.5, max_depth = 2, converge = 0, max_iterations = param(\"iterations\", 100), "
      "checkpoint_every = param(\"every\", 0), ply = param(\"ply\", \"x.ply\") } }\n");

  const std::string reference_ply = (dir / "reference.ply").string();
  auto solve = [&](int every, double kill_after, const std::string& tag) {
    Solve s;
    const std::string ply = (dir / (tag + ".ply")).string(), stats = (dir / (tag + ".json")).string();
    Farm farm({"run", script, "--output", (dir / (tag + ".png")).string(), "--stats-json", stats, "--set",
               "iterations=" + std::to_string(iterations), "--set", "every=" + std::to_string(every), "--set",
               "ply=" + ply});
    if (kill_after > 0) {
      // Timed from the first shooter, so the loss lands anywhere between two checkpoints.
      Farm::eventually([&] { return farm.err_so_far().find("iteration 0,") != std::string::npos; }, 120);
      std::this_thread::sleep_for(std::chrono::duration<double>(kill_after));
      for (pid_t pid : lf::test::actor_pids(farm.tag(), "radiosity.1.0")) ::kill(pid, SIGKILL);
    }
    auto r = farm.wait(600);
    if (r.status != 0) {
      std::fprintf(stderr, "ring_recovery_bench: %s failed (exit %d):\n%s", tag.c_str(), r.status, r.err.c_str());
      return s;
    }
    const std::string json = lf::test::read_file(stats);
    s.ok = true;
    s.seconds = bench::json_number(json, "solve_seconds");
    s.checkpoint_mb = bench::json_number(json, "checkpoint_bytes") / 1e6;
    if (kill_after > 0) {
      const double lost = bench::json_number(json, "lost_at_iteration"), from = bench::json_number(json, "resumed_from_iteration");
      s.repeated = lost < 0 ? -1 : lost - from - 1;
    }
    if (bench::fs::exists(reference_ply)) s.same = lf::test::read_file(ply) == lf::test::read_file(reference_ply);
    else bench::fs::copy_file(ply, reference_ply);
    return s;
  };

  std::printf("lightfarm ring recovery: built-in room, 2 x 2 nodes, %d iterations, %d repeats\n", iterations, repeats);
  const std::vector<std::pair<std::string, int>> fault_free{{"none", 0}, {"every10", 10}, {"every1", 1}};
  const std::vector<std::pair<std::string, int>> faulty{{"killed-none", 0}, {"killed-every10", 10}};
  std::map<std::string, std::vector<Solve>> runs;
  double half = 0;
  for (int r = 0; r < repeats; ++r) {
    for (const auto& [name, every] : fault_free) runs[name].push_back(solve(every, 0, name + "-" + std::to_string(r)));
    if (half == 0) half = runs["none"].front().seconds / 2;
    for (const auto& [name, every] : faulty) runs[name].push_back(solve(every, half, name + "-" + std::to_string(r)));
  }

  lf::Value::Map doc{{"iterations", iterations}, {"repeats", repeats}, {"kill_after_seconds", half}};
  int differing = 0, failed = 0;
  std::printf("%-16s %10s %18s %14s %10s %9s\n", "solve", "seconds", "vs none (min-max)", "checkpoint MB", "repeated", "differing");
  for (const auto& name : {"none", "every10", "every1", "killed-none", "killed-every10"}) {
    std::vector<double> seconds, ratio, repeated;
    int diff = 0;
    double mb = 0;
    for (size_t i = 0; i < runs[name].size(); ++i) {
      const Solve& s = runs[name][i];
      if (!s.ok) {
        ++failed;
        continue;
      }
      seconds.push_back(s.seconds);
      ratio.push_back(s.seconds / runs["none"][i].seconds);
      repeated.push_back(s.repeated);
      mb = s.checkpoint_mb;
      diff += s.same ? 0 : 1;
    }
    differing += diff;
    const auto t = bench::spread(seconds), q = bench::spread(ratio), rep = bench::spread(repeated);
    std::printf("%-16s %10.2f %6.3f (%.3f-%.3f) %14.2f %10.0f %9d\n", name, t.median, q.median, q.min, q.max, mb,
                rep.median, diff);
    doc[name] = lf::Value::Map{{"solve_seconds", t.to_value()},
                               {"ratio_to_none", q.to_value()},
                               {"checkpoint_mb", mb},
                               {"iterations_repeated", rep.to_value()},
                               {"differing", diff}};
  }
  doc["differing"] = differing;
  doc["failed"] = failed;
  bench::fs::remove_all(dir);
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return differing == 0 && failed == 0 ? 0 : 1;
}
