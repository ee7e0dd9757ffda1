// Load balancing of the radiosity ring (Stürzlinger et al., Tables 1-4), on the built-in furnished room: for each layout
// (N nodes as rings x ring length) and each balancing scheme, the per-node work — visibility rays cast, packets
// processed — as max/mean imbalance, and the mean iteration wall time. Work counts stay meaningful when 8
// processes share 2 cores; times do not (they are printed for the record).
//
//   build/bench/radiosity_bench [--iterations 6] [--json bench-radiosity.json]
#include <cmath>
#include <cstring>
#include <map>

#include "bench_util.hpp"
#include "core/value.hpp"

namespace {

struct NodeFigures {
  double rays = 0, visits = 0, samples = 0, lent = 0, borrowed = 0, elements = 0, surfaces = 0, cpu = 0;
};

// Every radiosity node's "detail" block in the stats JSON.
std::vector<NodeFigures> node_figures(const std::string& stats) {
  std::vector<NodeFigures> out;
  for (size_t at = stats.find("\"detail\""); at != std::string::npos; at = stats.find("\"detail\"", at + 1)) {
    const size_t open = stats.find('{', at), close = stats.find('}', open);
    const std::string block = stats.substr(open, close - open + 1);
    if (block.find("\"rays\"") == std::string::npos) continue;
    NodeFigures f;
    f.rays = bench::json_number(block, "rays");
    f.visits = bench::json_number(block, "visits");
    f.samples = bench::json_number(block, "samples");
    f.lent = bench::json_number(block, "packets_lent");
    f.borrowed = bench::json_number(block, "packets_borrowed");
    f.elements = bench::json_number(block, "elements");
    f.surfaces = bench::json_number(block, "surfaces_held");
    f.cpu = bench::json_number(block, "solve_cpu_seconds");
    out.push_back(f);
  }
  return out;
}

double imbalance(const std::vector<NodeFigures>& nodes, double NodeFigures::*field) {
  double sum = 0, most = 0;
  for (const auto& n : nodes) {
    sum += n.*field;
    most = std::max(most, n.*field);
  }
  return sum > 0 ? most / (sum / static_cast<double>(nodes.size())) : 1.0;
}

// Mean of the "iteration_seconds" array.
double mean_iteration_seconds(const std::string& stats) {
  const std::vector<double> seconds = bench::json_array(stats, "iteration_seconds");
  double sum = 0;
  for (double v : seconds) sum += v;
  return seconds.empty() ? 0 : sum / static_cast<double>(seconds.size());
}

struct Layout {
  int rings, length;
};

}  // namespace

