#include "farm/builders.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <set>
#include <string_view>

#include "farm/light_path_check.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf {

std::string unique_name(const FarmSpec& spec, const std::string& wanted) {
  if (spec.find(wanted) < 0) return wanted;
  for (int i = 2;; ++i)
    if (spec.find(wanted + "-" + std::to_string(i)) < 0) return wanted + "-" + std::to_string(i);
}

int add_actor(FarmSpec& spec, ActorSpec actor) {
  actor.name = unique_name(spec, actor.name);
  spec.actors.push_back(std::move(actor));
  return static_cast<int>(spec.actors.size() - 1);
}

bool is_wired(const FarmSpec& spec, int i) {
  if (spec.lighting == i) return true;
  for (const auto& a : spec.actors)
    for (int in : a.inputs)
      if (in == i) return true;
  return false;
}

namespace {

ActorSpec& at(FarmSpec& spec, int i) { return spec.actors[static_cast<size_t>(i)]; }

// hosts[i % n], or "local" for an empty list.
std::string spread(const std::vector<std::string>& hosts, size_t i) { return hosts.empty() ? "local" : hosts[i % hosts.size()]; }

// The actor itself and, for a multiplexer, its replicas' subtrees (not their inputs, which replicas share).
void subtree(const FarmSpec& spec, int i, std::vector<int>& out) {
  out.push_back(i);
  if (spec.actors[static_cast<size_t>(i)].is_multiplexer())
    for (int r : spec.actors[static_cast<size_t>(i)].inputs) subtree(spec, r, out);
}

}  // namespace

Result<int> replicate(FarmSpec& spec, const PoolSpec& pool) {
  if (pool.op < 0 || static_cast<size_t>(pool.op) >= spec.actors.size()) return make_error("no such LightOp");
  if (is_wired(spec, pool.op))
    return make_error("lightop '" + at(spec, pool.op).name +
                      "' is already wired elsewhere; give the multiplexer a LightOp of its own");
  if (pool.replicas < 1) return make_error("a pool needs at least one replica");
  if (!pool.slowdown.empty() && pool.slowdown.size() != static_cast<size_t>(pool.replicas))
    return make_error("multiplexer: slowdown must list one factor per replica (" + std::to_string(pool.replicas) + ")");
  const std::string base = at(spec, pool.op).name;
  const std::string wanted = pool.name.empty() ? base : pool.name;

  std::vector<int> nodes;
  subtree(spec, pool.op, nodes);
  // Pools of pools multiply: three nested pools of 64 would be 262,144 processes, and building them alone took the
  // director seconds (found by fuzzing scripts). A farm is capped well above any real one.
  const size_t after = spec.actors.size() + nodes.size() * static_cast<size_t>(pool.replicas - 1) + 1;
  if (after > kMaxActors)
    return make_error("multiplexer: this pool would make the farm " + std::to_string(after) + " actors (at most " +
                      std::to_string(kMaxActors) + ")");
  // "direct" -> "direct.1"; an inner replica "direct.0" -> "direct.1.0"; a node named otherwise keeps its name
  // under the replica's prefix.
  auto renamed = [&](const std::string& name, int replica) {
    const std::string suffix = name.rfind(base, 0) == 0 ? name.substr(base.size()) : "." + name;
    return base + "." + std::to_string(replica) + suffix;
  };
  std::vector<int> roots;
  for (int r = 0; r < pool.replicas; ++r) {
    std::map<int, int> index_of;  // template node -> this replica's node
    for (int n : nodes) {
      if (r == 0) {
        index_of[n] = n;
      } else {
        spec.actors.push_back(spec.actors[static_cast<size_t>(n)]);
        index_of[n] = static_cast<int>(spec.actors.size() - 1);
      }
    }
    for (int n : nodes)
      for (int& in : at(spec, index_of[n]).inputs)
        if (index_of.count(in)) in = index_of[in];
    roots.push_back(index_of[pool.op]);
  }
  // Rename after copying, all at once: inner names may be what outer renaming frees (direct.0 -> direct.0.0).
  std::vector<std::pair<int, std::string>> new_names;
  std::set<int> moving;
  for (int r = 0; r < pool.replicas; ++r) {
    std::vector<int> mine;
    subtree(spec, roots[static_cast<size_t>(r)], mine);
    for (int n : mine) {
      new_names.emplace_back(n, renamed(at(spec, n).name, r));
      moving.insert(n);
    }
  }
  // One set of the names that stay, not a scan per new name: a pool of pools of a few thousand actors took the
  // fuzzer's sanitized build seconds per script.
  std::set<std::string_view> staying;
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (!moving.count(static_cast<int>(i))) staying.insert(spec.actors[i].name);
  for (const auto& [n, name] : new_names)
    if (staying.count(name)) return make_error("multiplexer: replica name '" + name + "' is already taken");
  for (const auto& [n, name] : new_names) at(spec, n).name = name;
  if (!pool.hosts.empty())
    for (int r = 0; r < pool.replicas; ++r) {
      std::vector<int> mine;
      subtree(spec, roots[static_cast<size_t>(r)], mine);
      for (int n : mine) at(spec, n).host = spread(pool.hosts, static_cast<size_t>(r));
    }
  for (size_t r = 0; r < pool.slowdown.size(); ++r) {
    if (pool.slowdown[r] == 1.0) continue;
    ActorSpec& root = at(spec, roots[r]);
    if (root.is_multiplexer()) return make_error("multiplexer: slowdown applies to LightOp replicas, not multiplexers");
    root.debug["slowdown"] = pool.slowdown[r];
  }
  if (spec.find(wanted) >= 0) return make_error("multiplexer: name '" + wanted + "' is already taken");
  ActorSpec m;
  m.name = wanted;
  m.kind = kMultiplexer.name;
  m.params = pool.params.to_map();
  m.inputs = roots;
  m.host = spread(pool.hosts, 0);
  m.loc = pool.loc;
  spec.actors.push_back(std::move(m));
  return static_cast<int>(spec.actors.size() - 1);
}

