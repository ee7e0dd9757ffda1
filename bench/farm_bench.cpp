// Farm benchmarks (issues 2 and 16): what the farm costs beside the light it computes. For a cheap LightOp
// (`direct`, 2 light samples) and a heavy one (`pathtrace`, depth 12) on the Cornell box:
//   - the bare loop: the same kernel and the same LightOp class in one process, no messages, on 1 thread and on 2;
//   - farm 1+1 (1 renderer, 1 LightOp) against the 1-thread loop, per wall second and per CPU-second of every
//     process (the director, the actors, every thread of each);
//   - farm 2+2 (2 renderers, a pool of 2) against the 2-thread loop: what a 2-core farm is compared with;
//   - core scaling: farm 2+2 with every process pinned to 1 core vs to 2 cores (sched_setaffinity, inherited).
// Every ratio is taken within one run (the configurations interleave) and printed as min / median / max over the
// runs, because this 2-core machine is noisy. Start-up (6 actors, launch to first tile) as before. The frames are a
// few seconds of light each (64 spp): long enough that the figures are of rendering, not of starting a farm.
//
//   build/bench/farm_bench [--json FILE] [--runs N] [--size PIXELS] [--spp N] [--pathtrace-size PIXELS]
#include <sched.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/tracing/camera.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/tile_kernel.hpp"

using Clock = std::chrono::steady_clock;

namespace {

struct OpCase {
  std::string label;     // "direct", "pathtrace"
  std::string kind;      // LightOp kind
  lf::Value::Map params;
  std::string lua_params;  // the same, as a Lua table body
  int size = 0, spp = 0;
};

// The bare loop on `threads` threads: tiles taken in turn from one counter, each thread with its own LightOp
// instance (as each replica of a pool has), trace -> shade -> resolve. Samples per second.
double bare_loop(const OpCase& c, int threads) {
  auto scene = lf::Scene::builtin("cornell");
  lf::RayTracer tracer(*scene);
  lf::ImageSpec image;
  image.width = image.height = c.size;
  image.spp = c.spp;
  image.edge_spp = lf::ImageSpec::default_edge_spp(c.spp);  // as the scripts' image { } has it
  lf::Camera camera(lf::CameraSpec{}, c.size, c.size);  // the scripts' camera (the Cornell box's default)
  const lf::EmitterEdges edges = lf::emitter_edges(*scene, camera, image);
  const auto tiles = lf::make_tiles(c.size, c.size, image.tile);
  std::vector<std::unique_ptr<lf::LightOp>> ops;
  lf::LocalInputs none;
  for (int t = 0; t < threads; ++t) {
    ops.push_back(lf::create_lightop(*lf::find_lightop_kind(c.kind), lf::ParamTable(c.params, c.kind)));
    lf::run_to_completion(ops.back()->setup(lf::SceneContext{&*scene, &tracer}, none));
  }
  std::atomic<size_t> next{0};
  std::atomic<double> checksum{0};
  auto t0 = Clock::now();
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      lf::TileWork work;
      std::vector<lf::RGB> radiance, pixels;
      lf::LocalInputs mine;
      double sum = 0;
      for (size_t i = next++; i < tiles.size(); i = next++) {
        lf::trace_tile(*scene, tracer, camera, image, tiles[i], work, edges);
        radiance.assign(work.points.size(), {});
        lf::run_to_completion(ops[static_cast<size_t>(t)]->shade(work.points, radiance, mine));
        lf::resolve_tile(work, radiance, pixels);
        sum += pixels[0].x;
      }
      checksum = checksum + sum;
    });
  for (auto& th : pool) th.join();
  const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  if (checksum < 0) std::puts("");  // keep the work observable
  return static_cast<double>(c.size) * c.size * c.spp / secs;
}

struct FarmFigures {
  double samples_per_second = 0;  // render phase
  double samples_per_cpu_second = 0;  // whole run, every process
  double cpu_seconds = 0, director_cpu = 0, renderers_cpu = 0, lightops_cpu = 0, multiplexer_cpu = 0, wall = 0;
};

// Sums the cpu_seconds of every actor of a kind in a --stats-json text (entries hold "cpu_seconds" then "kind").
std::map<std::string, double> cpu_by_kind(const std::string& stats) {
  std::map<std::string, double> out;
  size_t pos = 0;
  while ((pos = stats.find("\"cpu_seconds\"", pos)) != std::string::npos) {
    const double cpu = std::strtod(stats.c_str() + stats.find(':', pos) + 1, nullptr);
    const size_t kind = stats.find("\"kind\"", pos);
    const size_t q1 = stats.find('"', stats.find(':', kind) + 1), q2 = stats.find('"', q1 + 1);
    out[stats.substr(q1 + 1, q2 - q1 - 1)] += cpu;
    pos = kind;
  }
  return out;
}

