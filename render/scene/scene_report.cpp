#include "render/scene/scene_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <thread>

#include "render/shading/bsdf.hpp"
#include "render/shading/sampler.hpp"
#include "render/tracing/camera.hpp"
#include "render/lights/light_checks.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

namespace {

std::string format(const char* fmt, double a, double b = 0, double c = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}
std::string vec(Vec3 v) { return format("{%.4g, %.4g, %.4g}", v.x, v.y, v.z); }

const char* kind_name(Material::Type t) {
  switch (t) {
    case Material::Type::diffuse: return "diffuse";
    case Material::Type::glossy: return "glossy";
    case Material::Type::mirror: return "mirror";
    case Material::Type::glass: return "glass";
    case Material::Type::metal_rough: return "metal_rough";
  }
  return "?";
}

// Where to look from: the side of the scene whose visible surfaces face its light. From 8 directions around the
// bounding sphere (a little above it, +z first), a coarse 32 x 24 view counts the camera rays whose first hit is on
// the side of its surface that faces the emitters' centre (with no emitters: every hit); the first best wins. A
// fixed +z view looked at the back of a backdrop whose lamp and test object were on its -z side: an image of zeros.
Vec3 suggested_eye(const Scene& s, const RayTracer& tracer, Vec3 centre, float distance) {
  const auto eye_at = [&](int k) {
    const float az = static_cast<float>(k) * kPi / 4;
    return centre + normalize(Vec3{std::sin(az), 0.35f, std::cos(az)}) * distance;
  };
  Vec3 light{};
  double weight = 0;
  for (uint32_t t : s.emitters()) {
    const float a = s.area(t);
    light += (s.vertex(t, 0) + s.vertex(t, 1) + s.vertex(t, 2)) * (a / 3.0f);
    weight += a;
  }
  for (const auto& p : s.point_lights()) {
    light += p.position;
    weight += 1;
  }
  const bool lit = weight > 0;
  if (lit) light = light * static_cast<float>(1.0 / weight);
  int best = 0;
  size_t best_score = 0;
  constexpr int kWidth = 32, kHeight = 24;
  for (int k = 0; k < 8; ++k) {
    const Vec3 eye = eye_at(k);
    CameraSpec spec;
    spec.eye = {eye.x, eye.y, eye.z};
    spec.at = {centre.x, centre.y, centre.z};
    spec.fov = 45;
    const Camera camera(spec, kWidth, kHeight);
    std::vector<Ray> rays;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) rays.push_back(camera.ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f));
    std::vector<Hit> hits(rays.size());
    tracer.intersect(rays, hits);
    size_t score = 0;
    for (size_t r = 0; r < rays.size(); ++r) {
      if (!hits[r].valid()) continue;
      const Vec3 p = rays[r].origin + rays[r].direction * hits[r].t;
      Vec3 n = s.normal(hits[r].triangle);
      if (dot(n, rays[r].direction) > 0) n = -n;  // the side the camera sees
      score += !lit || dot(n, light - p) > 0;
    }
    if (score > best_score) best = k, best_score = score;
  }
  return eye_at(best);
}

// The share of the light-gathering rays of the surfaces a cache would serve that leave the scene: from points
// spread over the triangles whose materials have a diffuse lobe (by area), a cosine-distributed direction each on
// the side the triangle's winding faces, as an irradiance record's hemisphere would gather. Deterministic: the
// points and directions are seeded by their index.
double open_share(const Scene& s, const RayTracer& tracer) {
  std::vector<uint32_t> triangles;
  std::vector<double> cdf;
  double total = 0;
  for (uint32_t t = 0; t < s.triangle_count(); ++t)
    if (material_lobes(s.material(s.material_of(t))).contains(Lobe::diffuse) && s.area(t) > 0) {
      total += s.area(t);
      triangles.push_back(t);
      cdf.push_back(total);
    }
  if (triangles.empty()) return 0;
  constexpr int kRays = 4096;
  const float offset = 1e-4f * bounds_of(s.vertices()).diagonal();
  std::vector<Ray> rays;
  for (int i = 0; i < kRays; ++i) {
    Rng rng(static_cast<uint64_t>(i), 0x6f70656eu);  // "open"
    const double pick = rng.uniform() * total;
    const size_t k = std::min(static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()),
                              triangles.size() - 1);
    const uint32_t t = triangles[k];
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3 p = s.vertex(t, 0) * (1 - u - v) + s.vertex(t, 1) * u + s.vertex(t, 2) * v;
    const Vec3 n = s.normal(t);
    const Uniform2 d = rng.uniform2();
    rays.push_back({p + n * offset, cosine_hemisphere(n, d.u, d.v), 0.0f});
  }
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  size_t escaped = 0;
  for (const Hit& h : hits) escaped += !h.valid();
  return static_cast<double>(escaped) / kRays;
}

}  // namespace

