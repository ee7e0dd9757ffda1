#include "render/lights/light_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "render/shading/bsdf.hpp"
#include "render/shading/sampler.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

namespace {

constexpr int kRays = 1024;  // per light: the share is then known to about +-3 %

double escaping_share(const RayTracer& tracer, std::vector<Ray>& rays) {
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  size_t escaped = 0;
  for (const Hit& h : hits) escaped += h.valid() ? 0 : 1;
  return rays.empty() ? 0.0 : static_cast<double>(escaped) / static_cast<double>(rays.size());
}

}  // namespace

std::vector<LightEscape> light_escapes(const Scene& scene, const std::vector<std::string>& point_light_labels) {
  std::vector<LightEscape> out;
  if (scene.emitters().empty() && scene.point_lights().empty()) return out;
  const RayTracer tracer(scene);
  // Emitter triangles by material, with their areas' running sum for picking one in proportion.
  std::map<uint32_t, std::vector<uint32_t>> by_material;
  for (uint32_t t : scene.emitters()) by_material[scene.material_of(t)].push_back(t);
  for (const auto& [material, triangles] : by_material) {
    std::vector<double> cdf;
    double total = 0;
    for (uint32_t t : triangles) cdf.push_back(total += scene.area(t));
    Rng rng(material, streams::light_check);
    std::vector<Ray> rays;
    for (int i = 0; i < kRays; ++i) {
      const double pick = rng.uniform() * total;
      const size_t k = std::min(static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin()),
                                triangles.size() - 1);
      const uint32_t t = triangles[k];
      const float su = std::sqrt(rng.uniform()), v = rng.uniform();
      const Vec3 y = scene.vertex(t, 0) * (1 - su) + scene.vertex(t, 1) * (su * (1 - v)) + scene.vertex(t, 2) * (su * v);
      const Vec3 n = scene.normal(t);
      const float a = rng.uniform(), b = rng.uniform();
      rays.push_back(Ray{scene.ray_origin(t, y, n), cosine_hemisphere(n, a, b)});  // emitted flux goes as the cosine
    }
    const std::string& name = scene.material(material).name;
    // A script light's material is named after its line ("light at farm.lua:12"): the warning starts there.
    out.push_back({name.rfind("light at ", 0) == 0 ? name.substr(9) + ": light" : "material '" + name + "'",
                   escaping_share(tracer, rays)});
  }
  const auto& points = scene.point_lights();
  for (size_t p = 0; p < points.size(); ++p) {
    Rng rng(p, streams::light_check ^ 0x9e37);
    std::vector<Ray> rays;
    const PointLight& light = points[p];
    Vec3 t, b;  // a spot's frame
    if (light.spot()) basis(light.axis, t, b);
    for (int i = 0; i < kRays; ++i) {
      // Uniform over the sphere, or over a spot's outer cone.
      const float span = light.spot() ? 1 - light.cos_outer : 2.0f;
      const float z = 1 - span * rng.uniform(), phi = 2 * kPi * rng.uniform();
      const float r = std::sqrt(std::max(0.0f, 1 - z * z));
      rays.push_back(Ray{light.position, light.spot() ? t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + light.axis * z
                                                      : Vec3{r * std::cos(phi), r * std::sin(phi), z}});
    }
    const size_t first_labelled = points.size() - std::min(points.size(), point_light_labels.size());
    const std::string label = p >= first_labelled ? point_light_labels[p - first_labelled]
                                                  : "point light " + std::to_string(p + 1);
    out.push_back({label, escaping_share(tracer, rays)});
  }
  return out;
}

std::vector<std::string> escaping_light_warnings(const std::vector<LightEscape>& escapes, double threshold) {
  std::vector<std::string> out;
  for (const auto& e : escapes) {
    if (e.escaping <= threshold) continue;
    char share[16];
    std::snprintf(share, sizeof share, "%.0f%%", 100 * e.escaping);
    out.push_back(e.light + ": " + share + " of its flux leaves the scene without meeting a surface (wound the "
                  "wrong way, or outside the geometry?)");
  }
  return out;
}

}  // namespace lf
