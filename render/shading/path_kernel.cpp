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
  float metallic, roughness;  // a metal_rough material's here (its maps', or its factors)
  uint32_t material;
  uint32_t triangle;  // UINT32_MAX: a point that names none
  bool outside;
  bool light_only;    // a diffuse first vertex that takes light samples alone (PathOptions::light_only_on_diffuse)
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

// One batch of paths advanced a bounce at a time (a wavefront), in named stages; trace_paths below runs them and
// traces each stage's rays as one batch.
class Wavefront {
 public:
  Wavefront(const SceneContext& ctx, const ShadingPoints& points, const PathOptions& o, PathTally* tally)
      : ctx_(ctx), scene_(*ctx.scene), o_(o), tally_(tally), cache_(o.cache), per_(static_cast<size_t>(o.samples)) {
    start(points);
  }

  bool alive() const { return !active_.empty(); }
  void count_vertices() {
    if (tally_) tally_->vertices += active_.size();
  }

  // Next-event estimation: a light sample for every live non-delta vertex, its shadow ray in `rays`.
  void sample_lights(int depth) {
    rays.clear();
    pending_.clear();
    for (const uint32_t p : active_) sample_light_for(p, depth);
    blocked.resize(rays.size());
  }
  // The light of the unblocked samples.
  void add_unblocked_light() {
    for (size_t r = 0; r < pending_.size(); ++r)
      if (!blocked[r]) paths_[pending_[r].path].L += pending_[r].contribution;
  }

  // BSDF sampling: each path's continuation ray in `rays` (with the cache, a diffuse ray only as far as its
  // neighbourhood reaches).
  void sample_continuations(int depth);
  // With the cache: the continuation rays that met nothing in their neighbourhood are answered by the cache, or go
  // on through the scene as `far_batch`. True when there is such a batch to trace.
  bool answer_from_cache();
  void take_far_hits() {
    for (size_t k = 0; k < far_rays_.size(); ++k) hits[far_rays_[k]] = far_hits[k];
  }
  // Where each continuation landed: the emission it hit (with MIS), Russian roulette, the next vertex.
  void land(int depth);

  // What each global ray brought back beyond the hit it found (its reflected light, the emission there excluded):
  // the light gathered after it, over the throughput it arrived with. Recorded in path order.
  void record_into_cache();
  // Each point's paths averaged in sample order: the result does not depend on the batch.
  void average(std::span<RGB> radiance) const;

  std::vector<Ray> rays, far_batch;
  std::vector<uint8_t> blocked;
  std::vector<Hit> hits, far_hits;

 private:
  struct Recording {
    size_t path;
    uint32_t cell;
    Vec3 direction;
    RGB before, beta;  // the path's light and throughput right after the hit beyond the neighbourhood
  };

  void start(const ShadingPoints& points);
  void sample_light_for(uint32_t p, int depth);
  // Next-event estimation towards the environment: a direction, its shadow ray open-ended.
  void sample_environment_for(uint32_t p, const Path& path, const Material& m, const Bsdf& bsdf, const LightSample& ls);
  // A glossy vertex with the cache takes its lobes one at a time, so that its diffuse lobe's rays are the cache's as
  // a diffuse surface's are (MIS then pairs each lobe's samples with the light samples' share of that lobe).
  bool by_lobe(const Material& m) const { return cache_ && m.type == Material::Type::glossy; }
  // What light selection knows of a vertex: the normal it faces, or none (zero: any side) where the surface
  // transmits along rough lobes and gathers light from both sides; there the learned cells, which are per side,
  // are left out. Light samples and the MIS weights of emitters hit later both ask through these.
  Vec3 facing(const Path& path) const { return scene_.material(path.material).transmits() ? Vec3{} : path.n; }
  const LightSelection* selection_for(const Path& path) const {
    return scene_.material(path.material).transmits() ? nullptr : o_.light_selection;
  }
  // Whether a light sample's direction wi can reach the vertex's BSDF: above both normals, or, where the surface
  // transmits, below both; `below` then says which. A direction between the two normals reaches neither side.
  static bool reachable(const Path& path, const Bsdf& bsdf, Vec3 wi, bool& below) {
    below = false;
    if (above_both(wi, path.n, path.ng)) return true;
    below = bsdf.transmits() && above_both(-wi, path.n, path.ng);
    return below;
  }
  // Where rays towards wi leave the vertex: above its face, or below it for light it transmits.
  Vec3 origin_towards(const Path& path, bool below) const {
    return below ? scene_.ray_origin(path.triangle, path.x, -path.ng) : path.above;
  }
  // The directional cache's view of a diffuse vertex's direction wi towards a light's point `distance` away from
  // the ray's origin: whether a ray that way leaves the local neighbourhood before reaching it, and the cache
  // answers that direction.
  bool cache_answers(const Path& path, const Material& m, Vec3 origin, Vec3 wi, float distance) {
    if (!cache_ || (m.type != Material::Type::diffuse && !by_lobe(m))) return false;
    const uint32_t cell = cache_->cell_of(path.x);
    return distance > cache_->local_reach(cell, origin, wi) && cache_->lookup(cell, wi, cached_);
  }