std::string complete_network_for(const Lobes& lobes, const NetworkChoices& choices) {
  const int cores = choices.cores;
  const bool glossy = lobes.contains(Lobe::glossy), mirrors = lobes.contains(Lobe::specular);
  // An op that does most of the work is a pool of one replica a core: one process would leave the other cores
  // idle while it works (the cache's pre-pass is all bounce paths). On Lost Empire, 16 spp, two cores: 17.9 s
  // with one process each, 15.3 s with pools of two, the same image error.
  auto pooled = [&](const std::string& op) {
    return cores > 1 ? "multiplexer { " + op + ", replicas = " + std::to_string(cores) + " }" : op;
  };
  // Without a diffuse lobe no cache has anything to hold, and the ops left would be a path tracer cut into
  // processes: on glTF's material balls (glossy only) it reached Cycles' noise in 1.35x Cycles' time, the path
  // tracer alone in 0.83x (bench/peer/README.md).
  // Each line's comment (the light paths it counts) in one column.
  auto line = [](const std::string& code, const std::string& comment) {
    return code + std::string(code.size() < 66 ? 66 - code.size() : 1, ' ') + "-- " + comment + "\n";
  };
  if (!lobes.contains(Lobe::diffuse) || !choices.worth_caching)
    return line("renderers { lighting = " + pooled("lightop \"pathtrace\" {}") + " }", "no diffuse light worth a cache");
  std::string s = line("local paths    = " + pooled("lightop \"pathtrace\" {}"), "what leaves the surfaces the ops below see") +
                  line("local direct   = " +
                           pooled(choices.many_lights ? "lightop \"direct\" { light_samples = 2, light_sampling = \"learned\" }"
                                                      : "lightop \"direct\" {}"),
                       "L(D|G)") +
                  line("local indirect = lightop \"irradiance\" { input = paths }", "L(D|G|S)+D");
  std::string parts = "direct, indirect";
  if (glossy) {
    s += line("local shiny    = lightop \"glossy\" { input = paths }", "L(D|G|S)+G");
    parts += ", shiny";
  }
  if (mirrors) {
    s += line("local chains   = lightop \"specular\" { input = lightop \"combine\" { inputs = { " + parts + " } } }",
              "L(D|G|S)*S");
    parts += ", chains";
  }
  return s + "renderers { lighting = lightop \"combine\" { inputs = { " + parts + " } } }\n";
}

