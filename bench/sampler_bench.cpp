// Error per sample of the two samplers: McGuire's empty Cornell box (CornellBox-Empty-RG in
// ../shared/scenes), path traced to depth 12 by a farm of 2 renderers and a pool of 2 `pathtrace`, with
// image { sampler = "independent" } and "sobol" at 4..256 spp; relative RMSE (per pixel, over the reference's mean,
// the light's pixels left out) against a 4096-spp independent reference made with another seed and kept between
// runs (bench-sampler-reference-SIZE.exr). Prints error and wall time per sample count, the error ratio, and how
// many Sobol samples reach the independent sampler's 256-spp error (log-log interpolation). Then the cost of a
// sample alone, without the farm's noise: the bare single-thread loop (trace, shade with pathtrace, resolve) with
// each sampler, interleaved, --runs times; the median time ratio with its spread. Writes bench-sampler.json.
//
//   build/bench/sampler_bench [--size PIXELS] [--reference-spp N] [--runs N] [--json FILE]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bare_frame.hpp"
#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "bench/image_error.hpp"
#include "render/tracing/camera.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/tile_kernel.hpp"

namespace {

// Seconds for one frame of the bare loop (bench/bare_frame.hpp) with this sampler.
double bare_frame(const lf::Scene& scene, const lf::RayTracer& tracer, const char* sampler, int size, int spp) {
  return bench::bare_pathtrace_frame(scene, tracer, bench::empty_cornell_camera(), sampler, size, spp).seconds;
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/sampler_bench [--size PIXELS] [--reference-spp N] [--runs N] [--json FILE]",
                            {"--size", "--reference-spp", "--runs", "--json"});
  int size = 128, reference_spp = 4096, runs = 5;
  std::string json_path = "bench-sampler.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") size = std::atoi(argv[i + 1]);
    else if (a == "--reference-spp") reference_spp = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
  }
  const std::string obj = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/cornell_box_mcguire/CornellBox-Empty-RG.obj";
  if (!bench::fs::exists(obj)) {
    std::printf("no %s: nothing to measure\n", obj.c_str());
    return 0;
  }
  const std::string script = bench::temp_script(
      "sampler.lua", "scene { file = \"" + obj + "\" }\n"
                     "camera { eye = {0, 1, 3.4}, at = {0, 1, 0}, fov = 40 }\n"
                     "image { width = param(\"size\", 128), height = param(\"size\", 128), spp = param(\"spp\", 16),\n"
                     "        sampler = param(\"sampler\", \"independent\") }\n"
                     "local paths = lightop \"pathtrace\" { max_depth = 12, seed = param(\"seed\", 0) }\n"
                     "renderers { count = 2, lighting = multiplexer { paths, replicas = 2 } }\n");
  const std::string s = std::to_string(size);
  const std::string reference_path = "bench-sampler-reference-" + s + ".exr";
  lf::Image reference;
  if (auto kept = lf::read_image(reference_path); kept && kept->width == size) {
    reference = *kept;
    std::printf("reference: %s (kept)\n", reference_path.c_str());
  } else {
    double t = 0;
    reference = bench::render_image(script, {"size=" + s, "spp=" + std::to_string(reference_spp), "seed=7"}, reference_path, t);
    std::printf("reference: independent, seed 7, %d spp, %.1f s\n", reference_spp, t);
  }
  const std::string out = (bench::fs::temp_directory_path() / ("lightfarm-sampler-" + std::to_string(::getpid()) + ".exr")).string();
  struct Row {
    int spp;
    double error[2], seconds[2];
  };
  std::vector<Row> rows;
  const char* kinds[2] = {"independent", "sobol"};
  for (int spp : {4, 16, 64, 256}) {
    Row r{spp, {}, {}};
    for (int k = 0; k < 2; ++k)
      r.error[k] = bench::relative_rmse(bench::render_image(script, {"size=" + s, "spp=" + std::to_string(spp), std::string("sampler=") + kinds[k]},
                                        out, r.seconds[k]),
                                 reference);
    rows.push_back(r);
  }
  bench::fs::remove(out);
  std::printf("\nempty Cornell box (CornellBox-Empty-RG), %dx%d, pathtrace depth 12, 2 renderers + pool of 2\n", size, size);
  std::printf("%6s %14s %10s %14s %10s %12s\n", "spp", "independent", "seconds", "sobol", "seconds", "error ratio");
  lf::Value::Array table;
  for (const Row& r : rows) {
    std::printf("%6d %14.4f %10.2f %14.4f %10.2f %12.2f\n", r.spp, r.error[0], r.seconds[0], r.error[1], r.seconds[1],
                r.error[0] / r.error[1]);
    table.push_back(lf::Value::Map{{"spp", r.spp}, {"rmse_independent", r.error[0]}, {"seconds_independent", r.seconds[0]},
                                   {"rmse_sobol", r.error[1]}, {"seconds_sobol", r.seconds[1]}});
  }
  // Sobol samples for the independent sampler's 256-spp error: log-log interpolation along Sobol's rows.
  const double target = rows.back().error[0];
  double needed = rows.back().spp;
  for (size_t i = 0; i + 1 < rows.size(); ++i)
    if (rows[i].error[1] >= target && rows[i + 1].error[1] <= target) {
      const double t = std::log(rows[i].error[1] / target) / std::log(rows[i].error[1] / rows[i + 1].error[1]);
      needed = rows[i].spp * std::pow(static_cast<double>(rows[i + 1].spp) / rows[i].spp, t);
    }
  std::printf("\nSobol reaches the independent sampler's 256-spp error (%.4f) at about %.0f spp (%.2fx fewer samples)\n",
              target, needed, 256.0 / needed);

  // The cost of a sample: one process, one thread, no messages; the two samplers interleaved.
  auto scene = lf::Scene::load_obj(obj);
  if (!scene) {
    std::printf("cannot load %s: %s\n", obj.c_str(), scene.error().message.c_str());
    return 1;
  }
  lf::RayTracer tracer(*scene);
  std::vector<double> ratios, independent_s, sobol_s;
  for (int r = 0; r < runs; ++r) {
    independent_s.push_back(bare_frame(*scene, tracer, "independent", size, 64));
    sobol_s.push_back(bare_frame(*scene, tracer, "sobol", size, 64));
    ratios.push_back(sobol_s.back() / independent_s.back());
  }
  const auto cost = bench::spread(ratios);
  std::printf("\ncost per sample, bare single-thread loop (%dx%d, 64 spp, %d runs): independent %.3f s, sobol %.3f s "
              "(medians); sobol / independent time: median %.3f (min %.3f, max %.3f)\n",
              size, size, runs, bench::median(independent_s), bench::median(sobol_s), cost.median, cost.min, cost.max);
  const double equal_error_time = cost.median * needed / 256.0;
  std::printf("time for the independent sampler's 256-spp error, sobol / independent: %.2f\n", equal_error_time);
  lf::Value doc = lf::Value::Map{{"benchmark", "sampler"}, {"size", size}, {"reference_spp", reference_spp},
                                 {"rows", std::move(table)}, {"sobol_spp_for_independent_256", needed},
                                 {"bare_loop_time_ratio", cost.to_value()},
                                 {"time_for_equal_error_ratio", equal_error_time}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