  const SceneContext& ctx_;
  const Scene& scene_;
  const PathOptions& o_;
  PathTally* tally_;
  DirectionalCache* cache_;
  size_t per_;
  size_t points_ = 0;
  std::vector<Path> paths_;
  // The paths still alive, in path order: each bounce visits only these (most paths end after a few bounces, and a
  // pass over every path at every depth cost more than the dead ones' share of the work).
  std::vector<uint32_t> active_;
  std::vector<Pending> pending_;
  std::vector<size_t> continuing_;
  std::vector<Bsdf::Sample> samples_;
  RGB cached_{};
  std::vector<Recording> recordings_;
  std::vector<uint32_t> ray_cell_;   // per continuation ray: its vertex's cell, or UINT32_MAX without the cache
  std::vector<uint8_t> ray_global_;  // per continuation ray: it left the neighbourhood and was traced on
  std::vector<size_t> far_rays_;
};

void Wavefront::start(const ShadingPoints& points) {
  points_ = points.size();
  paths_.reserve(points_ * per_);
  for (size_t i = 0; i < points_; ++i) {
    const Vec3 ng = points.face_normal(i, scene_);
    const Vec3 above = scene_.ray_origin(points.triangle_of(i), points.position[i], ng);
    const float footprint = ctx_.pixel_footprint(points.position[i]);
    const RGB albedo = points.albedo(i, scene_, footprint);
    float metallic, roughness;
    points.metal_rough(i, scene_, footprint, metallic, roughness);
    const bool outside = points.outside(i, scene_);
    // A point that names no triangle starts its rays a coarse epsilon() above it, which a BSDF ray near a light
    // would see brighter than the light samples do: it keeps light samples alone.
    const bool light_only = o_.light_only_on_diffuse && scene_.material(points.material[i]).type == Material::Type::diffuse &&
                            !(o_.mis_near && points.triangle_of(i) != UINT32_MAX && o_.mis_near->near(points.position[i]));
    for (size_t s = 0; s < per_; ++s)
      paths_.push_back(Path{points.position[i], points.normal[i], points.wo[i], above, ng, albedo, metallic, roughness,
                            points.material[i],
                            points.triangle_of(i), outside, light_only, {1, 1, 1}, {},
                            Sampler(ctx_.sampler, points.key[i], o_.stream, static_cast<uint32_t>(s), static_cast<uint32_t>(per_))});
  }
  active_.reserve(paths_.size());
  for (size_t p = 0; p < paths_.size(); ++p)
    if (!o_.dark_on_specular || !scene_.material(paths_[p].material).specular()) active_.push_back(static_cast<uint32_t>(p));
  if (tally_) tally_->paths += paths_.size();
}

