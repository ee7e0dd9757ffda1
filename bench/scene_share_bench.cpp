// What a big scene costs each actor: Lost Empire (225k triangles, ../shared/scenes). Prints min/median/max
// over --runs and writes bench-scene-share.json:
//   in one process: parsing the OBJ (what every actor did before scenes were shipped), reading the shipped file
//     into a private copy, mapping the host's shared scene image (what an actor does now), building the BVH
//   in a local farm of 1 renderer + a pool of N `direct` replicas, with its host agent (one BVH for the host,
//     shared by the actors it forks) and without (every actor builds its own), interleaved: each `direct` actor's
//     start-up (from its `lightfarm actor` process's start to READY configure, from its STATS) and the farm's
//     memory: the peak, sampled every 50 ms, of the proportional set sizes of every process under the director
//     (actors, the agent, the actors' stand-ins), so pages shared through the scene image or the agent's BVH count
//     once; the growth per extra actor is (peak at 6 replicas - at 2) / 4
// Usage: build/bench/scene_share_bench [--runs N] [--json FILE]
#include <cstdio>
#include <fstream>
#include <map>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/scene/scene_file.hpp"
#include "render/scene/scene_image.hpp"
#include "render/tracing/tracer.hpp"

namespace {

// Per actor in a stats JSON text: its kind, start-up and memory (keys come sorted, "kind" before the others).
struct ActorFigures {
  std::string kind;
  double start_seconds = 0, pss_bytes = 0;
};
std::vector<ActorFigures> actors_of(const std::string& stats) {
  std::vector<ActorFigures> out;
  size_t at = stats.find("\"actors\"");
  while ((at = stats.find("\"kind\": \"", at)) != std::string::npos) {
    ActorFigures a;
    const size_t begin = at + 9;
    a.kind = stats.substr(begin, stats.find('"', begin) - begin);
    a.pss_bytes = bench::json_number(stats.substr(at), "memory_pss_bytes");
    a.start_seconds = bench::json_number(stats.substr(at), "start_seconds");
    out.push_back(a);
    at = begin;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/scene_share_bench [--runs N] [--json FILE]",
                            {"--runs", "--json"});
  int runs = 5;
  std::string json_path = "bench-scene-share.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  const std::string obj = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/lost_empire/lost_empire.obj";
  if (!bench::fs::exists(obj)) {
    std::fprintf(stderr, "scene_share_bench: %s is absent; nothing to measure\n", obj.c_str());
    return 0;
  }
  const auto dir = bench::fs::temp_directory_path() / ("lightfarm-scene-share-" + std::to_string(::getpid()));
  bench::fs::create_directories(dir);
  std::string shipped_bytes;
  {
    auto scene = lf::Scene::load_obj(obj);
    if (!scene) {
      std::fprintf(stderr, "scene_share_bench: %s\n", scene.error().message.c_str());
      return 1;
    }
    shipped_bytes = lf::scene_to_bytes(*scene);
  }
  const std::string shipped = (dir / "scene").string(), hash = lf::content_hash(shipped_bytes);
  std::ofstream(shipped, std::ios::binary) << shipped_bytes;

  const std::string farm = bench::temp_script(
      "scene-share.lua", "scene { file = \"" + obj + "\" }\n"
                         "camera { eye = {-25, 28, 55}, at = {0, 8, 0}, fov = 60 }\n"
                         "light { point = {0, 40, 0}, intensity = {4000, 3600, 3000} }\n"
                         "image { width = 128, height = 128, spp = 4 }\n"
                         "farm { host_agents = param(\"agents\", true) }\n"
                         "local d = multiplexer { lightop \"direct\" {}, replicas = param(\"n\", 2) }\n"
                         "renderers { count = 1, lighting = d }\n");
  bench::run_farm(farm, {});  // the first farm ships the scene into this machine's cache and makes its image

  std::map<std::string, std::vector<double>> v;
  for (int r = 0; r < runs; ++r) {
    v["parse_obj_seconds"].push_back(bench::seconds_of([&] { (void)lf::Scene::load_obj(obj); }));
    v["read_shipped_private_seconds"].push_back(bench::seconds_of([&] { (void)lf::load_cached_scene(shipped, hash, "x"); }));
    bench::fs::remove(shipped + ".image");
    v["make_shared_image_seconds"].push_back(bench::seconds_of([&] { (void)lf::load_shared_scene(shipped, hash, "x"); }));
    v["map_shared_image_seconds"].push_back(bench::seconds_of([&] { (void)lf::load_shared_scene(shipped, hash, "x"); }));
    {
      auto mapped = lf::load_shared_scene(shipped, hash, "x");
      v["build_bvh_seconds"].push_back(bench::seconds_of([&] { lf::RayTracer tracer(*mapped); }));
    }

    // Each farm with its host agent (the default) and without (every actor builds its own BVH), interleaved.
    for (const bool agents : {true, false}) {
      const std::string tag = agents ? "" : "_no_agent";
      double pss[2] = {0, 0};
      const int replicas[2] = {2, 6};
      for (int k = 0; k < 2; ++k) {
        const auto run = bench::run_farm(farm, {"n=" + std::to_string(replicas[k]), agents ? "agents=true" : "agents=false"},
                                         {}, true);
        pss[k] = run.peak_actors_pss_bytes;
        for (const auto& a : actors_of(run.stats))
          if (a.kind == "direct")
            v["actor_start_seconds_" + std::to_string(replicas[k]) + "_replicas" + tag].push_back(a.start_seconds);
      }
      v["farm_pss_mb_2_replicas" + tag].push_back(pss[0] / 1e6);
      v["farm_pss_mb_6_replicas" + tag].push_back(pss[1] / 1e6);
      v["growth_mb_per_extra_actor" + tag].push_back((pss[1] - pss[0]) / 4 / 1e6);
    }
    std::fprintf(stderr, "run %d/%d done\n", r + 1, runs);
  }
  bench::fs::remove_all(dir);

  const double obj_mb = static_cast<double>(bench::fs::file_size(obj)) / 1e6;
  const double shipped_mb = static_cast<double>(shipped_bytes.size()) / 1e6;
  std::printf("lightfarm scene sharing: Lost Empire (%.1f MB OBJ, %.1f MB shipped), %d runs\n", obj_mb, shipped_mb,
              runs);
  std::printf("%-32s %9s %9s %9s\n", "figure", "min", "median", "max");
  lf::Value::Map doc{{"obj_mb", obj_mb}, {"shipped_mb", shipped_mb}};
  for (const char* key : {"parse_obj_seconds", "read_shipped_private_seconds", "make_shared_image_seconds",
                          "map_shared_image_seconds", "build_bvh_seconds", "actor_start_seconds_2_replicas",
                          "actor_start_seconds_6_replicas", "actor_start_seconds_2_replicas_no_agent",
                          "actor_start_seconds_6_replicas_no_agent", "farm_pss_mb_2_replicas", "farm_pss_mb_6_replicas",
                          "farm_pss_mb_2_replicas_no_agent", "farm_pss_mb_6_replicas_no_agent",
                          "growth_mb_per_extra_actor", "growth_mb_per_extra_actor_no_agent"}) {
    const bench::Spread s = bench::spread(v[key]);
    std::printf("%-32s %9.3f %9.3f %9.3f\n", key, s.min, s.median, s.max);
    doc[key] = s.to_value();
  }
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
