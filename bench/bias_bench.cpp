// Bias at full size: every shipped network that says it computes all the light, on the bias matrix
// (tests/bias_matrix.hpp: diffuse, mirror and glass, glossy, glossy everywhere, a floor both diffuse and a mirror),
// against `pathtrace` at a high sample count. tests/unbiased.test.cpp runs the same matrix at 48x48 in ctest; here
// the frame is large enough that a bias of a fraction of a per cent stands above the reference's own noise, and the
// time each network took is printed beside it. Goal: every network's mean within 1 % of the reference's.
//
//   build/bench/bias_bench [--size PIXELS] [--reference-spp N] [--scenes a,b] [--json FILE]
//
// The mean is over the pixels that do not see the light (their emission is the same in both); the block RMSE is
// over 8x8-pixel block means, relative to the reference's mean, so it reads bias in regions rather than noise.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "bench/image_error.hpp"
#include "tests/bias_matrix.hpp"

namespace {

struct Args {
  int size = 256;
  int reference_spp = 4096;
  std::string only;  // comma-separated scene names, or all
  std::string json = "bench-bias.json";
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--size") a.size = std::atoi(argv[i + 1]);
    else if (k == "--reference-spp") a.reference_spp = std::atoi(argv[i + 1]);
    else if (k == "--scenes") a.only = "," + std::string(argv[i + 1]) + ",";
    else if (k == "--json") a.json = argv[i + 1];
  }
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/bias_bench [--size PIXELS] [--reference-spp N] [--scenes a,b] [--json FILE]",
                            {"--size", "--reference-spp", "--scenes", "--json"});
  const Args args = parse(argc, argv);
  const std::string src = LIGHTFARM_SOURCE_DIR;
  const std::string mcguire = bench::shared_scene("cornell_box_mcguire/");
  if (mcguire.empty()) return 0;
  const std::string size = std::to_string(args.size);
  const std::vector<std::string> frame{"width=" + size, "height=" + size};
  std::printf("bias matrix at %dx%d, reference pathtrace at %d spp\n\n", args.size, args.size, args.reference_spp);
  std::printf("%-14s %-18s %8s %8s %8s\n", "scene", "network", "mean", "blocks", "seconds");
  lf::Value::Array rows;
  double worst = 0;
  for (const lf::bias::Scene& scene : lf::bias::scenes(mcguire)) {
    if (!args.only.empty() && args.only.find("," + std::string(scene.name) + ",") == std::string::npos) continue;
    auto script = [&](const char* example, const std::string& tag) {
      const std::string text = lf::bias::with_scene(src + "/examples/" + example, scene);
      if (text.empty()) {
        std::fprintf(stderr, "examples/%s has no scene line to replace\n", example);
        std::exit(1);
      }
      return bench::temp_script(tag + ".lua", text);
    };
    // Its own name: two runs at once (another scene list) must not read each other's image.
    const std::string out =
        (bench::fs::temp_directory_path() / ("lightfarm-bias-" + std::to_string(::getpid()) + ".exr")).string();
    std::vector<std::string> sets = frame;
    sets.push_back("spp=" + std::to_string(args.reference_spp));
    double reference_seconds = 0;
    const lf::Image reference =
        bench::render_image(script("pathtrace.lua", std::string(scene.name) + "_ref"), sets, out, reference_seconds);
    std::printf("%-14s %-18s %8s %8s %8.1f\n", scene.name, "(reference)", "", "", reference_seconds);
    for (const lf::bias::Network& n : lf::bias::networks()) {
      std::vector<std::string> run_sets = frame;
      run_sets.insert(run_sets.end(), n.sets.begin(), n.sets.end());
      const std::string tag = std::string(scene.name) + "_" + n.example;
      double seconds = 0;
      const lf::Image image = bench::render_image(script(n.example, tag), run_sets, out, seconds);
      const lf::bias::Agreement g = lf::bias::agreement(image, reference);
      worst = std::max(worst, std::abs(g.mean - 1));
      std::printf("%-14s %-18s %8.4f %8.4f %8.1f%s\n", scene.name, n.example, g.mean, g.block_rmse, seconds,
                  std::abs(g.mean - 1) > 0.01 ? "   over 1 %" : "");
      lf::Value::Array n_sets;
      for (const auto& s : n.sets) n_sets.emplace_back(s);
      rows.emplace_back(lf::Value::Map{{"scene", scene.name}, {"network", n.example}, {"sets", n_sets},
                                       {"mean", g.mean}, {"block_rmse", g.block_rmse}, {"seconds", seconds}});
    }
    bench::fs::remove(out);
  }
  std::printf("\nlargest |mean - 1|: %.4f (goal <= 0.01)\n", worst);
  const lf::Value doc = lf::Value::Map{{"size", args.size}, {"reference_spp", args.reference_spp}, {"rows", rows},
                                       {"worst_mean_error", worst}};
  std::ofstream(args.json) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", args.json.c_str());
  return 0;
}