void add_renderers(FarmSpec& spec, int count, int lighting, const RendererParams& params,
                   const std::vector<std::string>& hosts, const SourceLoc& loc) {
  spec.lighting = lighting;
  for (int i = 0; i < count; ++i) {
    ActorSpec a;
    a.name = "renderer-" + std::to_string(i);
    a.kind = kRenderer.name;
    a.params = params.to_map();
    a.inputs = {lighting};
    a.host = spread(hosts, static_cast<size_t>(i));
    a.loc = loc;
    spec.actors.push_back(std::move(a));
  }
}

Status add_partition(FarmSpec& spec, int parts, bool colocate, const std::vector<std::string>& hosts,
                     const SourceLoc& loc) {
  if (spec.partition_parts > 0) return make_error("partition is declared twice");
  for (int i = 0; i < parts; ++i) {
    ActorSpec g;
    g.kind = kGeometry.name;
    g.name = "geometry." + std::to_string(i);
    if (spec.find(g.name) >= 0) return make_error("partition: name '" + g.name + "' is already taken");
    g.params = Value::Map{{"part", static_cast<int64_t>(i)}, {"parts", static_cast<int64_t>(parts)}};
    g.host = spread(hosts, static_cast<size_t>(i));
    g.loc = loc;
    spec.actors.push_back(std::move(g));
  }
  spec.partition_parts = parts;
  spec.partition_colocate = colocate;
  spec.partition_loc = loc;
  return Ok{};
}

Result<int> expand_ring(FarmSpec& spec, const radiosity::RingConfig& config, const Value::Map& params,
                        const std::string& name, const std::vector<std::string>& hosts, const SourceLoc& loc) {
  if (spec.find(name) >= 0) return make_error("radiosity: name '" + name + "' is already taken");
  const int first = static_cast<int>(spec.actors.size());
  const int nodes = config.layout.nodes();
  for (int i = 0; i < nodes; ++i) {
    ActorSpec n;
    n.kind = kRingNode.name;
    n.name = name + "." + std::to_string(config.layout.ring_of(i)) + "." + std::to_string(config.layout.position_of(i));
    if (spec.find(n.name) >= 0) return make_error("radiosity: name '" + n.name + "' is already taken");
    n.params = params;
    n.params["node"] = static_cast<int64_t>(i);
    for (int j = 0; j < nodes; ++j)
      if (j != i) n.inputs.push_back(first + j);
    n.host = spread(hosts, static_cast<size_t>(i));
    n.loc = loc;
    spec.actors.push_back(std::move(n));
  }
  ActorSpec op;
  op.kind = "radiosity";
  op.name = name;  // the op reads the solution, not the ring's settings: it takes no parameters
  op.host = spread(hosts, 0);
  op.loc = loc;
  spec.actors.push_back(std::move(op));
  return static_cast<int>(spec.actors.size() - 1);
}