void Wavefront::sample_light_for(uint32_t p, int depth) {
  Path& path = paths_[p];
  const Material& m = scene_.material(path.material);
  const Bsdf bsdf(m, path.albedo, path.metallic, path.roughness, path.outside);
  if (bsdf.is_delta()) return;
  path.rng.at_dimension(kSlotsPerVertex * (depth - 1));
  std::optional<LightSample> picked =
      o_.light_tree ? sample_light_at(scene_, path.x, facing(path), path.rng, o_.light_point, selection_for(path))
                   : sample_light(scene_, path.rng);
  if (!picked) return;
  const LightSample& ls = *picked;
  if (ls.at_infinity) {
    sample_environment_for(p, path, m, bsdf, ls);
    return;
  }
  const Vec3 d = ls.point - path.x;
  const float dist2 = dot(d, d);
  if (!(dist2 > 0)) return;
  const Vec3 wi = d / std::sqrt(dist2);
  const float cos_y = ls.is_point ? 1.0f : -dot(ls.normal, wi);
  bool below;
  if (!reachable(path, bsdf, wi, below) || cos_y <= 0) return;
  const float cos_x = std::fabs(dot(path.n, wi));
  const RGB f = bsdf.eval(path.n, path.wo, wi);
  if (is_black(f)) return;
  // The shadow ray runs between the two surfaces' offset points, so it neither starts on the wrong side of this
  // one nor ends beyond the light's.
  const Vec3 origin = origin_towards(path, below);
  const Vec3 target = ls.is_point ? ls.point : scene_.ray_origin(ls.triangle, ls.point, ls.normal);
  const Vec3 to_light = target - origin;
  const float span = length(to_light);
  if (ls.is_point) {
    // A point light: I cos / d^2, and no BSDF sample can ever hit it, so no MIS.
    const RGB intensity = ls.radiance_towards(path.x);
    if (is_black(intensity)) return;  // outside a spot's cone
    pending_.push_back({p, path.beta * f * intensity * (cos_x / (dist2 * ls.pdf_area))});
  } else {
    const float light_pdf = ls.pdf_area * dist2 / cos_y;  // per solid angle
    if (by_lobe(m)) {
      const float w_d = cache_answers(path, m, origin, wi, span)
                            ? 1.0f
                            : power_heuristic(light_pdf, bsdf.pdf_diffuse(path.n, path.wo, wi));
      const float w_g = power_heuristic(light_pdf, bsdf.pdf_glossy(path.n, path.wo, wi));
      const RGB fw = bsdf.eval_diffuse(path.n, path.wo, wi) * w_d + bsdf.eval_glossy(path.n, path.wo, wi) * w_g;
      pending_.push_back({p, path.beta * fw * ls.radiance * (cos_x / light_pdf)});
    } else {
      const bool light_only = path.light_only || cache_answers(path, m, origin, wi, span);
      const float w = light_only ? 1.0f : power_heuristic(light_pdf, bsdf.pdf(path.n, path.wo, wi));
      pending_.push_back({p, path.beta * f * ls.radiance * (cos_x * w / light_pdf)});
    }
  }
  rays.push_back(Ray{origin, to_light / span, 0.0f, span});
}

void Wavefront::sample_environment_for(uint32_t p, const Path& path, const Material& m, const Bsdf& bsdf,
                                       const LightSample& ls) {
  const Vec3 wi = ls.direction;
  bool below;
  if (is_black(ls.radiance) || !(ls.pdf_area > 0) || !reachable(path, bsdf, wi, below)) return;
  const float cos_x = std::fabs(dot(path.n, wi));
  const float light_pdf = ls.pdf_area;  // per solid angle already
  const float span = std::numeric_limits<float>::infinity();
  // The same weights as an area light's (sample_light_for): the directional cache answers only light reflected
  // beyond its neighbourhood, so a direction it answers leaves the environment's light to this sample alone.
  RGB fw;
  if (by_lobe(m)) {
    const float w_d = cache_answers(path, m, path.above, wi, span) ? 1.0f
                                                                   : power_heuristic(light_pdf, bsdf.pdf_diffuse(path.n, path.wo, wi));
    const float w_g = power_heuristic(light_pdf, bsdf.pdf_glossy(path.n, path.wo, wi));
    fw = bsdf.eval_diffuse(path.n, path.wo, wi) * w_d + bsdf.eval_glossy(path.n, path.wo, wi) * w_g;
  } else {
    const bool light_only = path.light_only || cache_answers(path, m, path.above, wi, span);
    fw = bsdf.eval(path.n, path.wo, wi) * (light_only ? 1.0f : power_heuristic(light_pdf, bsdf.pdf(path.n, path.wo, wi)));
  }
  if (is_black(fw)) return;
  pending_.push_back({p, path.beta * fw * ls.radiance * (cos_x / light_pdf)});
  rays.push_back(Ray{origin_towards(path, below), wi, 0.0f, span});
}

