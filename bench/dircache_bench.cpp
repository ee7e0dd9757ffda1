// The directional cache measured like Jansen & Reinhard's Tables 1-3: Lost Empire (../shared/scenes, torches
// emitting), a camera inside the city, a partitioned farm (3 geometry actors, 2 renderers, a pool of 3 `pathtrace` of
// depth 4), at three quality settings, each without and with the directional cache, and each with the replicas
// holding no part or one part each (partition { colocate = true }: "home"). Per run: wall time (setup and fill
// included), the ray visits the replicas sent to geometry actors (the paper counts intersection tests, which Embree
// does not report; rays that leave a process are what a partitioned farm pays for), relative RMSE against a
// high-sample reference (kept between runs, bench-dircache-reference-v2-WxH.exr), the diffuse rays split into local /
// global / lookup, the hit ratio lookups / (global + lookups), and the MB the geometry actors received (the
// renderers' camera rays included). Goals: hit ratio >= 60.8 % at the accurate setting with RMSE <= 1.3x the
// uncached farm's, and the bytes to the parts at least halved. Writes bench-dircache.json.
//
//   build/bench/dircache_bench [--size WIDTH] [--reference-spp N] [--radius R] [--json FILE] [--glossy]
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "bench/image_error.hpp"
#include "core/value.hpp"
#include "render/scene/scene.hpp"

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/dircache_bench [--size WIDTH] [--reference-spp N] [--radius R] [--json FILE]"
                            " [--glossy]",
                            {"--size", "--reference-spp", "--radius", "--json"}, {"--glossy"});
  int width = 160, reference_spp = 1024;
  double radius = 0.5;
  std::string json_path = "bench-dircache.json";
  bool glossy = false;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--glossy") glossy = true;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--glossy") {
      --i;
      continue;
    }
    if (a == "--size") width = std::atoi(argv[i + 1]);
    else if (a == "--reference-spp") reference_spp = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
    else if (a == "--radius") radius = std::atof(argv[i + 1]);
  }
  const std::string obj = bench::shared_scene("lost_empire/lost_empire.obj");
  if (obj.empty()) return 0;
  const int height = width * 3 / 4;
  // --glossy: every diffuse material gets a Phong lobe as exporters write them (Ks 0.2, Ns 40; less where Kd leaves
  // less room), so that the cache works on the diffuse lobe of glossy materials.
  std::string shine;
  if (glossy) {
    auto scene = lf::Scene::load_obj_unlit(obj);
    if (!scene) return 1;
    for (const auto& m : scene->materials()) {
      const float room = 1.0f - std::max({m.kd.x, m.kd.y, m.kd.z});
      if (m.name == "Torch" || m.name == "(default)" || m.type != lf::Material::Type::diffuse || room < 0.02f) continue;
      const std::string ks = std::to_string(std::min(0.2f, room));
      shine += "material \"" + m.name + "\" { type = \"glossy\", ks = {" + ks + ", " + ks + ", " + ks + "}, ns = 40 }\n";
    }
  }
  const std::string script = bench::temp_script(
      "dircache.lua",
      "scene { file = \"" + obj + "\" }\n" + shine +
      "material \"Torch\" { emission = {9, 9, 6}, kd = {0, 0, 0} }\n"  // as examples/lost_empire.lua: no fireflies
      "camera { eye = {-8, 16, 20}, at = {6, 12, 0}, fov = 70 }\n"
      "image { width = " + std::to_string(width) + ", height = " + std::to_string(height) +
      ", spp = param(\"spp\", 8) }\n"
      "if param(\"parts\", 3) > 0 then partition { parts = param(\"parts\", 3), colocate = param(\"home\", false) } end\n"
      "renderers { count = 2, lighting = multiplexer { replicas = 3, lightop \"pathtrace\" { max_depth = 4,\n"
      "  seed = param(\"seed\", 0), directional_cache = param(\"cache\", false), cache_cells = param(\"cells\", 8),\n"
      "  cache_radius = param(\"radius\", 1.5), cache_fill_spp = param(\"fill\", 4) } } }\n");
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  const std::string reference_path = "bench-dircache-reference-v2-" + size + (glossy ? "-glossy" : "") + ".exr";
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
  const Setting settings[3] = {{"accurate", 32, 8, radius}, {"fast", 16, 4, radius}, {"low", 8, 2, radius}};
  const std::string out = (bench::fs::temp_directory_path() / "lightfarm-dircache.exr").string();
  std::printf("Lost Empire %s, pathtrace depth 4, 3 parts, 2 renderers, a pool of 3; reference %d spp\n", size.c_str(),
              reference_spp);
  std::printf("home: each replica holds a part itself and is sent the points there (partition { colocate = true })\n");
  std::printf("%-9s %-5s %-5s %8s %12s %8s %12s %12s %12s %12s %8s %9s %9s\n", "quality", "home", "cache", "seconds",
              "rays sent", "rmse", "diffuse", "local", "global", "lookup", "hit", "MB sent", "MB parts");
  lf::Value::Array rows;
  for (const Setting& s : settings) {
    for (bool home : {false, true}) {
      double plain_rmse = 0, plain_mb = 0, plain_sent = 0, plain_sent_mb = 0;
      for (bool cache : {false, true}) {
        const auto run = bench::run_farm(script,
                                         {"spp=" + std::to_string(s.spp), "fill=" + std::to_string(s.fill),
                                          "radius=" + std::to_string(s.radius),
                                          std::string("cache=") + (cache ? "true" : "false"),
                                          std::string("home=") + (home ? "true" : "false")},
                                         out);
        const auto image = lf::read_image(out);
        const double rmse = image ? bench::relative_rmse(*image, *reference) : -1;
        auto op = [&](const char* key) { return bench::sum_detail_over_kind(run.stats, "pathtrace", key); };
        // Ray visits the op's replicas sent to geometry actors (those in a replica's own part stay home).
        const double sent = op("part_visits") - op("local_part_visits");
        const double sent_mb = op("ray_bytes_to_parts") / 1e6;  // those rays and their answers
        const double mb = bench::sum_over_kind(run.stats, "geometry", "bytes_in") / 1e6;
        const double diffuse = op("diffuse_rays"), local = op("local_rays"), global = op("global_rays"),
                     lookups = op("cache_lookups");
        const double hit = global + lookups > 0 ? lookups / (global + lookups) : 0;
        std::printf("%-9s %-5s %-5s %8.2f %12.0f %8.4f %12.0f %12.0f %12.0f %12.0f %7.1f%% %9.1f %9.1f\n", s.name,
                    home ? "yes" : "no", cache ? "yes" : "no", run.wall_seconds, sent, rmse, diffuse, local, global,
                    lookups, 100 * hit, sent_mb, mb);
        if (!cache) {
          plain_rmse = rmse;
          plain_mb = mb;
          plain_sent = sent;
          plain_sent_mb = sent_mb;
        } else {
          // MB sent: the rays the replicas sent to other processes' parts, and their answers (the fill pass's
          // included): with home parts, what moved between parts. MB parts: everything the geometry actors
          // received, the renderers' camera rays too (renderers hold no geometry), with message headers.
          std::printf("                cache / no cache: rmse %.2fx (goal <= 1.3); hit ratio %.1f%% (goal >= 60.8%%); "
                      "rays sent %.2fx, MB sent %.2fx (goal <= 0.5), MB parts %.2fx\n",
                      rmse / plain_rmse, 100 * hit, sent / plain_sent, sent_mb / plain_sent_mb, mb / plain_mb);
        }
        rows.push_back(lf::Value::Map{{"quality", s.name}, {"home", home}, {"cache", cache}, {"spp", s.spp},
                                      {"fill_spp", s.fill}, {"radius", s.radius}, {"seconds", run.wall_seconds},
                                      {"ray_visits_sent", sent}, {"mb_sent", sent_mb}, {"relative_rmse", rmse}, {"diffuse_rays", diffuse},
                                      {"local_rays", local}, {"global_rays", global}, {"cache_lookups", lookups},
                                      {"hit_ratio", hit}, {"mb_to_parts", mb}});
      }
    }
  }
  bench::fs::remove(out);
  lf::Value doc = lf::Value::Map{{"benchmark", "dircache"}, {"width", width}, {"height", height},
                                 {"reference_spp", reference_spp}, {"rows", std::move(rows)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
