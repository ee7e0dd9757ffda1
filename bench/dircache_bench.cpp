// The directional cache measured like seed 002's Tables 1-3 (issue 14): Lost Empire (../shared/scenes, torches
// emitting), a camera inside the city, a partitioned farm (3 geometry actors, 2 renderers, one `pathtrace` of depth
// 4), at three quality settings, each without and with the directional cache. Per setting and variant: wall time
// (setup and fill included), rays traced through the parts (the paper counts intersection tests, which Embree does
// not report; rays sent to parts are what a partitioned farm pays for), relative RMSE against a high-sample
// reference (kept between runs, bench-dircache-reference-WxH.exr), the diffuse rays split into local / global /
// lookup, the hit ratio lookups / (global + lookups), and the bytes sent to the parts. Goals: hit ratio >= 60.8 %
// at the accurate setting with RMSE <= 1.3x the uncached farm's, and the bytes to the parts at least halved.
// Writes bench-dircache.json.
//
//   build/bench/dircache_bench [--size WIDTH] [--reference-spp N] [--json FILE]
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "bench/image_error.hpp"
#include "core/value.hpp"

int main(int argc, char** argv) {
  int width = 160, reference_spp = 1024;
  std::string json_path = "bench-dircache.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") width = std::atoi(argv[i + 1]);
    else if (a == "--reference-spp") reference_spp = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  const std::string obj = bench::shared_scene("lost_empire/lost_empire.obj");
  if (obj.empty()) return 0;
  const int height = width * 3 / 4;
  const std::string script = bench::temp_script(
      "dircache.lua",
      "scene { file = \"" + obj + "\" }\n"
      "material \"Torch\" { emission = {9, 9, 6}, kd = {0, 0, 0} }\n"  // as examples/lost_empire.lua: no fireflies
      "camera { eye = {-8, 16, 20}, at = {6, 12, 0}, fov = 70 }\n"
      "image { width = " + std::to_string(width) + ", height = " + std::to_string(height) +
      ", spp = param(\"spp\", 8) }\n"
      "if param(\"parts\", 3) > 0 then partition { parts = param(\"parts\", 3) } end\n"
      "renderers { count = 2, lighting = lightop \"pathtrace\" { max_depth = 4, seed = param(\"seed\", 0),\n"
      "  directional_cache = param(\"cache\", false), cache_cells = param(\"cells\", 8),\n"
      "  cache_radius = param(\"radius\", 1.5), cache_fill_spp = param(\"fill\", 4) } }\n");
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const std::string reference_path = "bench-dircache-reference-v2-" + size + ".exr";
  if (!bench::fs::exists(reference_path)) {
    std::printf("rendering the reference (%d spp, another seed, no cache, whole scene) ...\n", reference_spp);
    bench::run_farm(script, {"spp=" + std::to_string(reference_spp), "seed=7", "parts=0"}, reference_path);
  }
  const auto reference = lf::read_image(reference_path);
  if (!reference) {
    std::printf("cannot read %s\n", reference_path.c_str());
    return 1;
  }
  struct Setting {
    const char* name;
    int spp, fill;
    double radius;
  };
  const Setting settings[3] = {{"accurate", 32, 32, 1.0}, {"fast", 16, 8, 1.0}, {"low", 8, 2, 1.0}};
  const std::string out = (bench::fs::temp_directory_path() / "lightfarm-dircache.exr").string();
  std::printf("Lost Empire %s, pathtrace depth 4, 3 parts, 2 renderers; reference %d spp\n", size.c_str(), reference_spp);
  std::printf("%-9s %-7s %8s %12s %8s %12s %12s %12s %12s %8s %9s\n", "quality", "cache", "seconds", "rays to parts",
              "rmse", "diffuse", "local", "global", "lookup", "hit", "MB parts");
  lf::Value::Array rows;
  for (const Setting& s : settings) {
    double plain_rmse = 0, plain_mb = 0;
    for (bool cache : {false, true}) {
      const auto run = bench::run_farm(script,
                                       {"spp=" + std::to_string(s.spp), "fill=" + std::to_string(s.fill),
                                        "radius=" + std::to_string(s.radius), std::string("cache=") + (cache ? "true" : "false")},
                                       out);
      const auto image = lf::read_image(out);
      const double rmse = image ? bench::relative_rmse(*image, *reference) : -1;
      const double rays = run.number("traced_rays");
      const double mb = bench::sum_over_kind(run.stats, "geometry", "bytes_in") / 1e6;
      const double diffuse = cache ? run.number("diffuse_rays") : 0, local = cache ? run.number("local_rays") : 0,
                   global = cache ? run.number("global_rays") : 0, lookups = cache ? run.number("cache_lookups") : 0;
      const double hit = cache ? run.number("cache_hit_ratio") : 0;
      std::printf("%-9s %-7s %8.2f %12.0f %8.4f %12.0f %12.0f %12.0f %12.0f %7.1f%% %9.1f\n", s.name, cache ? "yes" : "no",
                  run.wall_seconds, rays, rmse, diffuse, local, global, lookups, 100 * hit, mb);
      if (!cache) {
        plain_rmse = rmse;
        plain_mb = mb;
      } else {
        // What a data-parallel farm forwards beyond a neighbourhood: the diffuse rays that leave it. The cache answers
        // a share of them; the rest still travel. (All the op's rays go to geometry actors here, the fill pass's
        // too, since a LightOp holds no geometry of its own: that total is the MB column.)
        std::printf("          cache / no cache: rmse %.2fx (goal <= 1.3); rays leaving their neighbourhood %.0f, of "
                    "which %.0f still travel: their bytes %.2fx (goal <= 0.5); all MB to parts %.2fx\n",
                    rmse / plain_rmse, global + lookups, global, global / (global + lookups), mb / plain_mb);
      }
      rows.push_back(lf::Value::Map{{"quality", s.name}, {"cache", cache}, {"spp", s.spp}, {"fill_spp", s.fill},
                                    {"radius", s.radius}, {"seconds", run.wall_seconds}, {"rays_to_parts", rays},
                                    {"relative_rmse", rmse}, {"diffuse_rays", diffuse}, {"local_rays", local},
                                    {"global_rays", global}, {"cache_lookups", lookups}, {"hit_ratio", hit},
                                    {"mb_to_parts", mb}});
    }
  }
  bench::fs::remove(out);
  lf::Value doc = lf::Value::Map{{"benchmark", "dircache"}, {"width", width}, {"height", height},
                                 {"reference_spp", reference_spp}, {"rows", std::move(rows)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
