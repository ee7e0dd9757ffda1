// Farm benchmarks for the foundation (issue 2): framework overhead, renderer scaling, start-up.
// Prints a table and writes JSON. Times are medians of several runs; goals are ratios measured in one run, because
// this 2-core machine is noisy.
//
//   build/bench/farm_bench [--json FILE] [--runs N] [--size PIXELS] [--spp N]
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/camera.hpp"
#include "render/lightop_registry.hpp"
#include "render/tile_kernel.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

using bench::median;

struct FarmRun {
  double samples_per_second = 0;  // render phase
  double first_tile_seconds = 0;
  double cpu_seconds = 0;
};

FarmRun run_farm(const std::vector<std::string>& sets) {
  auto r = bench::run_farm(std::string(LIGHTFARM_SOURCE_DIR) + "/examples/cornell.lua", sets);
  return FarmRun{r.number("render_samples_per_second"), r.number("first_tile_seconds"), r.cpu_seconds};
}

// The same work as a farm of one renderer and one direct LightOp, in one process, no messages: trace a tile, shade
// its points with the same LightOp class, resolve. Returns samples per second.
double bare_loop(int size, int spp, int light_samples) {
  auto scene = lf::Scene::builtin("cornell");
  lf::RayTracer tracer(*scene);
  lf::ImageSpec image;
  image.width = image.height = size;
  image.spp = spp;
  lf::Camera camera(lf::CameraSpec{}, size, size);
  auto op = lf::create_lightop(*lf::find_lightop_kind("direct"),
                               lf::ParamTable(lf::Value::Map{{"light_samples", light_samples}}, "direct"));
  lf::LocalInputs none;
  lf::run_to_completion(op->setup(lf::SceneContext{&*scene, &tracer}, none));
  lf::TileWork work;
  std::vector<lf::RGB> radiance, pixels;
  double checksum = 0;
  auto t0 = Clock::now();
  for (const auto& tile : lf::make_tiles(size, size, image.tile)) {
    lf::trace_tile(*scene, tracer, camera, image, tile, work);
    radiance.assign(work.points.size(), {});
    lf::run_to_completion(op->shade(work.points, radiance, none));
    lf::resolve_tile(work, radiance, pixels);
    checksum += pixels[0].x;
  }
  double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  if (checksum < 0) std::puts("");  // keep the work observable
  return static_cast<double>(size) * size * spp / secs;
}

}  // namespace

int main(int argc, char** argv) {
  std::string json_path = "bench-farm.json";
  int runs = 3, size = 512, spp = 16, light_samples = 2;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--size") size = std::atoi(argv[i + 1]);
    else if (a == "--spp") spp = std::atoi(argv[i + 1]);
  }
  const std::vector<std::string> common{"width=" + std::to_string(size), "height=" + std::to_string(size),
                                        "spp=" + std::to_string(spp), "light_samples=" + std::to_string(light_samples)};
  auto with = [&](std::string extra) {
    auto v = common;
    v.push_back(std::move(extra));
    return v;
  };

  std::vector<double> bare, farm1, farm2, farm1_cpu_rate, startup;
  for (int r = 0; r < runs; ++r) {
    // Interleaved so drift in machine load hits every configuration alike.
    bare.push_back(bare_loop(size, spp, light_samples));
    FarmRun one = run_farm(with("renderers=1"));
    farm1.push_back(one.samples_per_second);
    farm1_cpu_rate.push_back(static_cast<double>(size) * size * spp / one.cpu_seconds);
    farm2.push_back(run_farm(with("renderers=2")).samples_per_second);
    // Start-up: a 6-actor farm (5 renderers + direct), small image so the first tile is the first thing done.
    startup.push_back(run_farm({"width=64", "height=64", "spp=1", "renderers=5"}).first_tile_seconds);
  }
  const double b = median(bare), f1 = median(farm1), f2 = median(farm2), s = median(startup);
  const double f1cpu = median(farm1_cpu_rate);

  std::printf("lightfarm farm benchmark: Cornell box %dx%d, %d spp, direct light_samples=%d, median of %d runs\n\n",
              size, size, spp, light_samples, runs);
  std::printf("%-44s %14s\n", "configuration", "M samples/s");
  std::printf("%-44s %14.3f\n", "bare single-process loop (same kernel, same op)", b / 1e6);
  std::printf("%-44s %14.3f\n", "farm: 1 renderer + 1 direct (render phase)", f1 / 1e6);
  std::printf("%-44s %14.3f\n", "farm: 2 renderers + 1 direct (render phase)", f2 / 1e6);
  std::printf("%-44s %14.3f\n", "farm: 1+1, per CPU-second of all processes", f1cpu / 1e6);
  std::printf("\n%-44s %14.3f   (goal >= 0.85)\n", "overhead: farm(1+1) / bare", f1 / b);
  // Whole-run CPU of every process (start-up, scene and BVH in each, the director) over render samples: what the farm
  // costs beyond the bare loop's one busy core.
  std::printf("%-44s %14.3f   (whole run, all processes)\n", "CPU efficiency: farm per CPU-s / bare", f1cpu / b);
  std::printf("%-44s %14.3f   (goal >= 1.8 with 2 LightOp replicas, issue 4)\n", "scaling: 2 renderers / 1 renderer",
              f2 / f1);
  std::printf("%-44s %14.3f s (goal < 0.5 s)\n", "start-up: launch to first tile, 6 actors", s);

  lf::Value doc = lf::Value::Map{
      {"benchmark", "farm"},
      {"scene", "cornell"},
      {"width", size},
      {"spp", spp},
      {"light_samples", light_samples},
      {"runs", runs},
      {"samples_per_second", lf::Value::Map{{"bare", b}, {"farm_1_renderer", f1}, {"farm_2_renderers", f2},
                                            {"farm_1_renderer_per_cpu_second", f1cpu}}},
      {"ratios", lf::Value::Map{{"farm_over_bare", f1 / b}, {"farm_cpu_over_bare", f1cpu / b},
                                {"two_over_one_renderer", f2 / f1}}},
      {"startup_first_tile_seconds", s},
      {"raw", lf::Value::Map{{"bare", lf::Value::Array(bare.begin(), bare.end())},
                             {"farm_1", lf::Value::Array(farm1.begin(), farm1.end())},
                             {"farm_2", lf::Value::Array(farm2.begin(), farm2.end())},
                             {"startup", lf::Value::Array(startup.begin(), startup.end())}}}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