FarmFigures run_farm(const std::string& script, const OpCase& c, int renderers, int replicas, const std::string& cpus) {
  auto r = bench::run_farm(script,
                           {"width=" + std::to_string(c.size), "height=" + std::to_string(c.size),
                            "spp=" + std::to_string(c.spp), "renderers=" + std::to_string(renderers),
                            "replicas=" + std::to_string(replicas)},
                           {}, false, cpus);
  FarmFigures f;
  f.samples_per_second = r.number("render_samples_per_second");
  f.cpu_seconds = r.cpu_seconds;
  f.wall = r.wall_seconds;
  f.samples_per_cpu_second = static_cast<double>(c.size) * c.size * c.spp / r.cpu_seconds;
  f.director_cpu = r.number("director_cpu_seconds");
  for (const auto& [kind, cpu] : cpu_by_kind(r.stats)) {
    if (kind == "renderer") f.renderers_cpu += cpu;
    else if (kind == "multiplexer") f.multiplexer_cpu += cpu;
    else f.lightops_cpu += cpu;
  }
  return f;
}

// A script with one LightOp (replicas = 1) or a pool of them.
std::string op_script(const OpCase& c) {
  return bench::temp_script(c.label + ".lua", R"(
scene  { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image  { width = param("width", 64), height = param("height", 64), spp = param("spp", 1), output = "bench.exr" }
local op = lightop ")" + c.kind + R"(" { )" + c.lua_params + R"( }
if param("replicas", 1) > 1 then op = multiplexer { op, replicas = param("replicas", 1) } end
renderers { count = param("renderers", 1), lighting = op }
)");
}

struct Series {
  std::vector<double> bare1, bare2, farm11, farm11_cpu, farm22, pinned1, pinned2;
  std::vector<double> overhead, efficiency, versus_bare2, scaling;
  FarmFigures last11, last22;
};

void print_spread(const char* label, const std::vector<double>& v, const char* goal) {
  const auto s = bench::spread(v);
  std::printf("  %-46s %7.3f  (min %.3f, max %.3f)%s\n", label, s.median, s.min, s.max, goal);
}

lf::Value spread_value(const std::vector<double>& v) { return bench::spread(v).to_value(); }

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/farm_bench [--json FILE] [--runs N] [--size PIXELS] [--spp N]"
                            " [--pathtrace-size PIXELS]",
                            {"--json", "--runs", "--size", "--spp", "--pathtrace-size"});
  std::string json_path = "bench-farm.json";
  // Frames of ~6 s (direct) and ~9 s (pathtrace) on one core: a farm's fixed cost (the director's ~0.7 CPU-s, each
  // actor's start) is printed apart; in a frame of 1 s of light it was what the ratios measured (CPU efficiency 0.55
  // for direct and 0.49 for pathtrace at 16 spp, 0.77 and 0.88 at 64 spp, same code).
  int runs = 3, size = 512, spp = 64, pathtrace_size = 384;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--size") size = std::atoi(argv[i + 1]);
    else if (a == "--spp") spp = std::atoi(argv[i + 1]);
    else if (a == "--pathtrace-size") pathtrace_size = std::atoi(argv[i + 1]);
  }
  const std::vector<OpCase> cases{
      {"direct", "direct", lf::Value::Map{{"light_samples", 2}}, "light_samples = 2", size, spp},
      {"pathtrace", "pathtrace", lf::Value::Map{{"max_depth", 12}}, "max_depth = 12", pathtrace_size, spp}};
  const std::string all_cores = bench::allowed_cpus();
  const std::string one_core = all_cores.substr(0, all_cores.find(','));

  std::map<std::string, Series> series;
  std::vector<double> startup;
  for (int r = 0; r < runs; ++r) {
    for (const auto& c : cases) {
      // Interleaved so drift in machine load hits every configuration alike.
      const std::string script = op_script(c);
      Series& s = series[c.label];
      const double b1 = bare_loop(c, 1), b2 = bare_loop(c, 2);
      const FarmFigures f11 = run_farm(script, c, 1, 1, {});
      const FarmFigures f22 = run_farm(script, c, 2, 2, {});
      const FarmFigures p1 = run_farm(script, c, 2, 2, one_core);
      const FarmFigures p2 = run_farm(script, c, 2, 2, all_cores);
      s.bare1.push_back(b1);
      s.bare2.push_back(b2);
      s.farm11.push_back(f11.samples_per_second);
      s.farm11_cpu.push_back(f11.samples_per_cpu_second);
      s.farm22.push_back(f22.samples_per_second);
      s.pinned1.push_back(p1.samples_per_second);
      s.pinned2.push_back(p2.samples_per_second);
      s.overhead.push_back(f11.samples_per_second / b1);
      s.efficiency.push_back(f11.samples_per_cpu_second / b1);
      s.versus_bare2.push_back(f22.samples_per_second / b2);
      s.scaling.push_back(p2.samples_per_second / p1.samples_per_second);
      s.last11 = f11;
      s.last22 = f22;
    }
    // Start-up: a 6-actor farm (5 renderers + direct), small image so the first tile is the first thing done.
    startup.push_back(bench::run_farm(std::string(LIGHTFARM_SOURCE_DIR) + "/examples/cornell.lua",
                                      {"width=64", "height=64", "spp=1", "renderers=5"})
                          .number("first_tile_seconds"));
  }

  std::printf("lightfarm farm benchmark: Cornell box, %d spp, %d runs (cores %s; pinned runs on %s)\n", spp, runs,
              all_cores.c_str(), one_core.c_str());
  lf::Value::Map doc{{"benchmark", "farm"}, {"scene", "cornell"}, {"spp", spp}, {"runs", runs}};
  for (const auto& c : cases) {
    const Series& s = series[c.label];
    const bool heavy = c.label == "pathtrace";
    std::printf("\n%s (%s), %dx%d — M samples/s, medians\n", c.label.c_str(), c.lua_params.c_str(), c.size, c.size);
    std::printf("  bare loop, 1 thread %.3f | 2 threads %.3f | farm 1+1 %.3f | farm 2+2 %.3f\n",
                bench::median(s.bare1) / 1e6, bench::median(s.bare2) / 1e6, bench::median(s.farm11) / 1e6,
                bench::median(s.farm22) / 1e6);
    std::printf("  farm 2+2 pinned to 1 core %.3f | to 2 cores %.3f\n", bench::median(s.pinned1) / 1e6,
                bench::median(s.pinned2) / 1e6);
    const FarmFigures& f = s.last11;
    std::printf("  CPU-seconds of the last farm 1+1: %.2f in %.2f s wall (director %.2f, renderer %.2f, %s %.2f)\n",
                f.cpu_seconds, f.wall, f.director_cpu, f.renderers_cpu, c.label.c_str(), f.lightops_cpu);
    const FarmFigures& g = s.last22;
    // The pool is dispatched by its renderers (no multiplexer process) unless a script asks for one.
    char multiplexer[48] = "";
    if (g.multiplexer_cpu > 0) std::snprintf(multiplexer, sizeof multiplexer, "multiplexer %.2f, ", g.multiplexer_cpu);
    std::printf("  CPU-seconds of the last farm 2+2: %.2f in %.2f s wall (director %.2f, renderers %.2f, %sreplicas %.2f)\n",
                g.cpu_seconds, g.wall, g.director_cpu, g.renderers_cpu, multiplexer, g.lightops_cpu);
    print_spread("farm 1+1 / bare 1 thread (render phase)", s.overhead, heavy ? "" : "   goal >= 0.85");
    print_spread("CPU efficiency: farm 1+1 per CPU-s / bare", s.efficiency,
                 heavy ? "   goal >= 0.95" : "   goal >= 0.7 (whole run, all processes)");
    print_spread("farm 2+2 / bare 2 threads", s.versus_bare2, heavy ? "   goal >= 0.95" : "   goal >= 0.85");
    print_spread("core scaling: pinned 2 cores / 1 core", s.scaling, heavy ? "   goal >= 1.8" : "   goal >= 1.6");
    doc[c.label] = lf::Value::Map{
        {"size", c.size},
        {"samples_per_second",
         lf::Value::Map{{"bare_1_thread", spread_value(s.bare1)}, {"bare_2_threads", spread_value(s.bare2)},
                        {"farm_1_1", spread_value(s.farm11)}, {"farm_2_2", spread_value(s.farm22)},
                        {"farm_2_2_pinned_1_core", spread_value(s.pinned1)},
                        {"farm_2_2_pinned_2_cores", spread_value(s.pinned2)},
                        {"farm_1_1_per_cpu_second", spread_value(s.farm11_cpu)}}},
        {"ratios", lf::Value::Map{{"farm_1_1_over_bare_1", spread_value(s.overhead)},
                                  {"cpu_efficiency", spread_value(s.efficiency)},
                                  {"farm_2_2_over_bare_2", spread_value(s.versus_bare2)},
                                  {"core_scaling", spread_value(s.scaling)}}},
        {"last_farm_1_1_cpu_seconds",
         lf::Value::Map{{"total", f.cpu_seconds}, {"director", f.director_cpu}, {"renderers", f.renderers_cpu},
                        {"lightops", f.lightops_cpu}, {"wall", f.wall}}},
        {"last_farm_2_2_cpu_seconds",
         lf::Value::Map{{"total", g.cpu_seconds}, {"director", g.director_cpu}, {"renderers", g.renderers_cpu},
                        {"multiplexer", g.multiplexer_cpu}, {"lightops", g.lightops_cpu}, {"wall", g.wall}}}};
  }
  std::printf("\nstart-up: launch to first tile, 6 actors: median %.3f s (goal < 0.5 s)\n", bench::median(startup));
  doc["startup_first_tile_seconds"] = spread_value(startup);
  std::ofstream(json_path) << lf::to_json(lf::Value(doc), 2) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
