// The path kernel alone: one process, one thread, no farm — trace a tile, shade its points with
// `pathtrace` (depth 12), resolve — on McGuire's empty Cornell box (the peer comparison's scene, Sobol sampler) and on
// the built-in Cornell box (farm_bench's, with its glass and mirror). Prints paths per second (median, min, max of
// --runs interleaved frames) and a hash of each frame's pixels, so that a change to the kernel that must not change
// the image can be checked bit for bit: the hash is the same on every run and before and after such a change.
// Writes bench-kernel.json.
//
//   build/bench/kernel_bench [--runs N] [--size PIXELS] [--spp N] [--json FILE]
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bare_frame.hpp"
#include "bench/bench_util.hpp"
#include "core/value.hpp"

namespace {

struct Case {
  std::string label;
  std::unique_ptr<lf::Scene> scene;
  lf::CameraSpec camera;
};

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/kernel_bench [--runs N] [--size PIXELS] [--spp N] [--json FILE]",
                            {"--runs", "--size", "--spp", "--json"});
  int size = 128, spp = 64, runs = 5;
  std::string json_path = "bench-kernel.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") size = std::atoi(argv[i + 1]);
    else if (a == "--spp") spp = std::atoi(argv[i + 1]);
    else if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  std::vector<Case> cases;
  const std::string obj = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/cornell_box_mcguire/CornellBox-Empty-RG.obj";
  if (bench::fs::exists(obj)) {
    auto scene = lf::Scene::load_obj(obj);
    if (!scene) {
      std::printf("cannot load %s: %s\n", obj.c_str(), scene.error().message.c_str());
      return 1;
    }
    cases.push_back({"empty Cornell box (sobol)", std::make_unique<lf::Scene>(std::move(*scene)), bench::empty_cornell_camera()});
  }
  {
    lf::CameraSpec cam;  // the Cornell box's default camera, as farm_bench's scripts
    cases.push_back({"built-in Cornell box (sobol)", std::make_unique<lf::Scene>(std::move(*lf::Scene::builtin("cornell"))), cam});
  }
  std::printf("the path kernel alone: pathtrace depth 12, %dx%d, %d spp, 1 thread, %d runs interleaved\n", size, size,
              spp, runs);
  lf::Value::Array out;
  std::vector<std::unique_ptr<lf::RayTracer>> tracers;
  for (auto& c : cases) tracers.push_back(std::make_unique<lf::RayTracer>(*c.scene));
  std::vector<std::vector<double>> rates(cases.size());
  std::vector<uint64_t> hashes(cases.size(), 0);
  std::vector<bool> stable(cases.size(), true);
  for (int r = 0; r < runs; ++r)
    for (size_t i = 0; i < cases.size(); ++i) {
      const bench::BareFrame f =
          bench::bare_pathtrace_frame(*cases[i].scene, *tracers[i], cases[i].camera, "sobol", size, spp);
      rates[i].push_back(static_cast<double>(size) * size * spp / f.seconds);
      if (r > 0 && f.hash != hashes[i]) stable[i] = false;
      hashes[i] = f.hash;
    }
  for (size_t i = 0; i < cases.size(); ++i) {
    const auto s = bench::spread(rates[i]);
    char hash[17];
    std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(hashes[i]));
    std::printf("  %-30s %7.3f M paths/s (min %.3f, max %.3f)   image %s%s\n", cases[i].label.c_str(), s.median / 1e6,
                s.min / 1e6, s.max / 1e6, hash, stable[i] ? "" : " (NOT the same on every run)");
    out.push_back(lf::Value::Map{{"case", cases[i].label},
                                 {"paths_per_second", s.to_value()},
                                 {"image_hash", std::string(hash)}});
  }
  std::ofstream(json_path) << lf::to_json(lf::Value::Map{{"size", size}, {"spp", spp}, {"runs", runs}, {"cases", out}}) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