void Wavefront::sample_continuations(int depth) {
  rays.clear();
  continuing_.clear();
  samples_.clear();
  for (const uint32_t p : active_) {
    Path& path = paths_[p];
    const Material& m = scene_.material(path.material);
    if (path.light_only && o_.max_depth == 1) {
      path.alive = false;
      continue;
    }
    path.rng.at_dimension(kSlotsPerVertex * (depth - 1) + 2);
    const float u0 = path.rng.uniform();
    const Uniform2 direction = path.rng.uniform2();
    const Bsdf bsdf(m, path.albedo, path.metallic, path.roughness, path.outside);
    auto s = by_lobe(m) ? bsdf.sample_by_lobe(path.n, path.wo, u0, direction.u, direction.v)
                        : bsdf.sample(path.n, path.wo, path.outside, u0, direction.u, direction.v);
    // Only glass, smooth or rough, may send a path through the face; a reflection the shading normal allows below
    // it ends here, and so does a refraction it allows above. A diffuse or glossy surface's mirror term is the
    // specular op's where specular surfaces are (`direct`).
    auto leaves_well = [&](Vec3 wi) {
      if (m.type == Material::Type::glass) return true;
      if (bsdf.transmits()) return above_both(wi, path.n, path.ng) || above_both(-wi, path.n, path.ng);
      return dot(wi, path.ng) > 0;
    };
    if (!s || is_black(s->weight) || !leaves_well(s->wi) || (o_.dark_on_specular && s->delta)) {
      path.alive = false;
      continue;
    }
    path.beta = path.beta * s->weight;
    path.bsdf_pdf = s->pdf;
    path.delta = s->delta;
    const bool through = dot(s->wi, path.ng) <= 0;  // refraction leaves through the back
    rays.push_back(Ray{scene_.ray_origin_along(path.triangle, path.x, through ? -path.ng : path.ng, s->wi), s->wi});
    continuing_.push_back(p);
    samples_.push_back(*s);
  }
  hits.resize(rays.size());
  ray_cell_.assign(rays.size(), UINT32_MAX);
  ray_global_.assign(rays.size(), 0);
  if (cache_) {
    // Diffuse rays first look only as far as their neighbourhood reaches.
    for (size_t r = 0; r < continuing_.size(); ++r) {
      const Path& path = paths_[continuing_[r]];
      if ((scene_.material(path.material).type != Material::Type::diffuse && !samples_[r].diffuse_lobe) ||
          samples_[r].delta)
        continue;
      ray_cell_[r] = cache_->cell_of(path.x);
      rays[r].tfar = cache_->local_reach(ray_cell_[r], rays[r].origin, rays[r].direction);
    }
  }
}

bool Wavefront::answer_from_cache() {
  if (!cache_) return false;
  // Those that met nothing there: the cache answers, or they are traced on through the scene.
  far_rays_.clear();
  far_batch.clear();
  for (size_t r = 0; r < continuing_.size(); ++r) {
    if (ray_cell_[r] == UINT32_MAX) continue;
    if (tally_) ++tally_->diffuse_rays;
    if (hits[r].valid()) {
      if (tally_) ++tally_->local_rays;
      continue;
    }
    Path& path = paths_[continuing_[r]];
    if (cache_->lookup(ray_cell_[r], rays[r].direction, cached_)) {
      if (tally_) ++tally_->cache_lookups;
      path.L += path.beta * cached_;
      path.alive = false;
      continue;
    }
    if (tally_) ++tally_->global_rays;
    ray_global_[r] = 1;
    far_rays_.push_back(r);
    // On from where the neighbourhood ended: the stretch before it is known to be empty, and in a partitioned
    // farm the parts it crossed need not be asked again.
    Ray on = rays[r];
    on.tnear = on.tfar;
    on.tfar = std::numeric_limits<float>::infinity();
    far_batch.push_back(on);
  }
  far_hits.resize(far_batch.size());
  return !far_batch.empty();
}

