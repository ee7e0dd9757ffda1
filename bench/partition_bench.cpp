// A partitioned farm against the whole-scene farm: Lost Empire (../shared/scenes, torches emitting), a
// camera inside the city, 2 renderers and one `pathtrace` (depth 3), its scene whole or split into 2, 3 and 5
// geometry actors (partition { parts = N }). Per split: render time over the whole farm's (median, min, max over
// --runs, interleaved), each part's share of the rays it traced (imbalance = max / mean; goal <= 1.2 with the
// cost-based split), part visits per traced ray, trace requests (the op's and the renderers' camera rays), and the
// bytes between the askers and the parts. The
// images are compared too: every split must give the whole farm's pixels. Writes bench-partition.json.
//
//   build/bench/partition_bench [--runs N] [--size WIDTH] [--spp N] [--json FILE]
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/images/image.hpp"


int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/partition_bench [--runs N] [--size WIDTH] [--spp N] [--json FILE]",
                            {"--runs", "--size", "--spp", "--json"});
  int runs = 3, width = 160, spp = 4;
  std::string json_path = "bench-partition.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--size") width = std::atoi(argv[i + 1]);
    else if (a == "--spp") spp = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  const std::string obj = bench::shared_scene("lost_empire/lost_empire.obj");
  if (obj.empty()) return 0;
  const int height = width * 3 / 4;
  const std::string script = bench::temp_script(
      "partition.lua", "scene { file = \"" + obj + "\" }\n"
                       "material \"Torch\" { emission = {9, 9, 6} }\n"
                       "camera { eye = {-8, 16, 20}, at = {6, 12, 0}, fov = 70 }\n"
                       "image { width = " + std::to_string(width) + ", height = " + std::to_string(height) +
                       ", spp = " + std::to_string(spp) + " }\n"
                       "if param(\"parts\", 0) > 0 then partition { parts = param(\"parts\", 0) } end\n"
                       "renderers { count = 2, lighting = lightop \"pathtrace\" { max_depth = 3 } }\n");
  const int part_counts[3] = {2, 3, 5};
  const std::string whole_image = (bench::fs::temp_directory_path() / "lightfarm-partition-whole.exr").string();
  const std::string split_image = (bench::fs::temp_directory_path() / "lightfarm-partition-split.exr").string();
  struct Split {
    std::vector<double> ratios;
    double imbalance = 0, visits_per_ray = 0, requests = 0, mb_to_parts = 0, mb_from_parts = 0;
    std::vector<double> shares;
    bool same_image = true;
  };
  Split splits[3];
  std::vector<double> whole_seconds;
  for (int r = 0; r < runs; ++r) {
    const auto whole = bench::run_farm(script, {}, whole_image);
    whole_seconds.push_back(whole.number("render_seconds"));
    const auto reference = lf::read_image(whole_image);
    for (int k = 0; k < 3; ++k) {
      const auto split = bench::run_farm(script, {"parts=" + std::to_string(part_counts[k])}, split_image);
      Split& s = splits[k];
      s.ratios.push_back(split.number("render_seconds") / whole_seconds.back());
      const auto image = lf::read_image(split_image);
      s.same_image = s.same_image && reference && image && reference->pixels == image->pixels;
      if (r > 0) continue;  // the counts are the same every run
      const auto rays = bench::json_numbers(split.stats, "rays");
      double total = 0, most = 0;
      for (double v : rays) {
        total += v;
        most = std::max(most, v);
      }
      s.imbalance = rays.empty() ? 0 : most / (total / static_cast<double>(rays.size()));
      for (double v : rays) s.shares.push_back(v / total);
      // Summed over the askers: the op's rays and, since the renderers trace their camera rays through the parts
      // too, theirs.
      auto sum = [&](const char* key) {
        double total = 0;
        for (double v : bench::json_numbers(split.stats, key)) total += v;
        return total;
      };
      s.visits_per_ray = sum("part_visits") / sum("traced_rays");
      s.requests = sum("trace_requests");
      s.mb_to_parts = bench::sum_over_kind(split.stats, "geometry", "bytes_in") / 1e6;
      s.mb_from_parts = bench::sum_over_kind(split.stats, "geometry", "bytes_out") / 1e6;
    }
  }
  std::printf("Lost Empire, %dx%d, %d spp, pathtrace depth 3, 2 renderers; %d runs; whole farm's render phase: median "
              "%.2f s\n",
              width, height, spp, runs, bench::median(whole_seconds));
  lf::Value::Array rows;
  for (int k = 0; k < 3; ++k) {
    const Split& s = splits[k];
    const auto ratio = bench::spread(s.ratios);
    std::printf("  %d parts: render time / whole %.3f (min %.3f, max %.3f); rays per part max / mean %.3f (goal <= "
                "1.2); %.2f part visits per traced ray; %.0f trace requests; %.1f MB to the parts, %.1f MB back; "
                "image %s\n",
                part_counts[k], ratio.median, ratio.min, ratio.max, s.imbalance, s.visits_per_ray, s.requests,
                s.mb_to_parts, s.mb_from_parts, s.same_image ? "identical" : "DIFFERS");
    lf::Value::Array shares;
    for (double v : s.shares) shares.push_back(v);
    rows.push_back(lf::Value::Map{{"parts", part_counts[k]}, {"render_time_over_whole", ratio.to_value()},
                                  {"imbalance_max_over_mean", s.imbalance}, {"ray_share_per_part", std::move(shares)},
                                  {"part_visits_per_traced_ray", s.visits_per_ray}, {"trace_requests", s.requests},
                                  {"mb_to_parts", s.mb_to_parts}, {"mb_from_parts", s.mb_from_parts},
                                  {"image_identical", s.same_image}});
  }
  bench::fs::remove(whole_image);
  bench::fs::remove(split_image);
  lf::Value doc = lf::Value::Map{{"benchmark", "partition"}, {"width", width}, {"height", height}, {"spp", spp},
                                 {"runs", runs}, {"whole_render_seconds", bench::median(whole_seconds)},
                                 {"splits", std::move(rows)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
