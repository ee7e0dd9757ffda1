// Visibility work of long radiosity rings, in one process: the ring nodes of examples/radiosity_room.lua's solve run
// their real algorithm (radiosity/ring.cpp) and pass packets through a queue instead of sockets, so layouts of up to
// 64 positions are measured exactly on two cores. Work is each node's visibility queries (rays cast against a BVH);
// it does not depend on timing, except under dynamic balancing, which is modelled as the tests model it (an idle node
// takes a waiting packet from the node at its position in another ring).
//
// Two imbalance figures per layout (max/mean over nodes):
//   summed        of each node's work over all iterations (what radiosity_bench reports from a farm's stats)
//   per iteration the busiest node's work in each iteration, summed, over the mean's: every iteration ends at the
//                 director's barrier, so the busiest node's work is what sets the solve's time
// and that busiest work itself ("critical path"), over the same layout's without balancing: an even ring that
// casts many more rays is no faster.
//
//   build/bench/ring_balance_bench [--iterations 6] [--layouts 1x8,2x4,...] [--per-shot] [--json bench-ring-balance.json]
// --per-shot also prints, for each shot, the busiest node against the plan's own estimate of it.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/value.hpp"
#include "radiosity/config.hpp"
#include "radiosity/ring.hpp"

using namespace lf;
using namespace lf::radiosity;

namespace {

struct LayoutResult {
  RingLayout layout;
  std::string scheme;
  double summed = 1, per_iteration = 1, critical = 0, plan_ms = 0, rays = 0, visits = 0, surfaces_held_max = 0, surfaces = 0;
  std::vector<uint32_t> shooters;
};

double max_over_mean(const std::vector<double>& v) {
  double sum = 0, most = 0;
  for (double x : v) sum += x, most = std::max(most, x);
  return sum > 0 ? most / (sum / static_cast<double>(v.size())) : 1.0;
}

float patch_size = 0.25f, element_size = 0.125f;
bool per_shot = false;

LayoutResult run(const Scene& scene, RingLayout layout, const std::string& scheme, int iterations) {
  RingConfig config;
  config.layout = layout;
  config.mesh.patch_size = patch_size;
  config.mesh.element_size = element_size;
  config.solver.shooter_samples = 16;
  config.solver.subdivide = 0.5f;
  config.solver.max_depth = 2;
  config.solver.converge = 0.0;
  config.solver.max_iterations = iterations;
  config.ring.samples_per_packet = 50;
  config.static_balance = scheme == "static" || scheme == "static+dynamic";
  config.dynamic_balance = scheme == "dynamic" || scheme == "static+dynamic";
  auto plan = plan_ring(scene, config);
  if (!plan) {
    std::fprintf(stderr, "%s\n", plan.error().message.c_str());
    std::exit(1);
  }
  const int n = layout.nodes();
  std::vector<std::unique_ptr<RingNode>> nodes;
  for (int i = 0; i < n; ++i)
    nodes.push_back(std::make_unique<RingNode>(plan->mesh, plan->bsp, layout, i, plan->patches_of(i), config.solver,
                                               config.ring));
  LayoutResult result;
  result.layout = layout;
  result.scheme = scheme;
  result.surfaces = static_cast<double>(plan->mesh.surfaces.size());
  std::vector<double> total(static_cast<size_t>(n), 0);
  double busiest_sum = 0, mean_sum = 0;
  struct Hop {
    int node;
    bool home;
    int home_node;
    SamplePacket packet;
  };
  for (int it = 0; it < iterations; ++it) {
    Candidate best;
    for (auto& node : nodes)
      if (node->candidate().beats(best)) best = node->candidate();
    if (best.patch == UINT32_MAX) break;
    result.shooters.push_back(best.patch);
    const Shooter shooter = make_shooter(plan->mesh, best.patch, best.unshot, config.solver.shooter_samples);
    // What every node spends planning the shot (in begin_iteration), timed once here.
    const auto plan_start = std::chrono::steady_clock::now();
    (void)plan->bsp.plan_shot(plan->mesh, shooter.polygon, shooter.targets);
    result.plan_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - plan_start).count();
    std::vector<uint64_t> before(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      before[static_cast<size_t>(i)] = nodes[static_cast<size_t>(i)]->work().rays;
      nodes[static_cast<size_t>(i)]->begin_iteration(static_cast<uint32_t>(it), shooter);
      const RingNode& node = *nodes[static_cast<size_t>(i)];
      result.surfaces_held_max =
          std::max(result.surfaces_held_max, static_cast<double>(node.surfaces_in_memory()));
    }
    std::deque<Hop> queue;
    for (bool busy = true; busy;) {
      busy = false;
      for (int i = 0; i < n; ++i) {
        RingNode& node = *nodes[static_cast<size_t>(i)];
        if (auto p = node.take_pending()) {
          queue.push_back({i, false, i, std::move(*p)});
          busy = true;
        } else if (config.dynamic_balance && node.finished()) {
          for (int r = 0; r < layout.rings; ++r) {
            auto& other = *nodes[static_cast<size_t>(layout.node(r, node.position()))];
            if (auto q = other.take_pending()) {
              queue.push_back({i, false, i, std::move(*q)});
              busy = true;
              break;
            }
          }
        }
      }
      while (!queue.empty()) {
        busy = true;
        Hop h = std::move(queue.front());
        queue.pop_front();
        if (h.home) {
          nodes[h.packet.origin]->complete(h.packet);
          continue;
        }
        RingNode& node = *nodes[static_cast<size_t>(h.node)];
        node.process(h.packet);
        const int next = node.next_position(h.packet, node.position());
        if (next >= 0)
          queue.push_back({layout.node(node.ring(), next), false, h.home_node, std::move(h.packet)});
        else
          queue.push_back({h.home_node, true, h.home_node, std::move(h.packet)});
      }
    }
    std::vector<double> work(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      work[static_cast<size_t>(i)] =
          static_cast<double>(nodes[static_cast<size_t>(i)]->work().rays - before[static_cast<size_t>(i)]);
      total[static_cast<size_t>(i)] += work[static_cast<size_t>(i)];
    }
    double sum = 0, most = 0;
    for (double w : work) sum += w, most = std::max(most, w);
    if (per_shot) {
      // The plan's own estimate beside what the nodes then cast: how far the cost model is from the ring.
      GlobalBsp::ShotEstimate e;
      (void)plan->bsp.plan_shot(plan->mesh, shooter.polygon, shooter.targets, &e);
      double off = 0;
      for (int i = 0; i < n && e.mean > 0 && e.per_node.size() == work.size(); ++i)
        off = std::max(off, std::abs(e.per_node[static_cast<size_t>(i)] / e.mean - work[static_cast<size_t>(i)] / (sum / n)));
      std::printf("  shot %d (patch %u): busiest node %.3f of the mean, estimated %.3f; a node's share at most %.3f "
                  "from its estimate\n", it + 1, best.patch, most / (sum / n), e.mean > 0 ? e.busiest / e.mean : 1.0, off);
    }
    busiest_sum += most;
    mean_sum += sum / n;
  }
  result.summed = max_over_mean(total);
  result.per_iteration = mean_sum > 0 ? busiest_sum / mean_sum : 1.0;
  result.critical = busiest_sum;
  if (!result.shooters.empty()) result.plan_ms /= static_cast<double>(result.shooters.size());
  for (auto& node : nodes) {
    result.rays += static_cast<double>(node->work().rays);
    result.visits += static_cast<double>(node->work().visits);
  }
  return result;
}