void Wavefront::land(int depth) {
  for (size_t r = 0; r < continuing_.size(); ++r) {
    Path& path = paths_[continuing_[r]];
    if (!path.alive) continue;  // answered by the cache
    if (!hits[r].valid()) {
      // Out of the scene: the environment's light from there (weighed against its light samples), and nothing
      // reflected, which the cache learns (it holds reflected light only).
      if (scene_.environment_share() > 0) {
        const Vec3 wi = rays[r].direction;
        const RGB le = scene_.environment()->radiance(wi);
        if (!is_black(le)) {
          const float share = o_.light_tree ? environment_share_at(scene_, path.x, facing(path), selection_for(path))
                                            : scene_.environment_share();
          path.L += path.beta * le * (path.delta ? 1.0f : power_heuristic(path.bsdf_pdf, environment_pdf(scene_, wi, share)));
        }
      }
      if (ray_global_[r] && !cache_->frozen()) cache_->record(ray_cell_[r], rays[r].direction, RGB{});
      path.alive = false;
      continue;
    }
    const uint32_t tri = hits[r].triangle;
    const Vec3 wo = -rays[r].direction;
    const Vec3 ng = scene_.normal(tri);
    const bool front = dot(ng, wo) > 0;
    const Material& hit_material = scene_.material(scene_.material_of(tri));
    if (hit_material.emissive() && front) {
      float w = 1.0f;
      if (!path.delta) {
        // The light's density for this direction as a light sample from the vertex would have it: the distance
        // from the vertex, not from the ray's origin above it. The origin's offset (1e-4 of the scene for a point
        // that names no triangle, 128 units of the coordinates' precision otherwise) would otherwise unbalance
        // the weights by twice its share of the distance: 1.2 % under a light 1 away on a 100-wide floor.
        const float dist = length(rays[r].origin + rays[r].direction * hits[r].t - path.x);
        const float cos_y = dot(ng, wo);
        const float pdf_area = o_.light_tree ? light_pdf_area_at(scene_, tri, path.x, facing(path), o_.light_point,
                                                              dist, cos_y, selection_for(path))
                                            : light_pdf_area(scene_, tri);
        const float light_pdf = pdf_area * dist * dist / cos_y;
        w = power_heuristic(path.bsdf_pdf, light_pdf);
      }
      path.L += path.beta * scene_.emission_at(tri, rays[r].origin + rays[r].direction * hits[r].t) * w;
    }
    if (ray_global_[r] && !cache_->frozen())
      recordings_.push_back({continuing_[r], ray_cell_[r], rays[r].direction, path.L, path.beta});
    if (depth == o_.max_depth) {
      path.alive = false;
      continue;
    }
    if (depth >= o_.rr_depth) {
      const float most = std::max({path.beta.x, path.beta.y, path.beta.z}) / o_.rr_threshold;
      const float q = o_.roulette == PathOptions::Roulette::sqrt ? std::min(1.0f, std::sqrt(most)) : std::min(0.95f, most);
      path.rng.at_dimension(kSlotsPerVertex * (depth - 1) + 4);
      if (path.rng.uniform() >= q) {
        path.alive = false;
        continue;
      }
      path.beta *= 1.0f / q;
    }
    path.x = rays[r].origin + rays[r].direction * hits[r].t;
    const SurfacePoint sp = surface_at(scene_, tri, path.x, wo);
    path.n = sp.ns;
    path.ng = sp.ng;
    path.above = scene_.ray_origin(tri, path.x, sp.ng);
    path.wo = wo;
    path.material = scene_.material_of(tri);
    path.triangle = tri;
    path.albedo = hit_material.kd;
    path.metallic = hit_material.metallic;
    path.roughness = hit_material.roughness;
    const bool metal_rough_maps = hit_material.metallic_map >= 0 || hit_material.roughness_map >= 0;
    if (hit_material.kd_map >= 0 || metal_rough_maps) {  // textures: where on the triangle, once for all of them
      const Vec3 b = scene_.barycentrics(tri, path.x);
      const float footprint = ctx_.pixel_footprint(path.x);
      if (hit_material.kd_map >= 0) path.albedo = scene_.albedo(tri, b, footprint);
      if (metal_rough_maps) scene_.metal_rough_at(tri, b, footprint, path.metallic, path.roughness);
    }
    path.outside = front;
  }
  // Those that go on are among those that continued, in the same order.
  active_.clear();
  for (const size_t p : continuing_)
    if (paths_[p].alive) active_.push_back(static_cast<uint32_t>(p));
}

void Wavefront::record_into_cache() {
  for (const Recording& rec : recordings_) {
    const RGB after = paths_[rec.path].L - rec.before;
    if (!(rec.beta.x > 0 && rec.beta.y > 0 && rec.beta.z > 0)) continue;  // a channel it cannot tell about
    cache_->record(rec.cell, rec.direction, {after.x / rec.beta.x, after.y / rec.beta.y, after.z / rec.beta.z});
  }
}

void Wavefront::average(std::span<RGB> radiance) const {
  for (size_t i = 0; i < points_; ++i) {
    RGB sum{};
    for (size_t s = 0; s < per_; ++s) sum += paths_[i * per_ + s].L;
    radiance[i] = sum * (1.0f / static_cast<float>(per_));
  }
}

}  // namespace

Task trace_paths(const SceneContext& ctx, const ShadingPoints& points, std::span<RGB> radiance, const PathOptions& o,
                 PathTally* tally) {
  Wavefront w(ctx, points, o, tally);
  for (int depth = 1; depth <= o.max_depth && w.alive(); ++depth) {
    w.count_vertices();
    w.sample_lights(depth);
    if (!w.rays.empty()) co_await trace_occluded(ctx, w.rays, w.blocked);
    w.add_unblocked_light();
    w.sample_continuations(depth);
    if (!w.rays.empty()) co_await trace_intersect(ctx, w.rays, w.hits);
    if (w.answer_from_cache()) co_await trace_intersect(ctx, w.far_batch, w.far_hits);
    w.take_far_hits();
    w.land(depth);
  }
  w.record_into_cache();
  w.average(radiance);
}

}  // namespace lf
