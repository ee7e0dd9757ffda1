// Quality per time on cornell_glass: relative RMSE against a high-sample path-traced reference versus
// wall time, for `pathtrace` alone and for two lighting networks — examples/cornell_glass.lua (irradiance caches
// over direct light) and examples/cornell_glass_radiosity.lua (one cache over a radiosity solution) — at several
// sample counts. Goal: a network reaches the path tracer's final RMSE in at most a third of the path tracer's time.
//
// RMSE is per pixel, relative to the reference's mean, over every pixel but the light's (both add the same
// emission). A second figure also leaves out the pixels next to the light: their error is how much of the light
// a pixel's camera samples happened to cover, which depends on the sample count alone, not on the lighting.
//
//   build/bench/quality_bench [--json FILE] [--size PIXELS] [--reference-spp N] [--reference FILE.exr]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "bench/image_error.hpp"

namespace {

struct Point {
  std::string method;
  int spp;
  double seconds, rmse, rmse_ring;
};

lf::Image run(const std::string& script, const std::vector<std::string>& sets, double& seconds) {
  const std::string out =
      (bench::fs::temp_directory_path() / ("lightfarm-quality-" + std::to_string(::getpid()) + ".exr")).string();
  lf::Image img = bench::render_image(script, sets, out, seconds);
  bench::fs::remove(out);
  return img;
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/quality_bench [--json FILE] [--size PIXELS] [--reference-spp N]"
                            " [--reference FILE.exr]",
                            {"--json", "--size", "--reference-spp", "--reference"});
  std::string json_path = "bench-quality.json";
  int size = 512, reference_spp = 2048;
  std::string reference_file;  // --reference: reuse this image if it exists, else render and keep it there
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--size") size = std::atoi(argv[i + 1]);
    else if (a == "--reference-spp") reference_spp = std::atoi(argv[i + 1]);
    else if (a == "--reference") reference_file = argv[i + 1];
  }
  const std::string src = LIGHTFARM_SOURCE_DIR;
  const std::string pt = src + "/tests/scripts/glass_pathtrace.lua";
  const std::string s = std::to_string(size);
  double t = 0;
  lf::Image reference;
  if (auto kept = reference_file.empty() ? lf::Result<lf::Image>(lf::make_error("none")) : lf::read_image(reference_file);
      kept && kept->width == size && kept->height == size) {
    reference = *kept;
    std::printf("reference: %s (%dx%d, kept from an earlier run)\n\n", reference_file.c_str(), size, size);
  } else {
    reference = run(pt, {"size=" + s, "spp=" + std::to_string(reference_spp)}, t);
    if (!reference_file.empty()) (void)lf::write_image(reference, reference_file);
    std::printf("reference: pathtrace, %dx%d, %d spp, %.1f s\n\n", size, size, reference_spp, t);
  }

  std::vector<Point> path, networks;
  for (int spp : {16, 64, 256}) {
    lf::Image img = run(pt, {"size=" + s, "spp=" + std::to_string(spp)}, t);
    path.push_back({"pathtrace", spp, t, bench::relative_rmse(img, reference), bench::relative_rmse(img, reference, true)});
  }
  const std::vector<std::pair<std::string, std::string>> nets{
      {"caches", src + "/examples/cornell_glass.lua"}, {"radiosity", src + "/examples/cornell_glass_radiosity.lua"}};
  for (const auto& [name, script] : nets)
    for (int spp : {4, 16}) {
      std::vector<std::string> sets{"width=" + s, "height=" + s, "spp=" + std::to_string(spp), "photons=300000"};
      if (name == "caches") sets.push_back("prepass=4000");  // its area-placed first cache
      lf::Image img = run(script, sets, t);
      networks.push_back({name, spp, t, bench::relative_rmse(img, reference), bench::relative_rmse(img, reference, true)});
    }
  std::printf("%-10s %6s %10s %10s %16s\n", "method", "spp", "seconds", "rel. RMSE", "without light rim");
  for (const auto* list : {&path, &networks})
    for (const auto& p : *list)
      std::printf("%-10s %6d %10.2f %10.3f %16.3f\n", p.method.c_str(), p.spp, p.seconds, p.rmse, p.rmse_ring);

  const Point& final_pt = path.back();
  lf::Value::Array reach;
  for (const auto& [name, script] : nets) {
    for (bool ring : {false, true}) {
      const double target = ring ? final_pt.rmse_ring : final_pt.rmse;
      double at = -1;
      for (const auto& p : networks)
        if (p.method == name && (ring ? p.rmse_ring : p.rmse) <= target) {
          at = p.seconds;
          break;
        }
      const char* metric = ring ? "without light rim" : "rel. RMSE";
      if (at > 0)
        std::printf("%-9s reaches pathtrace's final %s %.3f in %.2f s = %.2f of pathtrace's %.2f s (goal <= 0.33)\n",
                    name.c_str(), metric, target, at, at / final_pt.seconds, final_pt.seconds);
      else
        std::printf("%-9s does not reach pathtrace's final %s %.3f\n", name.c_str(), metric, target);
      reach.push_back(lf::Value::Map{{"network", name}, {"metric", metric}, {"seconds", at},
                                     {"fraction_of_pathtrace", at > 0 ? at / final_pt.seconds : -1.0}});
    }
  }

  auto to_array = [](const std::vector<Point>& v) {
    lf::Value::Array a;
    for (const auto& p : v)
      a.push_back(lf::Value::Map{{"method", p.method}, {"spp", p.spp}, {"seconds", p.seconds}, {"rmse", p.rmse},
                                 {"rmse_without_light_rim", p.rmse_ring}});
    return a;
  };
  lf::Value doc = lf::Value::Map{{"benchmark", "quality"}, {"size", size}, {"reference_spp", reference_spp},
                                 {"pathtrace", to_array(path)}, {"networks", to_array(networks)},
                                 {"reach", std::move(reach)}, {"pathtrace_final_seconds", final_pt.seconds}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