void settle_pool_dispatch(FarmSpec& spec) {
  const int n = static_cast<int>(spec.actors.size());
  for (int m = 0; m < n; ++m) {
    ActorSpec& pool = spec.actors[static_cast<size_t>(m)];
    pool.dispatched_by_clients = false;
    if (!pool.is_multiplexer()) continue;
    if (MultiplexerParams::read(ParamTable(pool.params, pool.name)).dispatch != "clients") continue;
    bool ok = !pool.inputs.empty();
    for (int r : pool.inputs) ok = ok && !spec.actors[static_cast<size_t>(r)].is_multiplexer();
    bool has_client = m == spec.lighting;
    for (const auto& client : spec.actors) {
      if (std::find(client.inputs.begin(), client.inputs.end(), m) == client.inputs.end()) continue;
      has_client = true;
      ok = ok && (client.is_renderer() || client.loads_scene());
    }
    pool.dispatched_by_clients = ok && has_client;
  }
}

Status validate(const FarmSpec& s) {
  const int n = static_cast<int>(s.actors.size());
  if (s.renderer_count() == 0) return make_error("the script declares no renderers (add renderers { lighting = ... })");
  if (s.lighting < 0 || s.lighting >= n) return make_error("the renderers have no lighting");
  std::set<std::string> names;
  for (const auto& a : s.actors) {
    if (!names.insert(a.name).second) return make_error(a.loc.str() + ": two actors are named '" + a.name + "'");
    if (!s.host_of(a)) return make_error(a.loc.str() + ": '" + a.name + "' is placed on undeclared host '" + a.host + "'");
    for (int in : a.inputs)
      if (in < 0 || in >= n) return make_error(a.loc.str() + ": '" + a.name + "' has an input that does not exist");
  }
  // No cycles: light must arrive from somewhere. Ring nodes ask each other by design; they are not light inputs.
  std::vector<int> state(s.actors.size(), 0);  // 0 new, 1 on the path, 2 done
  std::function<int(int)> cycle_at = [&](int i) -> int {
    if (state[static_cast<size_t>(i)] == 1) return i;
    if (state[static_cast<size_t>(i)] == 2 || s.actors[static_cast<size_t>(i)].is_ring_node()) return -1;
    state[static_cast<size_t>(i)] = 1;
    for (int in : s.actors[static_cast<size_t>(i)].inputs)
      if (int c = cycle_at(in); c >= 0) return c;
    state[static_cast<size_t>(i)] = 2;
    return -1;
  };
  for (int i = 0; i < n; ++i)
    if (int c = cycle_at(i); c >= 0)
      return make_error(s.actors[static_cast<size_t>(c)].loc.str() + ": '" + s.actors[static_cast<size_t>(c)].name +
                        "' is its own input through a cycle");
  std::vector<bool> used(s.actors.size(), false);
  std::vector<int> stack{s.lighting};
  while (!stack.empty()) {
    int i = stack.back();
    stack.pop_back();
    if (used[static_cast<size_t>(i)]) continue;
    used[static_cast<size_t>(i)] = true;
    for (int in : s.actors[static_cast<size_t>(i)].inputs) stack.push_back(in);
  }
  for (size_t i = 0; i < s.actors.size(); ++i)
    if (!s.actors[i].is_renderer() && !s.actors[i].is_ring_node() && !s.actors[i].is_geometry() && !used[i])
      return make_error(s.actors[i].loc.str() + ": lightop '" + s.actors[i].name +
                        "' is not connected to the renderers' lighting (nothing would ask it for light)");
  return Ok{};
}

bool traces_through_parts(const ActorSpec& a) {
  if (a.is_renderer()) return true;
  const LightOpKind* kind = find_lightop_kind(a.kind);
  return kind && kind->traces_through_context && !a.is_multiplexer();
}

int64_t colocated_part(const FarmSpec& spec, int i) {
  const ActorSpec& a = spec.actors.at(static_cast<size_t>(i));
  if (!spec.partition_colocate || spec.partition_parts <= 0) return -1;
  const int pool = spec.pool_of(i);
  if (pool < 0 || !traces_through_parts(a)) return -1;
  const auto& replicas = spec.actors[static_cast<size_t>(pool)].inputs;
  const auto j = std::find(replicas.begin(), replicas.end(), i) - replicas.begin();
  return static_cast<int64_t>(j % spec.partition_parts);
}

