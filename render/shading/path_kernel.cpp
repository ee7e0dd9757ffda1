#include "render/shading/path_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "render/shading/bsdf.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/surface.hpp"

namespace lf {

namespace {

struct Path {
  Vec3 x, n, wo;
  Vec3 above;  // where rays that leave x on the face's side start (Scene::ray_origin)
  Vec3 ng;     // the face's normal on n's side (n is the shading normal)
  RGB albedo;  // the diffuse reflectance here (a texture's, or the material's kd)
  uint32_t material;
  uint32_t triangle;  // UINT32_MAX: a point that names none
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
  const size_t n = points.size();
  const size_t per = static_cast<size_t>(o.samples);
  std::vector<Path> paths;
  paths.reserve(n * per);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 ng = points.face_normal(i, scene);
    const Vec3 above = scene.ray_origin(points.triangle_of(i), points.position[i], ng);
    const RGB albedo = points.albedo(i, scene, ctx.pixel_footprint(points.position[i]));
    const bool outside = points.outside(i, scene);
    for (size_t s = 0; s < per; ++s)
      paths.push_back(Path{points.position[i], points.normal[i], points.wo[i], above, ng, albedo, points.material[i],
                           points.triangle_of(i), outside, {1, 1, 1}, {},
                           Sampler(ctx.sampler, points.key[i], o.stream, static_cast<uint32_t>(s), static_cast<uint32_t>(per))});
  }

  std::vector<Ray> rays;
  std::vector<uint8_t> blocked;
  std::vector<Hit> hits;
  std::vector<Pending> pending;
  std::vector<size_t> continuing;
  std::vector<Bsdf::Sample> samples;

  // The directional cache's view of a diffuse vertex's direction wi towards a light's point `distance` away from
  // the ray's origin: whether a ray that way leaves the local neighbourhood before reaching it, and the cache
  // answers that direction.
  DirectionalCache* cache = o.cache;
  RGB cached{};
  // A glossy vertex with the cache takes its lobes one at a time, so that its diffuse lobe's rays are the cache's as a
  // diffuse surface's are (MIS then pairs each lobe's samples with the light samples' share of that lobe).
  auto by_lobe = [&](const Material& m) { return cache && m.type == Material::Type::glossy; };
  auto cache_answers = [&](const Path& path, const Material& m, Vec3 origin, Vec3 wi, float distance) {
    if (!cache || (m.type != Material::Type::diffuse && !by_lobe(m))) return false;
    const uint32_t cell = cache->cell_of(path.x);
    return distance > cache->local_reach(cell, origin, wi) && cache->lookup(cell, wi, cached);
  };
  struct Recording {
    size_t path;
    uint32_t cell;
    Vec3 direction;
    RGB before, beta;  // the path's light and throughput right after the hit beyond the neighbourhood
  };
  std::vector<Recording> recordings;
  std::vector<uint32_t> ray_cell;    // per continuation ray: its vertex's cell, or UINT32_MAX without the cache
  std::vector<uint8_t> ray_global;   // per continuation ray: it left the neighbourhood and was traced on
  std::vector<size_t> far_rays;
  std::vector<Ray> far_batch;
  std::vector<Hit> far_hits;

  // The paths still alive, in path order: each bounce visits only these (most paths end after a few bounces, and a
  // pass over every path at every depth cost more than the dead ones' share of the work).
  std::vector<uint32_t> active;
  active.reserve(paths.size());
  for (size_t p = 0; p < paths.size(); ++p)
    if (!o.dark_on_specular || !scene.material(paths[p].material).specular()) active.push_back(static_cast<uint32_t>(p));

