#include "farm/light_path_check.hpp"

#include <algorithm>
#include <functional>
#include <optional>

#include "render/lightops/lightop_registry.hpp"

namespace lf {

namespace {

// What every actor's answer counts, composed from the ops without inputs up; nullopt where unknown, with why.
struct Composition {
  std::vector<std::optional<LightPaths>> paths;
  std::vector<std::string> unknown;  // per actor: why its paths are unknown (empty when known or not an op)
  std::vector<bool> done;
};

std::string undeclared(const ActorSpec& a) {
  return "'" + a.name + "' (" + a.kind + ") does not say which light paths it returns";
}

const std::optional<LightPaths>& compose(const FarmSpec& spec, int i, Composition& c) {
  const size_t at = static_cast<size_t>(i);
  if (c.done[at]) return c.paths[at];
  c.done[at] = true;  // a cycle (which validate() refuses) ends here as unknown
  const ActorSpec& a = spec.actors[at];
  if (a.is_multiplexer()) {
    // A pool answers as any of its replicas does.
    if (!a.inputs.empty()) {
      c.paths[at] = compose(spec, a.inputs[0], c);
      c.unknown[at] = c.unknown[static_cast<size_t>(a.inputs[0])];
    }
    return c.paths[at];
  }
  const LightOpKind* kind = a.runtime.count("cmd") ? nullptr : find_lightop_kind(a.kind);
  if (!kind) {
    c.unknown[at] = undeclared(a);
    return c.paths[at];
  }
  std::vector<LightPaths> inputs;
  for (int in : a.inputs) {
    const auto& p = compose(spec, in, c);
    if (!p) {
      c.unknown[at] = c.unknown[static_cast<size_t>(in)];
      return c.paths[at];
    }
    inputs.push_back(*p);
  }
  try {
    const auto op = kind->create(ParamTable(a.params, a.name));
    c.paths[at] = op->paths(inputs);
    if (!c.paths[at]) c.unknown[at] = undeclared(a);
  } catch (const std::exception& e) {
    c.unknown[at] = "'" + a.name + "': " + e.what();
  }
  return c.paths[at];
}

Composition compose_all(const FarmSpec& spec) {
  Composition c;
  c.paths.resize(spec.actors.size());
  c.unknown.resize(spec.actors.size());
  c.done.assign(spec.actors.size(), false);
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (!spec.actors[i].is_renderer() && !spec.actors[i].is_ring_node() && !spec.actors[i].is_geometry())
      compose(spec, static_cast<int>(i), c);
  return c;
}

// The paths of at least one event the scene allows whose count passes `keep`, shortest first.
template <class Keep>
std::vector<size_t> paths_where(const LightPaths& p, Lobes lobes, Keep keep) {
  std::vector<size_t> out;
  for (size_t i = 1; i < LightPaths::kPathCount; ++i)
    if (LightPaths::made_of(i, lobes) && keep(p.count_at(i))) out.push_back(i);
  return out;
}

std::vector<std::string> named(const std::vector<size_t>& paths) {
  std::vector<std::string> out;
  for (size_t i : paths) out.push_back(LightPaths::path_of(i));
  return out;
}

bool counts_twice(float count) { return count > 1.0f; }

bool counts_some_twice(const LightPaths& p, Lobes lobes) { return !paths_where(p, lobes, counts_twice).empty(); }

std::string list(const std::vector<std::string>& items, size_t at_most) {
  std::string s;
  for (size_t i = 0; i < items.size() && i < at_most; ++i) s += (s.empty() ? "" : ", ") + items[i];
  if (items.size() > at_most) s += ", and " + std::to_string(items.size() - at_most) + " more";
  return s;
}

std::string quoted_list(const std::vector<std::string>& names, size_t at_most) {
  std::vector<std::string> q;
  for (const auto& n : names) q.push_back("'" + n + "'");
  return list(q, at_most);
}

// Paths an op counts more than once although each of its inputs counts every path at most once: where a double
// count begins. For a combine, which inputs both carry each.
std::string doubled_here(const FarmSpec& spec, size_t at, const Composition& c, Lobes lobes) {
  const ActorSpec& a = spec.actors[at];
  const std::vector<size_t> doubled = paths_where(*c.paths[at], lobes, counts_twice);
  if (doubled.empty()) return {};
  // The inputs that carry the shortest of them (a combine's double count).
  std::vector<std::string> carriers;
  for (int in : a.inputs)
    if (c.paths[static_cast<size_t>(in)]->count_at(doubled[0]) > 0) carriers.push_back(spec.actors[static_cast<size_t>(in)].name);
  const std::string first = LightPaths::path_of(doubled[0]);
  const std::string why = carriers.size() >= 2 ? ": its inputs " + quoted_list(carriers, 4) + " each compute " + first : "";
  return a.loc.str() + ": '" + a.name + "' counts light twice (" + list(named(doubled), 4) + ")" + why +
         "; each light path must come from one input only (docs/lua-api.md, \"Light paths\")";
}

// A group of left-out paths, by the lobe at the point the camera sees and whether they are direct light.
struct Gap {
  const char* what;
  const char* supplied_by;
  Lobe lobe;
  std::vector<std::string> paths;
};

}  // namespace

std::string LightPathReport::error_text() const {
  std::string all;
  for (const auto& e : errors) all += (all.empty() ? "" : "\n") + e;
  return all;
}

// A cache that the scene's materials leave nothing to serve: a warning at its op's line (it would say 0 records or
// cells at the end, after the time its pre-pass took).
static void warn_about_empty_caches(const FarmSpec& spec, const SceneLobes& scene, LightPathReport& report) {
  for (const ActorSpec& a : spec.actors) {
    auto param = [&](const char* key) {
      auto it = a.params.find(key);
      return it != a.params.end() && it->second.is_bool() && it->second.as_bool();
    };
    const auto& diffuse = scene.materials[static_cast<int>(Lobe::diffuse)];
    if (a.kind == "pathtrace" && param("directional_cache") && diffuse.size() == scene.elevation_weighted.size())
      report.warnings.push_back(a.loc.str() + ": '" + a.name +
                                "' has directional_cache = true, but no material of the scene has a Lambert lobe (the "
                                "cache answers only rays a Lambert lobe sends; metal_rough materials' are traced): it "
                                "will answer nothing and only cost its filling pass");
    if (a.kind == "irradiance" && scene.materials[static_cast<int>(Lobe::diffuse)].empty())
      report.warnings.push_back(a.loc.str() + ": '" + a.name +
                                "' caches diffuse light, but no material of the scene reflects diffusely: it has "
                                "nothing to cache");
    if (a.kind == "radiosity" && !scene.elevation_weighted.empty())
      report.warnings.push_back(a.loc.str() + ": '" + a.name + "' takes metal_rough materials for black (" +
                                quoted_list(scene.elevation_weighted, 3) +
                                "): the light their bases reflect diffusely is not in its solution (an `irradiance` "
                                "op over a path tracer lights them)");
  }
}

LightPathReport check_light_paths(const FarmSpec& spec, const SceneLobes& scene) {
  LightPathReport report;
  if (spec.lighting >= 0) warn_about_empty_caches(spec, scene, report);
  if (spec.light_paths == "off" || spec.lighting < 0) return report;
  const Composition c = compose_all(spec);
  const size_t root = static_cast<size_t>(spec.lighting);
  const ActorSpec& lighting = spec.actors[root];
  if (!c.paths[root]) {
    report.warnings.push_back(lighting.loc.str() + ": the lighting network's light paths are not checked: " + c.unknown[root]);
    return report;
  }
  const LightPaths& seen = *c.paths[root];
  const Lobes lobes = scene.lobes;

  // Counted twice: at every op reachable from the lighting where it begins.
  if (counts_some_twice(seen, lobes)) {
    std::vector<bool> reached(spec.actors.size(), false);
    std::function<void(size_t)> visit = [&](size_t i) {
      if (reached[i]) return;
      reached[i] = true;
      for (int in : spec.actors[i].inputs) visit(static_cast<size_t>(in));
    };
    visit(root);
    for (size_t i = 0; i < spec.actors.size(); ++i) {
      if (!reached[i] || !c.paths[i] || spec.actors[i].is_multiplexer()) continue;
      bool inputs_once = true;
      for (int in : spec.actors[i].inputs) inputs_once = inputs_once && !counts_some_twice(*c.paths[static_cast<size_t>(in)], lobes);
      if (!inputs_once) continue;
      if (auto message = doubled_here(spec, i, c, lobes); !message.empty()) report.errors.push_back(message);
    }
    if (report.errors.empty())
      report.errors.push_back(lighting.loc.str() + ": the lighting network counts some light twice (" +
                              list(named(paths_where(seen, lobes, counts_twice)), 4) + ")");
  }
  if (seen.count("L") != 0)
    report.errors.push_back(lighting.loc.str() + ": '" + lighting.name +
                            "' answers with the shaded point's own emission (L), which the renderers add themselves: "
                            "the camera would see every emitter twice");

  if (spec.light_paths == "partial") return report;
  if (!scene.emits) {
    report.warnings.push_back(lighting.loc.str() + ": nothing in the scene emits light: the image will be black");
    return report;
  }
  Gap gaps[] = {
      {"direct light on diffuse surfaces", "direct", Lobe::diffuse, {}},
      {"direct light on glossy surfaces", "direct", Lobe::glossy, {}},
      {"light seen in mirrors and glass", "specular", Lobe::specular, {}},
      {"indirect light reflected by diffuse surfaces", "irradiance (a cache over the light leaving what it sees) or pathtrace", Lobe::diffuse, {}},
      {"indirect light reflected by glossy lobes", "glossy (over the light leaving what its lobe samples see)", Lobe::glossy, {}},
  };
  for (size_t i : paths_where(seen, lobes, [](float count) { return count == 0; })) {
    const std::string path = LightPaths::path_of(i);
    const char last = path.back();
    const bool direct = path.size() == 2;
    Gap& g = last == 'S' ? gaps[2] : last == 'D' ? gaps[direct ? 0 : 3] : gaps[direct ? 1 : 4];
    g.paths.push_back(path);
  }
  for (const Gap& g : gaps) {
    if (g.paths.empty()) continue;
    std::string message = lighting.loc.str() + ": the lighting network leaves out " + g.what + " (" + list(g.paths, 3) +
                          "), on " + quoted_list(scene.materials[static_cast<int>(g.lobe)], 3) +
                          ": no op computes it; a `" + g.supplied_by + "` op would";
    if (spec.light_paths == "complete") {
      report.errors.push_back(message);
    } else {
      message += " (farm { light_paths = \"partial\" } says a network computes part of the light on purpose)";
      report.warnings.push_back(message);
    }
  }
  return report;
}

std::vector<std::string> light_path_summaries(const FarmSpec& spec) {
  const Composition c = compose_all(spec);
  std::vector<std::string> out(spec.actors.size());
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (c.paths[i]) out[i] = c.paths[i]->summary();
  return out;
}

std::vector<std::optional<AnswerEnds>> answer_ends(const FarmSpec& spec) {
  const Composition c = compose_all(spec);
  std::vector<std::optional<AnswerEnds>> out(spec.actors.size());
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (c.paths[i]) out[i] = c.paths[i]->ends();
  return out;
}

}  // namespace lf