std::string to_dot(const FarmSpec& spec) {
  std::string out = "digraph farm {\n  rankdir=LR;\n  node [shape=box, style=rounded];\n";
  auto id = [](const std::string& name) { return "\"" + name + "\""; };
  std::map<std::string, std::vector<std::string>> by_host;
  // Renderers are drawn as one node a host ("renderer × k" in each host's box), one node in all on one host.
  std::vector<std::pair<std::string, int>> renderer_hosts;  // host, count, in order of first appearance
  for (const auto& a : spec.actors)
    if (a.is_renderer()) {
      auto it = std::find_if(renderer_hosts.begin(), renderer_hosts.end(), [&](const auto& h) { return h.first == a.host; });
      if (it == renderer_hosts.end()) renderer_hosts.emplace_back(a.host, 1);
      else ++it->second;
    }
  std::vector<std::string> renderer_nodes;
  for (const auto& [host, count] : renderer_hosts) {
    renderer_nodes.push_back(renderer_hosts.size() == 1 ? std::string("renderers") : "renderers@" + host);
    by_host[host].push_back("    " + id(renderer_nodes.back()) + " [label=\"renderer × " + std::to_string(count) +
                            "\", shape=box3d];");
  }
  for (const auto& a : spec.actors) {
    if (a.is_renderer()) {
      continue;
    } else {
      // A pool its clients dispatch to is no process: drawn dashed, labelled "pool".
      const std::string shape = a.dispatched_by_clients ? ", shape=trapezium, style=dashed"
                                : a.is_multiplexer()    ? ", shape=trapezium"
                                : a.is_geometry()       ? ", shape=cylinder"
                                                        : "";
      const std::string kind = a.dispatched_by_clients ? "pool" : a.kind;
      const int64_t part = colocated_part(spec, static_cast<int>(&a - spec.actors.data()));
      const std::string holds = part >= 0 ? ", holds part " + std::to_string(part) : "";
      by_host[a.host].push_back("    " + id(a.name) + " [label=\"" + a.name + "\\n(" + kind + holds + ")\"" + shape + "];");
    }
  }
  for (const auto& [host, lines] : by_host) {
    out += "  subgraph \"cluster_" + host + "\" {\n    label=\"host " + host + "\";\n";
    for (const auto& l : lines) out += l + "\n";
    out += "  }\n";
  }
  out += "  film [shape=note, label=\"film\\n" + spec.image.output + "\"];\n";
  std::string ring_op;
  std::map<int64_t, std::string> ring_nodes;  // node number -> name
  int64_t rings = 1, length = 1;
  // Each arrow says which light paths it carries (farm/light_path_check.hpp).
  const std::vector<std::string> carried = light_path_summaries(spec);
  auto arrow = [&](int from) {
    const std::string& what = carried[static_cast<size_t>(from)];
    return what.empty() ? std::string(";\n") : " [label=\"" + what + "\"];\n";
  };
  for (const auto& a : spec.actors) {
    if (a.is_renderer()) continue;
    if (a.is_ring_node()) {
      auto param = [&](const char* key) { return a.params.count(key) ? a.params.at(key).as_int() : int64_t{1}; };
      ring_nodes[param("node")] = a.name;
      rings = param("rings");
      length = param("ring_length");
      continue;  // drawn as rings below, not as their all-to-all connections
    }
    if (a.kind == "radiosity") ring_op = a.name;
    for (int in : a.inputs) out += "  " + id(spec.actors[static_cast<size_t>(in)].name) + " -> " + id(a.name) + arrow(in);
  }
  // A partitioned scene: the parts answer the rays of the renderers and of the ops that trace through them
  // (dotted: rays, not light).
  std::vector<std::string> tracers = renderer_nodes;
  for (const auto& a : spec.actors)
    if (!a.is_renderer() && traces_through_parts(a)) tracers.push_back(a.name);
  for (const auto& g : spec.actors)
    if (g.is_geometry())
      for (const auto& t : tracers) out += "  " + id(g.name) + " -> " + id(t) + " [style=dotted, label=\"rays\"];\n";
  // A radiosity ring: packets go round each ring (solid), idle nodes borrow from the same position of another
  // ring (dashed), and the solution goes to the radiosity op (dotted).
  auto node_name = [&](int64_t r, int64_t p) {
    auto it = ring_nodes.find(r * length + p);
    return id(it == ring_nodes.end() ? "?" : it->second);
  };
  for (const auto& [node, name] : ring_nodes) {
    const int64_t r = node / length, p = node % length;
    if (length > 1) out += "  " + id(name) + " -> " + node_name(r, (p + 1) % length) + ";\n";
    if (rings > 1) out += "  " + id(name) + " -> " + node_name((r + 1) % rings, p) + " [style=dashed, dir=none];\n";
    if (!ring_op.empty()) out += "  " + id(name) + " -> " + id(ring_op) + " [style=dotted];\n";
  }
  for (const std::string& node : renderer_nodes) {
    if (spec.lighting >= 0)
      out += "  " + id(spec.actors[static_cast<size_t>(spec.lighting)].name) + " -> " + id(node) + arrow(spec.lighting);
    out += "  " + id(node) + " -> film;\n";
  }
  out += "}\n";
  return out;
}

}  // namespace lf
