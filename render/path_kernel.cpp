#include "render/path_kernel.hpp"

#include <algorithm>

#include "render/bsdf.hpp"
#include "render/light_sampling.hpp"
#include "render/sampler.hpp"
#include "render/surface.hpp"

namespace lf {

namespace {

struct Path {
  Vec3 x, n, wo;
  Vec3 ng;     // the face's normal on n's side (n is the shading normal)
  RGB albedo;  // the diffuse reflectance here (a texture's, or the material's kd)
  uint32_t material;
  bool outside;
  RGB beta{1, 1, 1};  // throughput
  RGB L{};            // gathered radiance
  Sampler rng;
  bool alive = true;
  // The BSDF sample that led here, for MIS at an emitter hit.
  float bsdf_pdf = 0;
  bool delta = false;
};

struct Pending {
  size_t path;
  RGB contribution;
};

// A vertex's draws, each a fixed dimension slot of the Sobol sampler: the light's pick, its point (2D), the BSDF's
// lobe, its direction (2D), Russian roulette.
constexpr uint32_t kSlotsPerVertex = 5;

}  // namespace

Task trace_paths(const SceneContext& ctx, const ShadingPoints& points, std::span<RGB> radiance, const PathOptions& o,
                 PathTally* tally) {
  const Scene& scene = *ctx.scene;
  const float eps = scene.epsilon();
  const size_t n = points.size();
  const size_t per = static_cast<size_t>(o.samples);
  std::vector<Path> paths;
  paths.reserve(n * per);
  for (size_t i = 0; i < n; ++i)
    for (size_t s = 0; s < per; ++s)
      paths.push_back(Path{points.position[i], points.normal[i], points.wo[i], points.face_normal(i, scene),
                           points.albedo(i, scene, ctx.pixel_footprint(points.position[i])), points.material[i], points.outside(i, scene), {1, 1, 1}, {},
                           Sampler(ctx.sampler, points.key[i], o.stream, static_cast<uint32_t>(s), static_cast<uint32_t>(per))});

  std::vector<Ray> rays;
  std::vector<uint8_t> blocked;
  std::vector<Hit> hits;
  std::vector<Pending> pending;
  std::vector<size_t> continuing;
  std::vector<Bsdf::Sample> samples;

  if (tally) tally->paths += paths.size();
  for (int depth = 1; depth <= o.max_depth; ++depth) {
    if (tally)
      for (const Path& path : paths) tally->vertices += path.alive ? 1 : 0;
    // Next-event estimation.
    rays.clear();
    pending.clear();
    for (size_t p = 0; p < paths.size(); ++p) {
      Path& path = paths[p];
      if (!path.alive) continue;
      const Material& m = scene.material(path.material);
      const Bsdf bsdf(m, path.albedo);
      if (bsdf.is_delta()) continue;
      path.rng.at_dimension(kSlotsPerVertex * (depth - 1));
      std::optional<LightSample> picked =
          o.light_tree ? sample_light_at(scene, path.x, path.n, path.rng) : sample_light(scene, path.rng);
      if (!picked) continue;
      const LightSample& ls = *picked;
      const Vec3 d = ls.point - path.x;
      const float dist2 = dot(d, d);
      if (!(dist2 > 0)) continue;
      const Vec3 wi = d / std::sqrt(dist2);
      const float cos_x = dot(path.n, wi);
      const float cos_y = ls.is_point ? 1.0f : -dot(ls.normal, wi);
      if (!above_both(wi, path.n, path.ng) || cos_y <= 0) continue;
      const RGB f = bsdf.eval(path.n, path.wo, wi);
      if (is_black(f)) continue;
      if (ls.is_point) {
        // A point light: I cos / d^2, and no BSDF sample can ever hit it, so no MIS.
        pending.push_back({p, path.beta * f * ls.radiance * (cos_x / (dist2 * ls.pdf_area))});
      } else {
        const float light_pdf = ls.pdf_area * dist2 / cos_y;  // per solid angle
        const bool light_only = o.light_only_on_diffuse && m.type == Material::Type::diffuse;
        const float w = light_only ? 1.0f : power_heuristic(light_pdf, bsdf.pdf(path.n, path.wo, wi));
        pending.push_back({p, path.beta * f * ls.radiance * (cos_x * w / light_pdf)});
      }
      const Vec3 origin = path.x + path.ng * eps;
      const Vec3 to_light = ls.point - origin;
      const float span = length(to_light);
      rays.push_back(Ray{origin, to_light / span, 0.0f, ls.is_point ? span : span - eps});
    }
    blocked.resize(rays.size());
    if (!rays.empty()) {
      if (ctx.tracing) co_await ctx.tracing->occluded(rays, blocked);
      else ctx.tracer->occluded(rays, blocked);
    }
    for (size_t r = 0; r < pending.size(); ++r)
      if (!blocked[r]) paths[pending[r].path].L += pending[r].contribution;

    // BSDF sampling: continue each path (and count lights it hits).
    rays.clear();
    continuing.clear();
    samples.clear();
    for (size_t p = 0; p < paths.size(); ++p) {
      Path& path = paths[p];
      if (!path.alive) continue;
      const Material& m = scene.material(path.material);
      if (o.light_only_on_diffuse && o.max_depth == 1 && m.type == Material::Type::diffuse) {
        path.alive = false;
        continue;
      }
      path.rng.at_dimension(kSlotsPerVertex * (depth - 1) + 2);
      const float u0 = path.rng.uniform();
      const Uniform2 direction = path.rng.uniform2();
      auto s = Bsdf(m, path.albedo).sample(path.n, path.wo, path.outside, u0, direction.u, direction.v);
      // Only glass may send a path through the face; a reflection the shading normal allows below it ends here.
      if (!s || is_black(s->weight) || (m.type != Material::Type::glass && dot(s->wi, path.ng) <= 0)) {
        path.alive = false;
        continue;
      }
      path.beta = path.beta * s->weight;
      path.bsdf_pdf = s->pdf;
      path.delta = s->delta;
      const Vec3 side = dot(s->wi, path.ng) > 0 ? path.ng : -path.ng;  // refraction leaves through the back
      rays.push_back(Ray{path.x + side * eps, s->wi});
      continuing.push_back(p);
      samples.push_back(*s);
    }
    hits.resize(rays.size());
    if (!rays.empty()) {
      if (ctx.tracing) co_await ctx.tracing->intersect(rays, hits);
      else ctx.tracer->intersect(rays, hits);
    }
    for (size_t r = 0; r < continuing.size(); ++r) {
      Path& path = paths[continuing[r]];
      if (!hits[r].valid()) {
        path.alive = false;
        continue;
      }
      const uint32_t tri = hits[r].triangle;
      const Vec3 wo = -rays[r].direction;
      const Vec3 ng = scene.normal(tri);
      const bool front = dot(ng, wo) > 0;
      const Material& hit_material = scene.material(scene.material_of(tri));
      if (hit_material.emissive() && front) {
        float w = 1.0f;
        if (!path.delta) {
          const float cos_y = dot(ng, wo);
          const float pdf_area = o.light_tree ? light_pdf_area_at(scene, tri, path.x, path.n) : light_pdf_area(scene, tri);
          const float light_pdf = pdf_area * hits[r].t * hits[r].t / cos_y;
          w = power_heuristic(path.bsdf_pdf, light_pdf);
        }
        path.L += path.beta * hit_material.ke * w;
      }
      if (depth == o.max_depth) {
        path.alive = false;
        continue;
      }
      if (depth >= o.rr_depth) {
        const float q = std::min(0.95f, std::max({path.beta.x, path.beta.y, path.beta.z}));
        path.rng.at_dimension(kSlotsPerVertex * (depth - 1) + 4);
        if (path.rng.uniform() >= q) {
          path.alive = false;
          continue;
        }
        path.beta *= 1.0f / q;
      }
      path.x = rays[r].origin + rays[r].direction * hits[r].t;
      const SurfacePoint sp = surface_at(scene, tri, path.x, wo);
      path.n = sp.ns;
      path.ng = sp.ng;
      path.wo = wo;
      path.material = scene.material_of(tri);
      path.albedo = hit_material.kd_map < 0 ? hit_material.kd : scene.albedo(tri, scene.barycentrics(tri, path.x), ctx.pixel_footprint(path.x));
      path.outside = front;
    }
  }

  // Average each point's paths in sample order: the result does not depend on the batch.
  for (size_t i = 0; i < n; ++i) {
    RGB sum{};
    for (size_t s = 0; s < per; ++s) sum += paths[i * per + s].L;
    radiance[i] = sum * (1.0f / static_cast<float>(per));
  }
}

}  // namespace lf