Result<std::string> describe_scene(const std::string& obj_path) {
  auto catalogue = Scene::catalogue_file(obj_path);
  if (!catalogue) return catalogue.error();
  auto scene = Scene::load_file_unlit(obj_path);
  if (!scene) return scene.error();
  if (scene->triangle_count() == 0) return make_error("scene file '" + obj_path + "' has no triangles");
  // With emitters of its own, how much of each one's flux meets nothing (light_checks.hpp).
  std::map<std::string, double> escaping;
  if (scene->finalize(obj_path).ok())
    for (const auto& e : light_escapes(*scene)) escaping[e.light] = e.escaping;
  const Scene& s = *scene;

  const Bounds bounds = bounds_of(s.vertices());
  const Vec3 lo = bounds.lo, hi = bounds.hi;
  struct Use {
    size_t faces = 0;
    double area = 0;
  };
  std::map<uint32_t, Use> used;
  for (uint32_t t = 0; t < s.triangle_count(); ++t) {
    Use& u = used[s.material_of(t)];
    ++u.faces;
    u.area += s.area(t);
  }

  std::string out = "scene file " + obj_path + "\n";
  out += "  triangles  " + std::to_string(s.triangle_count()) + "\n";
  out += "  bounds     " + vec(lo) + " to " + vec(hi) + format(", diagonal %.4g\n", bounds.diagonal());
  out += "  materials  " + std::to_string(s.materials().size() - 1) + " (+ a grey default for faces without one)\n";
  double total_flux = 0;
  size_t emitting_faces = 0;
  for (uint32_t m = 0; m < s.materials().size(); ++m) {
    const Material& mat = s.material(m);
    const auto it = used.find(m);
    if (mat.name == "(default)" && it == used.end()) continue;
    std::string line = "    " + mat.name + "  " + kind_name(mat.type) + "  kd " + vec(mat.kd);
    if (mat.type == Material::Type::metal_rough) {
      line += format("  metallic %.3g  roughness %.3g", mat.metallic, mat.roughness);
      if (mat.transmission > 0) line += format("  transmission %.3g  ior %.3g", mat.transmission, mat.ior);
    } else if (mat.type != Material::Type::diffuse) {
      line += "  ks " + vec(mat.ks);
    }
    line += "  faces " + std::to_string(it == used.end() ? 0 : it->second.faces);
    if (mat.emissive() && it != used.end()) {
      const double flux = kPi * it->second.area * average(mat.ke);  // one-sided Lambertian emitter
      total_flux += flux;
      emitting_faces += it->second.faces;
      line += "  emits " + vec(mat.ke) + format("  flux %.4g", flux);
      if (auto e = escaping.find("material '" + mat.name + "'"); e != escaping.end())
        line += format("  escaping %.0f%%", 100 * e->second);
    }
    out += line + "\n";
  }
  out += emitting_faces ? "  emitters   " + std::to_string(emitting_faces) + " triangles" + format(", flux %.4g\n", total_flux)
                        : "  emitters   none: add light { }, environment { }, sun { } or material \"Name\" { emission = "
                          "{r, g, b} } in the script\n";
  if (s.environment()) out += "  sky        " + s.environment()->describe() + "\n";  // a glTF's sun
  // One line per texture file: which statements use it, for how many materials, and whether it is there.
  struct TextureUse {
    std::map<std::string, int> slots;
    bool found = false;
  };
  std::map<std::string, TextureUse> files;
  for (const auto& t : catalogue->textures) {
    ++files[t.path].slots[t.slot];
    files[t.path].found = t.found;
  }
  size_t missing = 0;
  for (const auto& [path, u] : files) missing += !u.found;
  out += "  textures   " + std::to_string(files.size()) + " file" + (files.size() == 1 ? "" : "s") +
         (missing ? " (" + std::to_string(missing) + " missing)" : "") + "\n";
  for (const auto& [path, u] : files) {
    std::string slots;
    for (const auto& [slot, n] : u.slots) slots += (slots.empty() ? "" : ", ") + slot + " of " + std::to_string(n);
    out += "    " + path + "  " + slots + (u.found ? "" : "  (missing)") + "\n";
  }
  for (const auto& w : catalogue->warnings) out += "  warning    " + w + "\n";

  // A camera that frames the bounding sphere, a little above it, with a 45-degree field of view, from the side
  // whose surfaces face the light.
  const Vec3 centre = (lo + hi) * 0.5f;
  const float radius = 0.5f * bounds.diagonal();
  const float distance = radius / std::sin(0.5f * 45.0f * kPi / 180.0f);  // the sphere fits the view cone
  const RayTracer tracer(s);  // one BVH for the camera's probes and the open share
  const Vec3 eye = suggested_eye(s, tracer, centre, distance);
  out += "  camera     camera { eye = " + vec(eye) + ", at = " + vec(centre) + ", fov = 45 }\n";
  // A glTF file's own cameras, by the names camera { gltf = ... } takes; an animated one moves over a job's frames.
  for (const auto& c : catalogue->cameras)
    out += "             camera { gltf = \"" + c.name + "\" }" +
           (c.animated ? format("  (animated, %.3g s: frame n at n / fps)", c.animation_seconds) : std::string()) + "\n";

  // The lobes its materials have, and a network that counts every light path on them once (docs/lua-api.md,
  // "Light paths"); the farm checks whichever network the script wires against the same lobes.
  const SceneLobes lobes = scene_lobes(*scene);
  std::string present;
  static const char* kLobeNames[] = {"D (diffuse)", "G (glossy)", "S (mirror, glass)"};
  for (int l = 0; l < kLobeCount; ++l)
    if (lobes.lobes.has[l])
      present += (present.empty() ? "" : ", ") + std::string(kLobeNames[l]) + " on " +
                 std::to_string(lobes.materials[l].size()) + " material" + (lobes.materials[l].size() == 1 ? "" : "s");
  out += "  lobes      " + (present.empty() ? std::string("none") : present) + "\n";
  out += "  network    every light path on these lobes once:\n";
  // A cache is worth its pre-pass where some surface reflects diffusely: a Lambert lobe, or a dielectric base under
  // a metal_rough coating (not a metal's multiply scattered light alone).
  bool worth_caching = false;
  for (uint32_t t = 0; t < scene->triangle_count() && !worth_caching; ++t) {
    const Material& m = scene->material(scene->material_of(t));
    worth_caching = m.has_lambert_lobe() || (m.type == Material::Type::metal_rough && m.has_diffuse_lobe() && m.metallic < 1);
  }
  // Nor where most of what those surfaces gather comes from outside the scene (an object under an open sky): the
  // light that bounces between them, all a cache holds, is then the smaller part, and the paths a path tracer follows
  // end at the first or second bounce. On glTF's material balls under an HDRI (88 % open) the network's 1/(RMSE^2 s)
  // was 18.6 with a cache and 17.9 without, the path tracer's 48 (bench/RESULTS.md); Lost Empire (35 %) and the
  // Cornell boxes (15-19 %) are where the cache wins.
  const double open = open_share(s, tracer);
  out += format("  open       %.0f%% of the diffuse surfaces' gathering rays leave the scene\n", 100 * open);
  worth_caching = worth_caching && open <= 0.5;
  const int cores = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 64u));
  NetworkChoices choices;
  choices.worth_caching = worth_caching;
  choices.cores = cores;
  choices.many_lights = s.emitters().size() + s.point_lights().size() > 2;
  const std::string network = complete_network_for(lobes.lobes, choices);
  for (size_t at = 0; at < network.size();) {
    const size_t end = network.find('\n', at);
    out += "    " + network.substr(at, end - at) + "\n";
    at = end + 1;
  }
  return out;
}

}  // namespace lf
