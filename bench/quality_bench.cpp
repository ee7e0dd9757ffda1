// Quality per time on cornell_glass (issue 3): relative RMSE against a high-sample path-traced reference versus
// wall time, for `pathtrace` alone and for the lighting network of examples/cornell_glass.lua, at several sample
// counts. Goal: the network reaches the path tracer's final RMSE in at most a third of the path tracer's time.
//
//   build/bench/quality_bench [--json FILE] [--size PIXELS]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/image.hpp"

namespace {

struct Point {
  int spp;
  double seconds, rmse;
};

double relative_rmse(const lf::Image& a, const lf::Image& ref) {
  double se = 0, mean = 0;
  size_t n = 0;
  for (size_t i = 0; i < ref.pixels.size(); ++i) {
    if (ref.pixels[i].x > 1.0f) continue;  // the light: the same emission in both
    const double d = lf::average(a.pixels[i]) - lf::average(ref.pixels[i]);
    se += d * d;
    mean += lf::average(ref.pixels[i]);
    ++n;
  }
  return std::sqrt(se / n) / (mean / n);
}

lf::Image run(const std::string& script, const std::vector<std::string>& sets, double& seconds) {
  const std::string out =
      (bench::fs::temp_directory_path() / ("lightfarm-quality-" + std::to_string(::getpid()) + ".exr")).string();
  seconds = bench::run_farm(script, sets, out).wall_seconds;
  auto img = lf::read_image(out);
  bench::fs::remove(out);
  if (!img) {
    std::fprintf(stderr, "%s\n", img.error().message.c_str());
    std::exit(1);
  }
  return *img;
}

}  // namespace

int main(int argc, char** argv) {
  std::string json_path = "bench-quality.json";
  int size = 48;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--size") size = std::atoi(argv[i + 1]);
  }
  const std::string src = LIGHTFARM_SOURCE_DIR;
  const std::string pt = src + "/tests/scripts/glass_pathtrace.lua", net = src + "/examples/cornell_glass.lua";
  const std::string s = std::to_string(size);
  double t = 0;
  lf::Image reference = run(pt, {"size=" + s, "spp=8192"}, t);
  std::printf("reference: pathtrace, %dx%d, 8192 spp, %.1f s\n\n", size, size, t);

  std::vector<Point> path, network;
  for (int spp : {16, 64, 256, 1024}) {
    lf::Image img = run(pt, {"size=" + s, "spp=" + std::to_string(spp)}, t);
    path.push_back({spp, t, relative_rmse(img, reference)});
  }
  for (int spp : {4, 16, 64}) {
    lf::Image img = run(net, {"width=" + s, "height=" + s, "spp=" + std::to_string(spp), "prepass=4000",
                              "photons=300000"}, t);
    network.push_back({spp, t, relative_rmse(img, reference)});
  }
  std::printf("%-10s %6s %10s %10s\n", "method", "spp", "seconds", "rel. RMSE");
  for (const auto& p : path) std::printf("%-10s %6d %10.2f %10.3f\n", "pathtrace", p.spp, p.seconds, p.rmse);
  for (const auto& p : network) std::printf("%-10s %6d %10.2f %10.3f\n", "network", p.spp, p.seconds, p.rmse);

  const Point& final_pt = path.back();
  double reach = -1;
  for (const auto& p : network)
    if (p.rmse <= final_pt.rmse) {
      reach = p.seconds;
      break;
    }
  if (reach > 0)
    std::printf("\nnetwork reaches pathtrace's final RMSE %.3f in %.2f s = %.2f of pathtrace's %.2f s (goal <= 0.33)\n",
                final_pt.rmse, reach, reach / final_pt.seconds, final_pt.seconds);
  else
    std::printf("\nnetwork does not reach pathtrace's final RMSE %.3f (its best: %.3f): its bias (omitted bounces, "
                "photon-map blur) is above that floor\n",
                final_pt.rmse, network.back().rmse);

  lf::Value::Array pj, nj;
  for (const auto& p : path) pj.push_back(lf::Value::Map{{"spp", p.spp}, {"seconds", p.seconds}, {"rmse", p.rmse}});
  for (const auto& p : network) nj.push_back(lf::Value::Map{{"spp", p.spp}, {"seconds", p.seconds}, {"rmse", p.rmse}});
  lf::Value doc = lf::Value::Map{{"benchmark", "quality"}, {"size", size}, {"pathtrace", pj}, {"network", nj},
                                 {"reach_seconds", reach}, {"pathtrace_final_seconds", final_pt.seconds}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