  if (tally) tally->paths += paths.size();
  for (int depth = 1; depth <= o.max_depth && !active.empty(); ++depth) {
    if (tally) tally->vertices += active.size();
    // Next-event estimation.
    rays.clear();
    pending.clear();
    for (const uint32_t p : active) {
      Path& path = paths[p];
      const Material& m = scene.material(path.material);
      const Bsdf bsdf(m, path.albedo);
      if (bsdf.is_delta()) continue;
      path.rng.at_dimension(kSlotsPerVertex * (depth - 1));
      std::optional<LightSample> picked =
          o.light_tree ? sample_light_at(scene, path.x, path.n, path.rng, o.light_point, o.light_selection)
                       : sample_light(scene, path.rng);
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
      // The shadow ray runs between the two surfaces' offset points, so it neither starts below this one nor ends
      // beyond the light's.
      const Vec3 origin = path.above;
      const Vec3 target = ls.is_point ? ls.point : scene.ray_origin(ls.triangle, ls.point, ls.normal);
      const Vec3 to_light = target - origin;
      const float span = length(to_light);
      if (ls.is_point) {
        // A point light: I cos / d^2, and no BSDF sample can ever hit it, so no MIS.
        pending.push_back({p, path.beta * f * ls.radiance * (cos_x / (dist2 * ls.pdf_area))});
      } else {
        const float light_pdf = ls.pdf_area * dist2 / cos_y;  // per solid angle
        if (by_lobe(m)) {
          const float w_d = cache_answers(path, m, origin, wi, span)
                                ? 1.0f
                                : power_heuristic(light_pdf, bsdf.pdf_diffuse(path.n, path.wo, wi));
          const float w_g = power_heuristic(light_pdf, bsdf.pdf_glossy(path.n, path.wo, wi));
          const RGB fw = bsdf.eval_diffuse(path.n, path.wo, wi) * w_d + bsdf.eval_glossy(path.n, path.wo, wi) * w_g;
          pending.push_back({p, path.beta * fw * ls.radiance * (cos_x / light_pdf)});
        } else {
          const bool light_only = (o.light_only_on_diffuse && m.type == Material::Type::diffuse) ||
                                  cache_answers(path, m, origin, wi, span);
          const float w = light_only ? 1.0f : power_heuristic(light_pdf, bsdf.pdf(path.n, path.wo, wi));
          pending.push_back({p, path.beta * f * ls.radiance * (cos_x * w / light_pdf)});
        }
      }
      rays.push_back(Ray{origin, to_light / span, 0.0f, span});
    }
    blocked.resize(rays.size());
    if (!rays.empty()) co_await trace_occluded(ctx, rays, blocked);
    for (size_t r = 0; r < pending.size(); ++r)
      if (!blocked[r]) paths[pending[r].path].L += pending[r].contribution;

    // BSDF sampling: continue each path (and count lights it hits).
    rays.clear();
    continuing.clear();
    samples.clear();
    for (const uint32_t p : active) {
      Path& path = paths[p];
      const Material& m = scene.material(path.material);
      if (o.light_only_on_diffuse && o.max_depth == 1 && m.type == Material::Type::diffuse) {
        path.alive = false;
        continue;
      }
      path.rng.at_dimension(kSlotsPerVertex * (depth - 1) + 2);
      const float u0 = path.rng.uniform();
      const Uniform2 direction = path.rng.uniform2();
      const Bsdf bsdf(m, path.albedo);
      auto s = by_lobe(m) ? bsdf.sample_by_lobe(path.n, path.wo, u0, direction.u, direction.v)
                          : bsdf.sample(path.n, path.wo, path.outside, u0, direction.u, direction.v);
      // Only glass may send a path through the face; a reflection the shading normal allows below it ends here.
      // A diffuse or glossy surface's mirror term is the specular op's where specular surfaces are (`direct`).
      if (!s || is_black(s->weight) || (m.type != Material::Type::glass && dot(s->wi, path.ng) <= 0) ||
          (o.dark_on_specular && s->delta)) {
        path.alive = false;
        continue;
      }
      path.beta = path.beta * s->weight;
      path.bsdf_pdf = s->pdf;
      path.delta = s->delta;
      const bool through = dot(s->wi, path.ng) <= 0;  // refraction leaves through the back
      rays.push_back(Ray{through ? scene.ray_origin(path.triangle, path.x, -path.ng) : path.above, s->wi});
      continuing.push_back(p);
      samples.push_back(*s);
    }
    hits.resize(rays.size());
    ray_cell.assign(rays.size(), UINT32_MAX);
    ray_global.assign(rays.size(), 0);
    if (cache) {
      // Diffuse rays first look only as far as their neighbourhood reaches.
      for (size_t r = 0; r < continuing.size(); ++r) {
        const Path& path = paths[continuing[r]];
        if ((scene.material(path.material).type != Material::Type::diffuse && !samples[r].diffuse_lobe) ||
            samples[r].delta)
          continue;
        ray_cell[r] = cache->cell_of(path.x);
        rays[r].tfar = cache->local_reach(ray_cell[r], rays[r].origin, rays[r].direction);
      }
    }
    if (!rays.empty()) co_await trace_intersect(ctx, rays, hits);
    if (cache) {
      // Those that met nothing there: the cache answers, or they are traced on through the scene.
      far_rays.clear();
      far_batch.clear();
      for (size_t r = 0; r < continuing.size(); ++r) {
        if (ray_cell[r] == UINT32_MAX) continue;
        if (tally) ++tally->diffuse_rays;
        if (hits[r].valid()) {
          if (tally) ++tally->local_rays;
          continue;
        }
        Path& path = paths[continuing[r]];
        if (cache->lookup(ray_cell[r], rays[r].direction, cached)) {
          if (tally) ++tally->cache_lookups;
          path.L += path.beta * cached;
          path.alive = false;
          continue;
        }
        if (tally) ++tally->global_rays;
        ray_global[r] = 1;
        far_rays.push_back(r);
        // On from where the neighbourhood ended: the stretch before it is known to be empty, and in a partitioned
        // farm the parts it crossed need not be asked again.
        Ray on = rays[r];
        on.tnear = on.tfar;
        on.tfar = std::numeric_limits<float>::infinity();
        far_batch.push_back(on);
      }
      far_hits.resize(far_batch.size());
      if (!far_batch.empty()) co_await trace_intersect(ctx, far_batch, far_hits);
      for (size_t k = 0; k < far_rays.size(); ++k) hits[far_rays[k]] = far_hits[k];
    }
    for (size_t r = 0; r < continuing.size(); ++r) {
      Path& path = paths[continuing[r]];
      if (!path.alive) continue;  // answered by the cache
      if (!hits[r].valid()) {
        // Out of the scene: nothing comes from that direction, which the cache learns too.
        if (ray_global[r] && !cache->frozen()) cache->record(ray_cell[r], rays[r].direction, RGB{});
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
          const float pdf_area = o.light_tree ? light_pdf_area_at(scene, tri, path.x, path.n, o.light_point, hits[r].t, cos_y,
                                                                o.light_selection)
                                              : light_pdf_area(scene, tri);
          const float light_pdf = pdf_area * hits[r].t * hits[r].t / cos_y;
          w = power_heuristic(path.bsdf_pdf, light_pdf);
        }
        path.L += path.beta * hit_material.ke * w;
      }
      if (ray_global[r] && !cache->frozen())
        recordings.push_back({continuing[r], ray_cell[r], rays[r].direction, path.L, path.beta});
      if (depth == o.max_depth) {
        path.alive = false;
        continue;
      }
      if (depth >= o.rr_depth) {
        const float most = std::max({path.beta.x, path.beta.y, path.beta.z}) / o.rr_threshold;
        const float q = o.roulette == PathOptions::Roulette::sqrt ? std::min(1.0f, std::sqrt(most)) : std::min(0.95f, most);
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
      path.above = scene.ray_origin(tri, path.x, sp.ng);
      path.wo = wo;
      path.material = scene.material_of(tri);
      path.triangle = tri;
      path.albedo = hit_material.kd_map < 0 ? hit_material.kd : scene.albedo(tri, scene.barycentrics(tri, path.x), ctx.pixel_footprint(path.x));
      path.outside = front;
    }
    // Those that go on are among those that continued, in the same order.
    active.clear();
    for (const size_t p : continuing)
      if (paths[p].alive) active.push_back(static_cast<uint32_t>(p));
  }

  // What each global ray brought back beyond the hit it found (its reflected light, the emission there excluded):
  // the light gathered after it, over the throughput it arrived with. Recorded in path order.
  for (const Recording& rec : recordings) {
    const RGB after = paths[rec.path].L - rec.before;
    if (!(rec.beta.x > 0 && rec.beta.y > 0 && rec.beta.z > 0)) continue;  // a channel it cannot tell about
    cache->record(rec.cell, rec.direction, {after.x / rec.beta.x, after.y / rec.beta.y, after.z / rec.beta.z});
  }

  // Average each point's paths in sample order: the result does not depend on the batch.
  for (size_t i = 0; i < n; ++i) {
    RGB sum{};
    for (size_t s = 0; s < per; ++s) sum += paths[i * per + s].L;
    radiance[i] = sum * (1.0f / static_cast<float>(per));
  }
}

}  // namespace lf
