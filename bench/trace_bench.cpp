// Tracing a partitioned scene in one process (render/tracing/partition.hpp) on Lost Empire (../shared/scenes):
// rays per second of the whole scene's BVH with ties left to Embree and with them settled by the rule (what every
// farm now pays for images that do not depend on the BVH), and of the scene split into 2, 3 and 5 parts traced
// part by part; for each split, each part's share of the ray visits (imbalance = max / mean, the issue's <= 1.2
// goal for the cost-based split) and visits per ray. The rays: the camera's at 320x240 from inside the city, and as
// many diffuse bounce rays from the points it sees (cosine-distributed), the mix an indirect-lighting farm traces.
// Parts are split by probe rays and rebalanced by their visits (render/tracing/partition.hpp: partition_by_probes); the
// area-and-count split's imbalance is shown beside.
// --runs times, interleaved; medians with min and max. Writes bench-trace.json.
//
//   build/bench/trace_bench [--runs N] [--json FILE]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/tracing/camera.hpp"
#include "render/tracing/partition.hpp"
#include "render/tracing/tracer.hpp"

namespace {

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/trace_bench [--runs N] [--json FILE]",
                            {"--runs", "--json"});
  int runs = 5;
  std::string json_path = "bench-trace.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--runs") runs = std::atoi(argv[i + 1]);
    else if (a == "--json") json_path = argv[i + 1];
  }
  const std::string obj = bench::shared_scene("lost_empire/lost_empire.obj");
  if (obj.empty()) return 0;
  lf::SceneSpec spec;
  spec.file = obj;
  spec.materials.push_back(lf::Value::Map{{"name", "Torch"}, {"emission", lf::Value::Array{9.0, 9.0, 6.0}}});
  auto scene = lf::Scene::load(spec);
  if (!scene) {
    std::printf("cannot load %s: %s\n", obj.c_str(), scene.error().message.c_str());
    return 1;
  }
  const int w = 320, h = 240;
  lf::Camera camera(lf::CameraSpec{{-8, 16, 20}, {6, 12, 0}, {0, 1, 0}, 70}, w, h);
  std::vector<lf::Ray> rays;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) rays.push_back(camera.ray(x + 0.5f, y + 0.5f));
  lf::RayTracer whole(*scene);
  const double ties_seconds = bench::seconds_of([&] { (void)lf::TiedHits(*scene); });
  const size_t tied = lf::TiedHits(*scene).tied_triangles();
  {
    // Bounce rays from what the camera sees: cosine-distributed about the face normal, off the surface by epsilon.
    std::vector<lf::Hit> hits(rays.size());
    whole.intersect(rays, hits);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 1);
    const size_t camera_rays = rays.size();
    for (size_t i = 0; i < camera_rays; ++i) {
      if (!hits[i].valid()) continue;
      lf::Vec3 n = scene->normal(hits[i].triangle);
      if (lf::dot(n, rays[i].direction) > 0) n = -n;
      const lf::Vec3 a = std::fabs(n.x) > 0.5f ? lf::Vec3{0, 1, 0} : lf::Vec3{1, 0, 0};
      const lf::Vec3 t = lf::normalize(lf::cross(a, n)), b = lf::cross(n, t);
      const float r = std::sqrt(u(rng)), phi = 6.2831853f * u(rng);
      const lf::Vec3 d = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1 - r * r));
      const lf::Vec3 p = scene->ray_origin(hits[i].triangle, rays[i].origin + rays[i].direction * hits[i].t, n);
      rays.push_back(lf::Ray{p, lf::normalize(d)});
    }
  }
  const int part_counts[3] = {2, 3, 5};
  // Split by probe rays (80x60 camera rays and a bounce each), and by the area-and-count estimate.
  const lf::Camera probe_camera(lf::CameraSpec{{-8, 16, 20}, {6, 12, 0}, {0, 1, 0}, 70}, 80, 60);
  std::vector<std::unique_ptr<lf::PartitionedTracer>> split, by_area;
  for (int parts : part_counts) {
    split.push_back(std::make_unique<lf::PartitionedTracer>(
        *scene, lf::partition_by_probes(*scene, whole, probe_camera, 80, 60, parts)));
    by_area.push_back(std::make_unique<lf::PartitionedTracer>(*scene, lf::partition_scene(*scene, parts)));
  }

  std::vector<lf::Hit> hits(rays.size());
  std::vector<double> unsettled, settled, settle_ratio;
  std::vector<std::vector<double>> parted(3), parted_ratio(3);
  for (int r = 0; r < runs; ++r) {
    unsettled.push_back(bench::seconds_of([&] { whole.intersect_unsettled(rays, hits); }));
    settled.push_back(bench::seconds_of([&] { whole.intersect(rays, hits); }));
    settle_ratio.push_back(settled.back() / unsettled.back());
    for (int k = 0; k < 3; ++k) {
      parted[k].push_back(bench::seconds_of([&] { split[k]->intersect(rays, hits); }));
      parted_ratio[k].push_back(parted[k].back() / settled.back());
      if (r == 0) by_area[k]->intersect(rays, hits);  // only its work shares are reported
    }
  }
  const double n = static_cast<double>(rays.size());
  std::printf("Lost Empire (%zu triangles), %zu rays (camera %dx%d and one bounce each), %d runs, medians\n",
              scene->triangle_count(), rays.size(), w, h, runs);
  std::printf("  faces with an overlapping coplanar face: %zu (finding them and every corner's faces: %.3f s, once per "
              "tracer)\n", tied, ties_seconds);
  std::printf("  whole BVH, ties unsettled      %7.3f M rays/s\n", n / bench::median(unsettled) / 1e6);
  std::printf("  whole BVH, ties settled        %7.3f M rays/s\n", n / bench::median(settled) / 1e6);
  const auto cost = bench::spread(settle_ratio);
  std::printf("  settling ties costs: time settled / unsettled %.3f (min %.3f, max %.3f)\n", cost.median, cost.min,
              cost.max);
  lf::Value::Array partitions;
  for (int k = 0; k < 3; ++k) {
    const auto& visits = split[k]->rays_per_part();
    double total = 0, most = 0;
    for (uint64_t v : visits) {
      total += static_cast<double>(v);
      most = std::max(most, static_cast<double>(v));
    }
    const double imbalance = most / (total / static_cast<double>(visits.size()));
    double area_total = 0, area_most = 0;
    for (uint64_t v : by_area[k]->rays_per_part()) {
      area_total += static_cast<double>(v);
      area_most = std::max(area_most, static_cast<double>(v));
    }
    const double area_imbalance = area_most / (area_total / static_cast<double>(visits.size()));
    const auto ratio = bench::spread(parted_ratio[k]);
    std::printf("  %d parts: %7.3f M rays/s, time / whole %.3f (min %.3f, max %.3f); %.2f part visits per ray, the "
                "busiest part %.2f; ray work per part max / mean %.3f (goal <= 1.2; split by area and count instead: "
                "%.3f)\n",
                part_counts[k], n / bench::median(parted[k]) / 1e6, ratio.median, ratio.min, ratio.max,
                total / (n * runs), most / (n * runs), imbalance, area_imbalance);
    lf::Value::Array shares;
    for (uint64_t v : visits) shares.push_back(static_cast<double>(v) / total);
    partitions.push_back(lf::Value::Map{{"parts", part_counts[k]},
                                        {"m_rays_per_second", n / bench::median(parted[k]) / 1e6},
                                        {"time_over_whole", ratio.to_value()},
                                        {"visits_per_ray", total / (n * runs)},
                                        {"busiest_part_visits_per_ray", most / (n * runs)},
                                        {"work_share_per_part", std::move(shares)},
                                        {"imbalance_max_over_mean", imbalance},
                                        {"imbalance_split_by_area", area_imbalance}});
  }
  lf::Value doc = lf::Value::Map{{"benchmark", "trace"}, {"rays", n}, {"runs", runs},
                                 {"tied_faces", static_cast<double>(tied)}, {"tie_search_seconds", ties_seconds},
                                 {"m_rays_per_second_unsettled", n / bench::median(unsettled) / 1e6},
                                 {"m_rays_per_second_settled", n / bench::median(settled) / 1e6},
                                 {"settle_time_ratio", cost.to_value()},
                                 {"partitions", std::move(partitions)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
