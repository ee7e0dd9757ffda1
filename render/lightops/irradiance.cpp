// irradiance: Ward's irradiance caching with Ward & Heckbert's rotational and translational gradients. One input:
// the light leaving the surfaces a hemisphere sees (e.g. `direct`: then this op is one diffuse bounce of direct
// light; a radiosity solution: a final gather).
//
// Records: M x N stratified cosine-weighted hemisphere samples ask the input for radiance at the secondary hits;
// the record keeps E, the harmonic mean distance R (at most `nearest` times the nearest hit's distance) and both
// gradients, and serves points where
// |x - x_i| / R_i + sqrt(1 - n.n_i) < a, extrapolated with the gradients and weighted by 1 / that error.
// Determinism (an image must not depend on the farm's layout): records are made only in setup, by a pre-pass over
// candidate points in a fixed order — where the camera looks, where a camera-placed cache's hemisphere rays land (the
// overture), or `prepass` points spread over the scene's non-specular surfaces by area — in rounds: each round keeps
// the points the cache cannot yet serve, replicas of a pool each compute a contiguous share of them, and the shares are
// merged in order (all-gather), so every replica inserts the same records in the same order as a single op would. While
// rendering, a point the cache cannot serve (with `relax`, not even under 2a, then 4a) computes its own value from
// its own hemisphere samples and adds no record, so no point's value depends on which points came first.
// Output: Kd / pi * E on a Lambert lobe; on a metal_rough material, what its base and its conductor's multiply
// scattered light reflect of E, which they weigh by the elevation the light arrives from (the records keep E in
// elevation bands, render/shading/elevation_bands.hpp); nothing on mirrors and glass, nor for glossy lobes.
#include <algorithm>
#include <array>
#include <limits>
#include <cmath>

#include "render/byte_io.hpp"
#include "render/shading/bsdf.hpp"
#include "render/scene/surface.hpp"
#include "render/caches/irradiance_cache.hpp"
#include "render/lightops/derived_settings.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

constexpr std::string_view kCarriedTag = "LFIRRCACHE2";  // 2: records with elevation bands

bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