std::vector<RingLayout> parse_layouts(const std::string& text) {
  std::vector<RingLayout> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    RingLayout l;
    if (std::sscanf(item.c_str(), "%dx%d", &l.rings, &l.length) != 2 || l.rings < 1 || l.length < 1 ||
        l.length > 64) {
      std::fprintf(stderr, "bad layout '%s' (RINGSxLENGTH, length at most 64)\n", item.c_str());
      std::exit(2);
    }
    out.push_back(l);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 6;
  std::string json_path = "bench-ring-balance.json";
  std::string layouts_text = "1x4,1x8,2x4,4x2,8x1,1x16,2x32";
  std::string schemes_text = "none,static,static+dynamic";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc) iterations = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--layouts") && i + 1 < argc) layouts_text = argv[++i];
    else if (!std::strcmp(argv[i], "--schemes") && i + 1 < argc) schemes_text = argv[++i];
    else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) json_path = argv[++i];
    else if (!std::strcmp(argv[i], "--per-shot")) per_shot = true;
    else if (!std::strcmp(argv[i], "--patch-size") && i + 1 < argc) patch_size = std::strtof(argv[++i], nullptr);
    else if (!std::strcmp(argv[i], "--element-size") && i + 1 < argc) element_size = std::strtof(argv[++i], nullptr);
    else {
      std::fprintf(stderr, "usage: ring_balance_bench [--iterations N] [--layouts 1x8,2x4] [--schemes none,static] "
                           "[--patch-size M] [--element-size M] [--per-shot] [--json FILE]\n");
      return 2;
    }
  }
  auto scene = Scene::builtin("room");
  if (!scene) {
    std::fprintf(stderr, "%s\n", scene.error().message.c_str());
    return 1;
  }
  std::vector<std::string> schemes;
  {
    std::stringstream in(schemes_text);
    for (std::string s; std::getline(in, s, ',');) schemes.push_back(s);
  }
  std::printf("lightfarm ring balance benchmark (in-process rings): built-in room, patches %g m, elements %g m, first %d "
              "iterations, subdivide 0.5, S = 50, M = 16\nimbalance = max/mean over nodes of visibility queries\n\n",
              patch_size, element_size, iterations);
  std::printf("%-7s %-15s %9s %14s %14s %12s %10s %9s  %s\n", "layout", "balance", "summed", "per iteration",
              "critical path", "rays", "visits", "plan ms", "surfaces held (most, at any shot)");
  lf::Value::Array runs;
  for (const auto& l : parse_layouts(layouts_text)) {
    double first_critical = 0;
    for (const auto& scheme : schemes) {
      const LayoutResult r = run(*scene, l, scheme, iterations);
      if (first_critical == 0) first_critical = r.critical;
      std::printf("%dx%-5d %-15s %9.3f %14.3f %14.3f %12.0f %10.0f %9.2f  %.0f of %.0f\n", l.rings, l.length,
                  scheme.c_str(), r.summed, r.per_iteration, r.critical / first_critical, r.rays, r.visits, r.plan_ms,
                  r.surfaces_held_max, r.surfaces);
      std::fflush(stdout);
      runs.push_back(lf::Value::Map{{"rings", l.rings},
                                    {"ring_length", l.length},
                                    {"balance", scheme},
                                    {"summed_imbalance", r.summed},
                                    {"per_iteration_imbalance", r.per_iteration},
                                    {"critical_path_rays", r.critical},
                                    {"plan_ms_per_shot", r.plan_ms},
                                    {"rays", r.rays},
                                    {"visits", r.visits},
                                    {"most_surfaces_held", r.surfaces_held_max},
                                    {"surfaces", r.surfaces}});
    }
  }
  const lf::Value doc = lf::Value::Map{{"benchmark", "ring_balance"},
                                       {"iterations", iterations},
                                       {"patch_size", patch_size},
                                       {"element_size", element_size},
                                       {"runs", std::move(runs)}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("\nwrote %s\n", json_path.c_str());
  return 0;
}