int main(int argc, char** argv) {
  int iterations = 6;
  std::string json_path = "bench-radiosity.json";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--iterations") && i + 1 < argc) iterations = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--json") && i + 1 < argc) json_path = argv[++i];
    else {
      std::fprintf(stderr, "usage: radiosity_bench [--iterations N] [--json FILE]\n");
      return 2;
    }
  }
  const std::string script = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/radiosity_room.lua";
  const std::vector<Layout> layouts{{1, 1}, {1, 2}, {2, 1}, {1, 4}, {2, 2}, {4, 1}, {1, 8}, {2, 4}, {4, 2}, {8, 1}};
  const std::vector<std::string> schemes{"none", "static", "dynamic", "static+dynamic"};
  std::printf("lightfarm radiosity ring benchmark: built-in room, first %d iterations, subdivide 0.5, S = 50, M = 16\n",
              iterations);
  std::printf("imbalance = max/mean over nodes of visibility rays cast (packets processed in brackets)\n\n");
  struct Row {
    Layout layout;
    std::string scheme;
    double ray_imbalance, visit_imbalance, element_imbalance, surface_imbalance, seconds, lent, total_rays, max_rays,
        cpu_imbalance;
  };
  std::vector<Row> rows;
  for (const auto& scheme : schemes) {
    for (const auto& l : layouts) {
      auto run = bench::run_farm(script, {"rings=" + std::to_string(l.rings), "ring_length=" + std::to_string(l.length),
                                          "balance=" + scheme, "iterations=" + std::to_string(iterations), "width=32",
                                          "height=24", "spp=1"});
      const auto nodes = node_figures(run.stats);
      if (static_cast<int>(nodes.size()) != l.rings * l.length) {
        std::fprintf(stderr, "expected %d nodes in the stats, found %zu\n", l.rings * l.length, nodes.size());
        return 1;
      }
      double lent = 0, total_rays = 0, max_rays = 0;
      for (const auto& n : nodes) {
        lent += n.lent;
        total_rays += n.rays;
        max_rays = std::max(max_rays, n.rays);
      }
      rows.push_back({l, scheme, imbalance(nodes, &NodeFigures::rays), imbalance(nodes, &NodeFigures::visits),
                      imbalance(nodes, &NodeFigures::elements), imbalance(nodes, &NodeFigures::surfaces),
                      mean_iteration_seconds(run.stats), lent, total_rays, max_rays,
                      imbalance(nodes, &NodeFigures::cpu)});
      std::fprintf(stderr, "  %-15s %dx%d: rays %.3f\n", scheme.c_str(), l.rings, l.length, rows.back().ray_imbalance);
    }
  }
  // One table per scheme, rows N, columns ring length, like the paper's.
  const int lengths[] = {1, 2, 4, 8};
  int table = 1;
  for (const auto& scheme : schemes) {
    std::printf("Table %d: balance = %s\n%-4s", table++, scheme.c_str(), "N\\L");
    for (int len : lengths) std::printf(" %18d", len);
    std::printf("\n");
    for (int n : {1, 2, 4, 8}) {
      std::printf("%-4d", n);
      for (int len : lengths) {
        const Row* found = nullptr;
        for (const auto& r : rows)
          if (r.scheme == scheme && r.layout.length == len && r.layout.rings * r.layout.length == n) found = &r;
        if (found)
          std::printf("   %5.3f (%5.3f) %4.2fs", found->ray_imbalance, found->visit_imbalance, found->seconds);
        else
          std::printf(" %18s", "");
      }
      std::printf("\n");
    }
    std::printf("\n");
  }
  // Which scheme is most even in each layout.
  std::printf("busiest node's rays (the iteration's critical path) and all rays, static+dynamic over none:\n");
  std::printf("%-8s %-16s %10s %10s %10s %10s %12s %10s\n", "layout", "lowest imbalance", "none", "static", "dynamic",
              "st+dyn", "busiest", "all rays");
  bool goal = true;
  double worst_n8 = 0;
  for (const auto& l : layouts) {
    std::map<std::string, double> by, rays, busiest;
    for (const auto& r : rows)
      if (r.layout.rings == l.rings && r.layout.length == l.length) {
        by[r.scheme] = r.ray_imbalance;
        rays[r.scheme] = r.total_rays;
        busiest[r.scheme] = r.max_rays;
      }
    std::string best = "none";
    for (const auto& s : schemes)
      if (by[s] < by[best] - 1e-9) best = s;
    const bool combined_best = by["static+dynamic"] <= by[best] + 0.02;  // ties within noise count
    goal = goal && combined_best;
    if (l.rings * l.length == 8) worst_n8 = std::max(worst_n8, by["static+dynamic"]);
    std::printf("%dx%-6d %-16s %10.3f %10.3f %10.3f %10.3f %12.3f %10.3f\n", l.rings, l.length, best.c_str(), by["none"],
                by["static"], by["dynamic"], by["static+dynamic"], busiest["static+dynamic"] / busiest["none"],
                rays["static+dynamic"] / rays["none"]);
  }
  std::printf("\nstatic+dynamic lowest (within 0.02) in every layout: %s; worst at N = 8: %.3f (goal <= 1.15)\n",
              goal ? "yes" : "no", worst_n8);
  // The same question asked of each node's CPU time during the solve: the work it did, including what rays do
  // not count (form factors and routing at a packet's origin), whatever share of a core it got.
  std::printf("\nCPU-time imbalance (max/mean of each node's CPU seconds in the solve):\n%-8s %10s %10s %10s %10s\n",
              "layout", "none", "static", "dynamic", "st+dyn");
  bool cpu_goal = true;
  double cpu_worst_n8 = 0;
  for (const auto& l : layouts) {
    std::map<std::string, double> cpu;
    for (const auto& r : rows)
      if (r.layout.rings == l.rings && r.layout.length == l.length) cpu[r.scheme] = r.cpu_imbalance;
    double lowest = cpu["none"];
    for (const auto& sch : schemes) lowest = std::min(lowest, cpu[sch]);
    cpu_goal = cpu_goal && cpu["static+dynamic"] <= lowest + 0.02;
    if (l.rings * l.length == 8) cpu_worst_n8 = std::max(cpu_worst_n8, cpu["static+dynamic"]);
    std::printf("%dx%-6d %10.3f %10.3f %10.3f %10.3f\n", l.rings, l.length, cpu["none"], cpu["static"], cpu["dynamic"],
                cpu["static+dynamic"]);
  }
  std::printf("\nstatic+dynamic lowest (within 0.02) in every layout by CPU time: %s; worst at N = 8: %.3f\n",
              cpu_goal ? "yes" : "no", cpu_worst_n8);

  lf::Value::Array runs;
  for (const auto& r : rows)
    runs.push_back(lf::Value::Map{{"rings", r.layout.rings},
                                  {"ring_length", r.layout.length},
                                  {"balance", r.scheme},
                                  {"ray_imbalance", r.ray_imbalance},
                                  {"packet_imbalance", r.visit_imbalance},
                                  {"element_imbalance", r.element_imbalance},
                                  {"surface_imbalance", r.surface_imbalance},
                                  {"packets_lent", r.lent},
                                  {"total_rays", r.total_rays},
                                  {"busiest_node_rays", r.max_rays},
                                  {"cpu_imbalance", r.cpu_imbalance},
                                  {"mean_iteration_seconds", r.seconds}});
  const lf::Value doc = lf::Value::Map{{"benchmark", "radiosity_ring"},
                                       {"iterations", iterations},
                                       {"runs", std::move(runs)},
                                       {"static_dynamic_lowest_everywhere", goal},
                                       {"static_dynamic_worst_n8", worst_n8},
                                       {"cpu_static_dynamic_lowest_everywhere", cpu_goal},
                                       {"cpu_static_dynamic_worst_n8", cpu_worst_n8}};
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