class Irradiance final : public LightOp {
 public:
  explicit Irradiance(const ParamTable& p)
      : a_(accuracy(p)),
        m_(strata(p, "theta", 2, 256)),
        n_(strata(p, "phi", 3, 1024)),
        prepass_(static_cast<uint32_t>(p.get_int("prepass", 20000, 0, 10000000))),
        placement_(placement_of(p.get_string("placement", "camera", {"camera", "area", "overture"}))),
        overture_rays_(static_cast<int>(p.get_int("overture_rays", 8, 1, 256))),
        stride_(static_cast<int>(p.get_int("stride", 8, 1, 64))),
        finest_(static_cast<int>(p.get_int("finest", 2, 1, 64))),
        min_spacing_(static_cast<float>(p.get_float("min_spacing", 0.002, 0, 1))),
        max_spacing_(static_cast<float>(p.get_float("max_spacing", 0.2, 0, 10))),
        min_reach_(static_cast<float>(p.get_float("min_reach", static_cast<double>(finest_), 0, 64))),
        own_rays_(static_cast<int>(p.get_int("own_rays", 2, 0, 1 << 16))),
        nearest_(static_cast<float>(p.get_float("nearest", 1.5, 0, 1000))),
        bounds_(bounds_up_to(p.get_float("relax", 1, 1, 4))),
        reuse_(p.get_bool("reuse", true)),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))) {}

  Task setup(SceneContext ctx, Inputs& inputs) override {
    ctx_ = ctx;
    const Scene& scene = *ctx.scene;
    // Hemisphere strata the script left unset (0) follow the image's lit samples a pixel.
    const HemisphereStrata derived = cache_hemisphere(ctx.lit_samples > 0 ? ctx.lit_samples : 16);
    if (m_ == 0) m_ = derived.theta;
    if (n_ == 0) n_ = derived.phi;
    if (a_ == 0) a_ = cache_accuracy(ctx.lit_samples > 0 ? ctx.lit_samples : 16);
    extent_ = scene.bounds().diagonal();
    cache_ = std::make_unique<IrradianceCache>(a_, extent_, bounds_.back());
    if (inputs.count() != 1) throw LightOpError("irradiance needs one input");

    if (placement_ == Placement::camera) {
      co_await place_seen(ctx, inputs);
      co_return;
    }
    const std::vector<Candidate> candidates = placement_ == Placement::overture ? overture_candidates(ctx) : area_candidates(scene);
    co_await place(ctx, candidates, every_round(candidates.size()), inputs);
  }

  // Records placed by the camera (or by where its records' rays land) follow the view; ones placed by area do not.
  bool setup_sees_camera() const override { return placement_ != Placement::area; }
  // A camera-placed cache keeps its records over a job's frames (Radiance's ambient file over a walkthrough) and
  // adds them only where the new view finds none that serve it; `reuse = false`: a cache of each frame's own.
  bool carries_views() const override { return placement_ == Placement::camera && reuse_; }
  Task extend_to_view(SceneContext ctx, Inputs& inputs) override {
    ctx_ = ctx;
    co_await place_seen(ctx, inputs);
  }
  std::unique_ptr<LightOp> fork_view() const override {
    auto copy = std::make_unique<Irradiance>(*this);
    if (cache_) copy->cache_ = std::make_shared<IrradianceCache>(*cache_);  // the copy's records are its own
    return copy;
  }
  // What a job's record keeps of the carried cache: its records in insertion order (lookups visit them in that order,
  // so inserting them again gives the same answers), after a tag and the record's size.
  std::string carried_state() const override {
    std::string state(kCarriedTag);
    bytes::put(state, static_cast<uint32_t>(sizeof(IrradianceRecord)));
    return state + IrradianceCache::serialize(cache_->records());
  }
  void restore_carried(std::string_view state) override {
    bytes::Reader in(state);
    std::string tag;
    uint32_t record_size = 0;
    std::vector<IrradianceRecord> records;
    if (!in.str(tag, static_cast<uint32_t>(kCarriedTag.size())) || tag != kCarriedTag || !in.u32(record_size) ||
        record_size != sizeof(IrradianceRecord) ||
        !IrradianceCache::deserialize(std::string(state.substr(kCarriedTag.size() + 4)), records))
      throw LightOpError(
          "irradiance: the kept cache is not one this build reads (remove the job folder's setups/ to replay the views)");
    // Records are placed where the octree's cells are computed from them: nothing a cache could not have made.
    for (const IrradianceRecord& r : records)
      if (!finite(r.position) || !finite(r.normal) || !(r.harmonic_distance > 0) || !std::isfinite(r.harmonic_distance))
        throw LightOpError("irradiance: a kept cache with a record no cache makes");
    auto cache = std::make_unique<IrradianceCache>(a_, extent_, bounds_.back());
    for (const IrradianceRecord& r : records) cache->insert(r);
    cache->freeze();
    cache_ = std::move(cache);
  }

  // records: the cache's size; lookups: diffuse points asked for; served_a/_2a/_4a: answered by records valid under
  // a, else under the relaxed bounds; own_values: points that paid for their own hemisphere (raise `prepass` or `a`
  // when this is more than a few percent).
  Value stats() const override {
    const uint64_t served = served_[0] + served_[1] + served_[2];
    return Value::Map{{"records", static_cast<int64_t>(cache_ ? cache_->size() : 0)},
                      {"lookups", static_cast<int64_t>(lookups_)},
                      {"served_a", static_cast<int64_t>(served_[0])},
                      {"served_2a", static_cast<int64_t>(served_[1])},
                      {"served_4a", static_cast<int64_t>(served_[2])},
                      {"own_values", static_cast<int64_t>(own_values_)},
                      {"records_per_lookup", served ? static_cast<double>(records_used_) / served : 0.0}};
  }

  // What the input gives at the hemisphere's hits, reflected by the point's diffuse lobe.
  std::optional<LightPaths> paths(std::span<const LightPaths> inputs) const override {
    return inputs.empty() ? LightPaths() : inputs[0].then(Lobe::diffuse);
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs& inputs) override {
    const Scene& scene = *ctx_.scene;
    std::vector<Candidate> misses;
    std::vector<size_t> miss_owner;
    for (size_t i = 0; i < points.size(); ++i) {
      radiance[i] = RGB{};
      const Material& m = scene.material(points.material[i]);
      if (!m.has_diffuse_lobe()) continue;
      // The records valid under a, else (with `relax`) under 2a and 4a: a point the cache barely misses then uses its
      // nearest records (deterministically: the cache does not change while rendering) instead of paying for its
      // own value. Such points lie mostly near what occludes them, where the records farther off are brighter.
      RGB e;
      uint32_t records = 0;
      // A Lambert lobe needs the irradiance alone; the others weigh it by elevation (Bsdf::reflect_bands).
      const bool lambert = m.has_lambert_lobe();
      ElevationBands bands;
      const int bound = cache_->lookup_first(points.position[i], points.normal[i], bounds_, e, &records,
                                             lambert ? nullptr : &bands);
      ++lookups_;
      if (bound >= 0) {
        ++served_[bound];
        records_used_ += records;
        radiance[i] = lambert ? points.albedo(i, scene, ctx_.pixel_footprint(points.position[i])) * e * (1.0f / kPi)
                              : reflected_by_bands(points, i, bands);
      } else {
        ++own_values_;
        misses.push_back(Candidate{points.position[i], points.normal[i], points.face_normal(i, scene),
                                   splitmix64(points.key[i] ^ 0x1e7), points.triangle_of(i)});
        miss_owner.push_back(i);
      }
    }
    if (misses.empty()) co_return;
    std::vector<IrradianceRecord> own;
    // Used once, never inserted: `own_rays` cosine-distributed rays (strata in azimuth), else a record's hemisphere.
    if (own_rays_ > 0) co_await compute(misses, inputs, own, 1, own_rays_);
    else co_await compute(misses, inputs, own, m_, n_);
    for (size_t j = 0; j < misses.size(); ++j) {
      const size_t i = miss_owner[j];
      radiance[i] = scene.material(points.material[i]).has_lambert_lobe()
                        ? points.albedo(i, scene, ctx_.pixel_footprint(points.position[i])) * own[j].irradiance * (1.0f / kPi)
                        : reflected_by_bands(points, i, own[j].bands);
    }
  }

  // What point i's diffuse lobes (a metal_rough material's base and its conductor's multiply scattered light)
  // reflect towards the camera of the irradiance `bands` bring.
  RGB reflected_by_bands(const ShadingPoints& points, size_t i, const ElevationBands& bands) const {
    const Scene& scene = *ctx_.scene;
    const Material& m = scene.material(points.material[i]);
    const float footprint = ctx_.pixel_footprint(points.position[i]);
    float metallic = 0, roughness = 0;
    points.metal_rough(i, scene, footprint, metallic, roughness);
    const Bsdf bsdf(m, points.albedo(i, scene, footprint), metallic, roughness, points.outside(i, scene));
    return bsdf.reflect_bands(points.normal[i], points.wo[i], bands);
  }

 private:
  uint64_t lookups_ = 0, own_values_ = 0, records_used_ = 0;
  uint64_t served_[3] = {0, 0, 0};
  struct Candidate {
    Vec3 x, n;  // n: the shading normal, which the record's hemisphere is around
    Vec3 ng;    // the face's normal on n's side
    uint64_t key;
    uint32_t triangle;  // UINT32_MAX: a point that names none
  };

  // Records computed together: a round's points cannot serve each other, and each round is a round trip to the input.
  static constexpr size_t kRoundSize = 512;
  // Round ends every kRoundSize candidates.
  static std::vector<size_t> every_round(size_t candidates) {
    std::vector<size_t> ends;
    for (size_t end = kRoundSize; end < candidates; end += kRoundSize) ends.push_back(end);
    ends.push_back(candidates);
    return ends;
  }
  // Where the camera looks, rounds ending only where a finer level of the camera's pixels begins: a view the
  // carried cache mostly serves already (a job's later frames: a few hundred open points among ~19,000) then
  // computes them in a round or two instead of one small round trip per 512 candidates (measured: 36 rounds,
  // 0.65 s with the cores mostly idle).
  Task place_seen(const SceneContext& ctx, Inputs& inputs) {
    std::vector<size_t> level_ends;
    const std::vector<Candidate> candidates = camera_candidates(ctx, level_ends);
    co_await place(ctx, candidates, level_ends, inputs);
  }

  // The pre-pass: candidates in order, a round at a time; the ones no record serves yet become records, computed
  // by the replicas in shares and gathered in candidate order. A round takes candidates until kRoundSize of them are
  // open (served by no record as the round begins) or one of `ends` is reached. Frozen afterwards (rendering only
  // reads it).
  Task place(const SceneContext& ctx, const std::vector<Candidate>& candidates, const std::vector<size_t>& ends,
             Inputs& inputs) {
    SoloExchange solo;
    Exchange& exchange = ctx.exchange ? *ctx.exchange : solo;
    const uint64_t total_candidates = candidates.size();
    auto round_end = ends.begin();
    for (size_t next = 0; next < candidates.size();) {
      ctx.report("cache pre-pass", next, total_candidates);
      while (round_end != ends.end() && *round_end <= next) ++round_end;
      const size_t stop = round_end == ends.end() ? candidates.size() : std::min(candidates.size(), *round_end);
      // The round's points the cache cannot serve yet become records.
      std::vector<Candidate> open;
      for (; next < stop && open.size() < kRoundSize; ++next) {
        RGB unused;
        if (!cache_->lookup(candidates[next].x, candidates[next].n, unused)) open.push_back(candidates[next]);
      }
      // This replica's contiguous share of the open points; shares concatenate back into candidate order.
      const size_t r = static_cast<size_t>(ctx.replica_index), count = static_cast<size_t>(ctx.replica_count);
      const size_t begin = open.size() * r / count, end = open.size() * (r + 1) / count;
      std::vector<IrradianceRecord> mine;
      co_await compute(std::span<const Candidate>(open.data() + begin, end - begin), inputs, mine, m_, n_);
      std::vector<std::string> parts;
      co_await exchange.all_gather(IrradianceCache::serialize(mine), &parts);
      for (const auto& part : parts) {
        std::vector<IrradianceRecord> records;
        if (!IrradianceCache::deserialize(part, records)) throw LightOpError("irradiance: a replica's records are malformed");
        for (const auto& rec : records) cache_->insert(rec);
      }
    }
    ctx.report("cache pre-pass", total_candidates, std::max<uint64_t>(total_candidates, 1));
    cache_->freeze();
  }

  // `prepass` points stratified over the area of non-emitting, non-specular triangles, in a fixed order (front
  // sides): for a cache whose points come from other ops' hemispheres, anywhere in the scene.
  std::vector<Candidate> area_candidates(const Scene& scene) const {
    std::vector<uint32_t> tris;
    std::vector<double> cdf;
    double total = 0;
    for (uint32_t t = 0; t < scene.triangle_count(); ++t) {
      const Material& m = scene.material(scene.material_of(t));
      if (!m.has_diffuse_lobe()) continue;
      total += scene.area(t);
      tris.push_back(t);
      cdf.push_back(total);
    }
    std::vector<Candidate> out;
    if (tris.empty()) return out;
    for (uint32_t c = 0; c < prepass_; ++c) {
      Rng rng(splitmix64(c), streams::irradiance ^ (seed_ << 8) ^ 0x9e37);
      const double target = (static_cast<double>(c) + rng.uniform()) / prepass_ * total;
      const size_t i =
          std::min(tris.size() - 1, static_cast<size_t>(std::lower_bound(cdf.begin(), cdf.end(), target) - cdf.begin()));
      const uint32_t t = tris[i];
      const float su = std::sqrt(rng.uniform()), v = rng.uniform();
      const Vec3 b{1 - su, su * (1 - v), su * v};
      const Vec3 x = scene.vertex(t, 0) * b.x + scene.vertex(t, 1) * b.y + scene.vertex(t, 2) * b.z;
      out.push_back(Candidate{x, scene.shading_normal(t, b), scene.normal(t), splitmix64(c ^ 0x1c), t});
    }
    return out;
  }

  // Where the camera looks: the first diffuse hit through pixel centres, coarse to fine — every `stride`-th pixel
  // in x and y, then the pixels of the grid at half that spacing not yet visited, down to every `finest`-th — so
  // that the pre-pass (which keeps only candidates no record serves yet) lays records over the whole view first and
  // then adds them only where the coarse ones do not reach: edges, small and thin things. Camera rays follow
  // mirrors and glass (refraction, else reflection) for up to 4 bounces as the specular op's rays go, and the
  // point is on the side the ray came from. The same on every replica and layout.
  // `level_ends`: where each level's candidates end (a level: the pixels of one stride).
  std::vector<Candidate> camera_candidates(const SceneContext& ctx, std::vector<size_t>& level_ends) const {
    if (!ctx.camera) throw LightOpError("irradiance: placement = \"camera\" or \"overture\" needs the farm's camera (use \"area\")");
    const Scene& scene = *ctx.scene;
    std::vector<Ray> rays;
    std::vector<uint64_t> level_first_ray;
    for (int step = stride_, coarser = 0; step >= std::min(finest_, stride_); coarser = step, step /= 2) {
      level_first_ray.push_back(rays.size());
      for (int y = 0; y < ctx.height; y += step)
        for (int x = 0; x < ctx.width; x += step) {
          if (coarser && x % coarser == 0 && y % coarser == 0) continue;  // a coarser level's pixel
          rays.push_back(ctx.camera->ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f));
        }
    }
    std::vector<std::pair<uint64_t, Candidate>> found;  // by camera ray
    std::vector<Hit> hits(rays.size());
    std::vector<uint64_t> ids(rays.size());
    for (size_t i = 0; i < ids.size(); ++i) ids[i] = i;
    for (int bounce = 0; bounce <= 4 && !rays.empty(); ++bounce) {
      hits.resize(rays.size());
      ctx.tracer->intersect(rays, hits);
      std::vector<Ray> next;
      std::vector<uint64_t> next_ids;
      for (size_t i = 0; i < rays.size(); ++i) {
        if (!hits[i].valid()) continue;
        const uint32_t t = hits[i].triangle;
        const Vec3 wo = -rays[i].direction;
        const Vec3 p = rays[i].origin + rays[i].direction * hits[i].t;
        const SurfacePoint sp = surface_at(scene, t, p, wo);
        const bool front = sp.front;
        const Vec3 n = sp.ng;
        const Material& m = scene.material(scene.material_of(t));
        if (!m.specular()) {
          if (m.has_diffuse_lobe()) found.emplace_back(ids[i], Candidate{p, sp.ns, sp.ng, splitmix64(ids[i] ^ 0xca3e5a), t});
          continue;
        }
        Vec3 dir = reflect(wo, n);
        if (m.type == Material::Type::glass)
          if (auto t_dir = refract(wo, n, front ? m.ior : 1.0f / m.ior)) dir = *t_dir;
        const Vec3 side = dot(dir, n) > 0 ? n : -n;
        next.push_back(Ray{scene.ray_origin(t, p, side), dir});
        next_ids.push_back(ids[i]);
      }
      rays = std::move(next);
      ids = std::move(next_ids);
    }
    // The camera rays' order (coarse to fine), whichever bounce found the point.
    std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Candidate> out;
    level_ends.clear();
    for (const auto& [id, c] : found) {
      while (level_ends.size() + 1 < level_first_ray.size() && id >= level_first_ray[level_ends.size() + 1])
        level_ends.push_back(out.size());
      out.push_back(c);
    }
    level_ends.push_back(out.size());
    return out;
  }

  // Ward's overture, for a cache that feeds another cache placed by the camera: where that cache's hemisphere rays
  // land. From every camera candidate (in their coarse-to-fine order), `overture_rays` stratified cosine-weighted
  // directions around its shading normal; their first diffuse hits, in that order, are the candidates. The same
  // on every replica and layout.
  std::vector<Candidate> overture_candidates(const SceneContext& ctx) const {
    const Scene& scene = *ctx.scene;
    std::vector<size_t> unused;
    const std::vector<Candidate> seen = camera_candidates(ctx, unused);
    const int per = overture_rays_;
    const int rows = std::max(1, static_cast<int>(std::sqrt(static_cast<float>(per)) / 1.7f + 0.5f));
    std::vector<Ray> rays;
    rays.reserve(seen.size() * static_cast<size_t>(per));
    for (const Candidate& c : seen) {
      Vec3 u, v;
      basis(c.n, u, v);
      const Vec3 origin = scene.ray_origin(c.triangle, c.x, c.ng);
      for (int q = 0; q < per; ++q) {
        Rng rng(c.key, streams::irradiance ^ (seed_ << 8) ^ 0x0e7u ^ (static_cast<uint64_t>(q) << 24));
        const float a = rng.uniform(), b = rng.uniform();
        const int j = q % rows, k = q / rows, cols = (per + rows - 1) / rows;
        Vec3 d = stratum_direction(j, k, rows, cols, a, b, u, v, c.n);
        if (dot(d, c.ng) <= 0) d = d - c.ng * (2 * dot(d, c.ng));  // below the face: its mirror image above
        rays.push_back(Ray{origin, d});
      }
    }
    std::vector<Hit> hits(rays.size());
    if (!rays.empty()) ctx.tracer->intersect(rays, hits);
    std::vector<Candidate> out;
    for (size_t r = 0; r < rays.size(); ++r) {
      if (!hits[r].valid()) continue;
      const uint32_t t = hits[r].triangle;
      const Material& m = scene.material(scene.material_of(t));
      if (!m.has_diffuse_lobe()) continue;
      const Vec3 x = rays[r].origin + rays[r].direction * hits[r].t;
      const SurfacePoint sp = surface_at(scene, t, x, -rays[r].direction);
      out.push_back(Candidate{x, sp.ns, sp.ng, splitmix64(seen[r / static_cast<size_t>(per)].key ^ (0x0e70000ull + r)), t});
    }
    return out;
  }

  // One record per candidate, from m x n hemisphere samples whose radiance comes from the input in one batch.
  Task compute(std::span<const Candidate> candidates, Inputs& inputs, std::vector<IrradianceRecord>& out, int m, int n) {
    const Scene& scene = *ctx_.scene;
    const size_t per = static_cast<size_t>(m * n);
    std::vector<Ray> rays;
    rays.reserve(candidates.size() * per);
    std::vector<std::array<Vec3, 3>> frames;
    for (const Candidate& c : candidates) {
      Vec3 u, v;
      basis(c.n, u, v);
      frames.push_back({u, v, c.n});
      const Vec3 origin = scene.ray_origin(c.triangle, c.x, c.ng);
      for (int j = 0; j < m; ++j)
        for (int k = 0; k < n; ++k) {
          Rng rng(c.key, streams::irradiance ^ (seed_ << 8) ^ (static_cast<uint64_t>(j * n + k) << 20));
          const float a = rng.uniform(), b = rng.uniform();
          rays.push_back(Ray{origin, stratum_direction(j, k, m, n, a, b, u, v, c.n)});
        }
    }
    std::vector<Hit> hits(rays.size());
    if (!rays.empty()) ctx_.tracer->intersect(rays, hits);
    ShadingPoints secondary;
    std::vector<int> slot(rays.size(), -1);
    for (size_t r = 0; r < rays.size(); ++r) {
      // A direction of the shading hemisphere below the face sees the surface's inside: no light from there.
      if (dot(rays[r].direction, candidates[r / per].ng) <= 0) hits[r] = Hit{};
      if (!hits[r].valid()) continue;
      const uint32_t tri = hits[r].triangle;
      const Vec3 wo = -rays[r].direction;
      const Vec3 x = rays[r].origin + rays[r].direction * hits[r].t;
      slot[r] = static_cast<int>(secondary.size());
      secondary.push_back(x, surface_at(scene, tri, x, wo).ns, wo, scene.material_of(tri),
                          splitmix64(candidates[r / per].key ^ (r % per + 1)), tri);
    }
    std::vector<RGB> arriving;
    if (secondary.size() > 0) co_await inputs.shade(0, secondary, arriving);
    const float min_r = min_spacing_ * extent_, max_r = max_spacing_ * extent_;
    for (size_t c = 0; c < candidates.size(); ++c) {
      HemisphereSamples s;
      s.m = m;
      s.n = n;
      s.radiance.resize(per);
      s.distance.resize(per);
      for (size_t q = 0; q < per; ++q) {
        const size_t r = c * per + q;
        s.radiance[q] = slot[r] >= 0 ? arriving[static_cast<size_t>(slot[r])] : RGB{};
        s.distance[q] = hits[r].valid() ? hits[r].t : max_r;
      }
      IrradianceRecord rec = make_record(candidates[c].x, frames[c][0], frames[c][1], frames[c][2], s);
      // E by the elevation of each ray's direction (cosine-weighted rays: pi / count each, as E sums them).
      for (size_t q = 0; q < per; ++q)
        rec.bands[static_cast<size_t>(elevation_band(dot(rays[c * per + q].direction, frames[c][2])))] +=
            s.radiance[q] * (kPi / static_cast<float>(per));
      // The near field: the harmonic mean weighs a near occluder by the solid angle it covers, not by the light it
      // takes away, so a record a little way from a panel hung under a ceiling reached under the panel's shadow
      // (+50 % there). R is at most `nearest` times the distance to the nearest thing the hemisphere hits (the
      // minimum distance of Tabellion & Lamorlette 2004, loosened).
      if (nearest_ > 0) {
        const float closest = *std::min_element(s.distance.begin(), s.distance.end());
        rec.harmonic_distance = std::min(rec.harmonic_distance, nearest_ * closest);
      }
      // Placed by the camera, at least `min_reach` pixels (the finest candidate spacing), so that the points between
      // candidates are served; a record widened so scales its translational gradient down by as much, or a record
      // near a small bright thing extrapolates its steep gradient over the pixels it now reaches (fireflies: 80 % of
      // the squared error on Lost Empire without the scaling).
      const float reach = placement_ == Placement::camera ? min_reach_ : 0.0f;
      float floor_r = std::max(min_r, record_radius_floor(ctx_, candidates[c].x, frames[c][2], reach, a_));
      // A record must not reach under something that overhangs its surface (the ceiling in the gap above a panel
      // hung 1 cm under it), which its hemisphere, cosine-weighted, hardly sees at such grazing angles; widened to
      // reach the camera's pixels, neither.
      const float overhang = overhang_distance(candidates[c], frames[c], a_ * std::max(floor_r, rec.harmonic_distance));
      rec.harmonic_distance = std::min(rec.harmonic_distance, overhang / a_);
      floor_r = std::max(min_r, std::min(floor_r, overhang / a_));
      const float unclamped = rec.harmonic_distance;
      rec.harmonic_distance = std::clamp(rec.harmonic_distance, std::min(floor_r, max_r), max_r);
      if (rec.harmonic_distance > unclamped)
        for (Vec3& g : rec.translational) g = g * (unclamped / rec.harmonic_distance);
      out.push_back(rec);
    }
  }

  // How far along its surface, within `reach`, candidate c's point is surely clear of anything overhanging it: a
  // surface facing back at it (within 45 degrees of parallel) met by rays at low elevations (slopes 1 down to 1/8,
  // a factor of sqrt 2 apart) in 8 directions. A wall beside it (perpendicular) does not count; infinity where
  // nothing overhangs.
  float overhang_distance(const Candidate& c, const std::array<Vec3, 3>& frame, float reach) const {
    constexpr int kAzimuths = 8;
    constexpr float kSlopes[] = {1.0f, 0.7071f, 0.5f, 0.3536f, 0.25f, 0.1768f, 0.125f};
    const Scene& scene = *ctx_.scene;
    const Vec3 origin = scene.ray_origin(c.triangle, c.x, c.ng);
    std::vector<Ray> rays;
    std::vector<float> cosines;
    for (int k = 0; k < kAzimuths; ++k) {
      const float phi = 2 * kPi * (static_cast<float>(k) + 0.5f) / kAzimuths;
      const Vec3 along = frame[0] * std::cos(phi) + frame[1] * std::sin(phi);
      for (float slope : kSlopes) {
        const float cos_e = 1 / std::sqrt(1 + slope * slope);
        Ray r{origin, normalize(along + frame[2] * slope)};
        r.tfar = reach / cos_e;
        rays.push_back(r);
        cosines.push_back(cos_e);
      }
    }
    std::vector<Hit> hits(rays.size());
    ctx_.tracer->intersect(rays, hits);
    float nearest = std::numeric_limits<float>::infinity();
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!hits[i].valid() || !(hits[i].t <= rays[i].tfar)) continue;
      const Vec3 x = rays[i].origin + rays[i].direction * hits[i].t;
      const Vec3 ng = surface_at(scene, hits[i].triangle, x, -rays[i].direction).ng;
      if (dot(ng, frame[2]) < -0.7071f) nearest = std::min(nearest, hits[i].t * cosines[i]);
    }
    // The ray one slope steeper crossed the overhang's height at 1/sqrt 2 of that distance without meeting it (or it
    // would be the nearest): its edge lies beyond that, which is where the record stops.
    return 0.7071f * nearest;
  }

  // A hemisphere's strata as set, or 0 (unset, or set to 0): derived in setup.
  // a as set, or 0 (unset, or set to 0): derived from the image's lit samples in setup.
  static float accuracy(const ParamTable& p) {
    const double a = p.get_float("a", 0, 0, 2.0);
    if (a != 0) p.get_float("a", 0.2, 0.01, 2.0);  // below 0.01: the range error
    return static_cast<float>(a);
  }
  static int strata(const ParamTable& p, const char* name, int64_t min, int64_t max) {
    const int64_t v = p.get_int(name, 0, 0, max);
    if (v != 0) p.get_int(name, 0, min, max);  // below min: the range error
    return static_cast<int>(v);
  }
  float a_;
  int m_, n_;
  uint32_t prepass_;
  enum class Placement { camera, area, overture };
  static Placement placement_of(const std::string& name) {
    return name == "camera" ? Placement::camera : name == "area" ? Placement::area : Placement::overture;
  }
  Placement placement_;
  int overture_rays_;
  int stride_, finest_;
  float min_spacing_, max_spacing_;
  float min_reach_;
  int own_rays_;
  float nearest_;  // R <= nearest * the nearest hit's distance; 0: the harmonic mean alone
  // The bounds a lookup tries in turn, as multiples of a: {1}, {1, 2} or {1, 2, 4}.
  std::vector<float> bounds_;
  bool reuse_;
  static std::vector<float> bounds_up_to(double relax) {
    std::vector<float> b{1.0f};
    for (float f = 2.0f; f <= relax + 1e-6; f *= 2) b.push_back(f);
    return b;
  }
  uint64_t seed_;
  float extent_ = 1;
  SceneContext ctx_;
  std::shared_ptr<IrradianceCache> cache_;  // copyable with the op; fork_view() gives the copy a cache of its own
};

}  // namespace

extern const LightOpKind irradiance_kind{
    .name = "irradiance",
    .summary = "Ward irradiance caching with irradiance gradients over its input's light",
    .min_inputs = 1,
    .max_inputs = 1,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Irradiance>(p); },
    .shares_setup = true};

}  // namespace lf
