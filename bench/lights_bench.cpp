// Many lights: direct light on Lost Empire (examples/lost_empire.lua: 1636 torch triangles and
// the lava), lights chosen through the light tree vs by power alone. For each sample count both are rendered in the
// same run, interleaved, `--runs` times; the figures are the relative RMSE against a high-sample reference (tree,
// kept between runs with --reference) and the seconds of the setup and render phases (median; setup is where the
// learned lights are found, nothing for the others). The figure of merit is the usual efficiency
// 1 / (RMSE² × seconds): how much less time the tree needs for the same noise.
//
// A third variant draws the point on the chosen triangle by its solid angle (light_point = "solid_angle"); a
// fourth mixes the tree with lights learned where the camera looks (light_sampling = "learned",
// render/lights/light_selection.hpp).
//
//   build/bench/lights_bench [--json FILE] [--runs N] [--reference FILE.exr] [--reference-spp N] [--width W]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "render/images/image.hpp"

namespace {

double relative_rmse(const lf::Image& a, const lf::Image& ref) {
  double se = 0, mean = 0;
  for (size_t i = 0; i < ref.pixels.size(); ++i) {
    const double d = lf::average(a.pixels[i]) - lf::average(ref.pixels[i]);
    se += d * d;
    mean += lf::average(ref.pixels[i]);
  }
  const double n = static_cast<double>(ref.pixels.size());
  return std::sqrt(se / n) / (mean / n);
}

struct Render {
  lf::Image image;
  double render_seconds;  // setup and render phases
};

Render render(const std::string& script, const std::vector<std::string>& sets) {
  const std::string out =
      (bench::fs::temp_directory_path() / ("lightfarm-lights-" + std::to_string(::getpid()) + ".exr")).string();
  const bench::FarmRun run = bench::run_farm(script, sets, out);
  auto img = lf::read_image(out);
  bench::fs::remove(out);
  if (!img) {
    std::fprintf(stderr, "%s\n", img.error().message.c_str());
    std::exit(1);
  }
  return {*img, run.phase("setup") + run.phase("render")};
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/lights_bench [--json FILE] [--runs N] [--reference FILE.exr]"
                            " [--reference-spp N] [--width W]",
                            {"--json", "--runs", "--reference", "--reference-spp", "--width"});
  std::string json_path = "bench-lights.json", reference_file;
  int runs = 3, reference_spp = 1024, width = 320;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--json") json_path = argv[i + 1];
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--reference") reference_file = argv[i + 1];
    else if (a == "--reference-spp") reference_spp = std::atoi(argv[i + 1]);
    else if (a == "--width") width = std::atoi(argv[i + 1]);
  }
  const std::string script = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/lost_empire.lua";
  if (!bench::fs::exists(std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/lost_empire/lost_empire.obj")) {
    std::printf("Lost Empire is not in ../shared/scenes: nothing to measure\n");
    return 0;
  }
  const std::string size[2] = {"width=" + std::to_string(width), "height=" + std::to_string(width * 3 / 4)};
  lf::Image reference;
  if (auto kept = reference_file.empty() ? lf::Result<lf::Image>(lf::make_error("none")) : lf::read_image(reference_file)) {
    reference = *kept;
    std::printf("reference: %s (kept from an earlier run)\n", reference_file.c_str());
  } else {
    Render r = render(script, {"spp=" + std::to_string(reference_spp), "light_samples=4", "light_sampling=tree", size[0],
                               size[1]});
    reference = r.image;
    if (!reference_file.empty()) (void)lf::write_image(reference, reference_file);
    std::printf("reference: tree, %d spp x 4 light samples, render %.1f s\n", reference_spp, r.render_seconds);
  }

  std::printf("\n%5s %-7s %10s %10s %10s\n", "spp", "lights", "rel. RMSE", "seconds", "efficiency");
  lf::Value::Array rows;
  std::vector<double> gains, solid_gains, learned_gains;
  for (int spp : {4, 16, 64}) {
    // "solid": the tree's pick, and a point uniform over the solid angle of the chosen triangle (light_point).
    std::vector<double> seconds[4];
    double rmse[4] = {0, 0, 0, 0};
    const char* names[4] = {"tree", "power", "solid", "learned"};
    const char* sampling[4] = {"tree", "power", "tree", "learned"};
    for (int run = 0; run < runs; ++run)
      for (int k = 0; k < 4; ++k) {
        Render r = render(script, {"spp=" + std::to_string(spp), std::string("light_sampling=") + sampling[k],
                                   std::string("light_point=") + (k == 2 ? "solid_angle" : "area"), size[0], size[1]});
        seconds[k].push_back(r.render_seconds);
        rmse[k] = relative_rmse(r.image, reference);  // the same every run: images are deterministic
      }
    double efficiency[4];
    for (int k = 0; k < 4; ++k) {
      const bench::Spread s = bench::spread(seconds[k]);
      efficiency[k] = 1.0 / (rmse[k] * rmse[k] * s.median);
      std::printf("%5d %-7s %10.4f %10.3f %10.1f   (seconds min %.3f max %.3f)\n", spp, names[k], rmse[k], s.median,
                  efficiency[k], s.min, s.max);
      rows.push_back(lf::Value::Map{{"spp", spp}, {"lights", names[k]}, {"relative_rmse", rmse[k]},
                                    {"seconds", s.to_value()}, {"efficiency", efficiency[k]}});
    }
    gains.push_back(efficiency[0] / efficiency[1]);
    solid_gains.push_back(efficiency[2] / efficiency[0]);
    learned_gains.push_back(efficiency[3] / efficiency[0]);
    std::printf("%5d tree / power efficiency %.2f, solid angle / area points %.2f, learned / tree %.2f\n", spp,
                gains.back(), solid_gains.back(), learned_gains.back());
  }
  const bench::Spread g = bench::spread(gains), sg = bench::spread(solid_gains), lg = bench::spread(learned_gains);
  std::printf("\ntree / power efficiency over sample counts: min %.2f median %.2f max %.2f\n", g.min, g.median, g.max);
  std::printf("solid angle / area points (both with the tree): min %.2f median %.2f max %.2f\n", sg.min, sg.median,
              sg.max);
  std::printf("learned lights / tree alone: min %.2f median %.2f max %.2f\n", lg.min, lg.median, lg.max);
  std::ofstream(json_path) << lf::to_json(lf::Value::Map{{"rows", rows}, {"tree_over_power_efficiency", g.to_value()},
                                                         {"solid_angle_over_area_efficiency", sg.to_value()},
                                                         {"learned_over_tree_efficiency", lg.to_value()}},
                                          2)
                           << "\n";
  std::printf("wrote %s\n", json_path.c_str());
}
