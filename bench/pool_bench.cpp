// Pool and packet benchmarks: async packets vs synchronous single points, least_loaded vs round_robin
// with one slowed replica, and renderer / replica scaling. Prints a table and writes JSON; medians of several
// runs, ratios measured in the same run.
//
//   build/bench/pool_bench [--json FILE] [--runs N]
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "core/value.hpp"

using bench::median;

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/pool_bench [--json FILE] [--runs N]",
                            {"--json", "--runs"});
  std::string json_path = "bench-pool.json";
  int runs = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
  }
  const std::string source = LIGHTFARM_SOURCE_DIR;
  const std::string cornell = source + "/examples/cornell.lua";
  const std::string pool = source + "/examples/cornell_pool.lua";
  const std::string slowed = bench::temp_script("slowed.lua", R"(
scene { builtin = "cornell" }
image { width = 256, height = 256, spp = 16, output = "slowed.exr" }
local direct = multiplexer { lightop "direct" { light_samples = 2 }, replicas = 2,
                             strategy = param("strategy", "least_loaded"), slowdown = { 4, 1 } }
renderers { count = 2, lighting = direct, window = 8 }
)");

  std::vector<double> async_t, sync_t, async_msgs, sync_msgs, async_req, sync_req;
  std::vector<double> ll_t, rr_t;
  std::vector<double> r1, r2, p1, p2, shoot1, shoot2, setup1, setup2, exchange2;
  // Photon shooting alone: a photon map pool and nothing else, on a tiny image; the photon map reports how long
  // its share took (the slowest replica counts), and the exchange of shares apart.
  const std::string photons = bench::temp_script("photons.lua", R"(
scene  { builtin = "cornell_glass" }
image  { width = 16, height = 16, spp = 1, output = "photons.exr" }
local caustics = lightop "photonmap" { photons = 4000000, k = 100 }
if param("replicas", 1) > 1 then caustics = multiplexer { caustics, replicas = param("replicas", 1) } end
renderers { count = 1, lighting = caustics }
)");
  auto slowest = [](const bench::FarmRun& run, const char* key) {
    auto v = bench::json_numbers(run.stats, key);
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  };
  const std::vector<std::string> tiny{"width=48", "height=48", "spp=4", "renderers=1"};
  auto with = [](std::vector<std::string> v, const std::string& extra) {
    v.push_back(extra);
    return v;
  };
  for (int i = 0; i < runs; ++i) {
    auto a = bench::run_farm(cornell, with(tiny, "mode=async"));
    auto s = bench::run_farm(cornell, with(tiny, "mode=sync"));
    async_t.push_back(a.number("render_seconds"));
    sync_t.push_back(s.number("render_seconds"));
    async_msgs.push_back(a.number("messages_sent"));
    sync_msgs.push_back(s.number("messages_sent"));
    async_req.push_back(a.number("renderer_shading_requests"));
    sync_req.push_back(s.number("renderer_shading_requests"));

    ll_t.push_back(bench::run_farm(slowed, {"strategy=least_loaded"}).number("render_seconds"));
    rr_t.push_back(bench::run_farm(slowed, {"strategy=round_robin"}).number("render_seconds"));

    const auto one = bench::run_farm(photons, {"replicas=1"}), two = bench::run_farm(photons, {"replicas=2"});
    shoot1.push_back(slowest(one, "shoot_seconds"));
    shoot2.push_back(slowest(two, "shoot_seconds"));
    setup1.push_back(one.phase("setup"));
    setup2.push_back(two.phase("setup"));
    exchange2.push_back(slowest(two, "exchange_seconds"));

    const std::vector<std::string> scale{"width=384", "height=384", "spp=16"};
    r1.push_back(bench::run_farm(pool, with(with(scale, "renderers=1"), "replicas=2")).number("render_samples_per_second"));
    r2.push_back(bench::run_farm(pool, with(with(scale, "renderers=2"), "replicas=2")).number("render_samples_per_second"));
    p1.push_back(bench::run_farm(pool, with(with(scale, "renderers=2"), "replicas=1")).number("render_samples_per_second"));
    p2.push_back(bench::run_farm(pool, with(with(scale, "renderers=2"), "replicas=2")).number("render_samples_per_second"));
  }
  const double at = median(async_t), st = median(sync_t), am = median(async_msgs), sm = median(sync_msgs);
  const double ar = median(async_req), sr = median(sync_req);
  const double ll = median(ll_t), rr = median(rr_t);

  std::printf("lightfarm pool benchmark, median of %d runs\n\n", runs);
  std::printf("async packets vs synchronous single points (Cornell 48x48, 4 spp, 1 renderer, direct):\n");
  std::printf("  %-10s %12s %16s %14s\n", "mode", "render s", "shading requests", "messages sent");
  std::printf("  %-10s %12.3f %16.0f %14.0f\n", "async", at, ar, am);
  std::printf("  %-10s %12.3f %16.0f %14.0f\n", "sync", st, sr, sm);
  std::printf("  messages: sync / async = %.0fx (goal >= 100x); time: async / sync = %.3f (goal <= 0.5)\n\n", sm / am,
              at / st);
  std::printf("one replica slowed 4x (Cornell 256x256, 16 spp, 2 renderers with window 8, 2 replicas):\n");
  std::vector<double> ll_speedup, shoot_speedup;
  for (size_t i = 0; i < ll_t.size(); ++i) {
    ll_speedup.push_back(rr_t[i] / ll_t[i]);
    shoot_speedup.push_back(shoot1[i] / shoot2[i]);
  }
  const auto lls = bench::spread(ll_speedup), shs = bench::spread(shoot_speedup);
  std::printf("  least_loaded %.3f s, round_robin %.3f s: least_loaded is %.2fx faster (per run: min %.2f, median "
              "%.2f, max %.2f; goal >= 1.3x)\n\n",
              ll, rr, rr / ll, lls.min, lls.median, lls.max);
  std::printf("scaling (Cornell 384x384, 16 spp, render-phase M samples/s):\n");
  std::printf("  renderers 1 -> 2 (2 replicas): %.3f -> %.3f = %.2fx\n", median(r1) / 1e6, median(r2) / 1e6,
              median(r2) / median(r1));
  std::printf("  replicas  1 -> 2 (2 renderers): %.3f -> %.3f = %.2fx\n", median(p1) / 1e6, median(p2) / 1e6,
              median(p2) / median(p1));
  std::printf("\nphoton map alone (cornell_glass scene, 4 M photons):\n");
  std::printf("  shooting: 1 replica %.3f s, 2 replicas %.3f s (the slower): %.2fx faster (goal >= 1.7x)\n",
              median(shoot1), median(shoot2), median(shoot1) / median(shoot2));
  std::printf("  shooting speed-up per run: min %.2f, median %.2f, max %.2f\n", shs.min, shs.median, shs.max);
  std::printf("  whole setup phase: 1 replica %.3f s, 2 replicas %.3f s (%.2fx); the 2 replicas' exchange of shares "
              "%.3f s\n",
              median(setup1), median(setup2), median(setup1) / median(setup2), median(exchange2));

  lf::Value doc = lf::Value::Map{
      {"benchmark", "pool"},
      {"runs", runs},
      {"async_vs_sync", lf::Value::Map{{"async_render_seconds", at}, {"sync_render_seconds", st},
                                       {"async_messages", am}, {"sync_messages", sm},
                                       {"async_shading_requests", ar}, {"sync_shading_requests", sr},
                                       {"message_ratio", sm / am}, {"time_ratio", at / st}}},
      {"slowed_replica", lf::Value::Map{{"least_loaded_seconds", ll}, {"round_robin_seconds", rr},
                                        {"speedup", rr / ll}, {"speedup_per_run", lls.to_value()}}},
      {"photon_shooting_speedup_per_run", shs.to_value()},
      {"scaling", lf::Value::Map{{"renderers_1", median(r1)}, {"renderers_2", median(r2)},
                                 {"replicas_1", median(p1)}, {"replicas_2", median(p2)}}},
      {"photon_shooting_seconds", lf::Value::Map{{"replicas_1", median(shoot1)}, {"replicas_2", median(shoot2)}}},
      {"photon_setup_seconds", lf::Value::Map{{"replicas_1", median(setup1)}, {"replicas_2", median(setup2)},
                                              {"exchange_2", median(exchange2)}}}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
