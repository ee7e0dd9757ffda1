// pathtrace: an unbiased path tracer — next-event estimation with multiple importance sampling at every vertex,
// BSDF sampling through diffuse, glossy, mirror and glass surfaces, Russian roulette (render/shading/path_kernel.cpp).
// The reference the other LightOps are checked against. No inputs.
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/path_kernel.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/surface.hpp"

namespace lf {
namespace {

// Paths end by Russian roulette; max_depth only bounds the pathological (a closed box of white walls). 8, the old
// default, left out 2 % of a glossy-walled Cornell box's light (its paths were measured with max_depth 64): a
// path after 100 events carries at most 0.95^100 = 0.6 % of its light on surfaces that reflect 95 %.
constexpr int kDefaultMaxDepth = 100;

class PathTrace final : public LightOp {
 public:
  explicit PathTrace(const ParamTable& p) {
    options_.max_depth = static_cast<int>(p.get_int("max_depth", kDefaultMaxDepth, 1, 1024));
    options_.rr_depth = static_cast<int>(p.get_int("rr_depth", 3, 1, 1024));
    options_.roulette = p.get_string("roulette", "sqrt", {"sqrt", "throughput"}) == "sqrt" ? PathOptions::Roulette::sqrt
                                                                                             : PathOptions::Roulette::throughput;
    options_.rr_threshold = static_cast<float>(p.get_float("rr_threshold", options_.rr_threshold, 1e-6, 1));
    options_.samples = static_cast<int>(p.get_int("samples", 1, 1, 1 << 16));
    const LightSampling light_sampling = read_light_sampling(p);
    options_.light_tree = light_sampling != LightSampling::power;
    learned_ = light_sampling == LightSampling::learned;
    selection_options_ = light_selection_options(p, static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX)));
    options_.light_point = p.get_string("light_point", "area", {"area", "solid_angle"}) == "solid_angle"
                               ? LightPoint::solid_angle
                               : LightPoint::area;
    options_.stream = streams::pathtrace ^ (static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX)) << 8);
    use_cache_ = p.get_bool("directional_cache", false);
    reuse_ = p.get_bool("reuse", true);
    cache_options_.cells = static_cast<int>(p.get_int("cache_cells", cache_options_.cells, 1, 256));
    cache_options_.radius = static_cast<float>(p.get_float("cache_radius", cache_options_.radius, 0, 1e9));
    cache_options_.min_samples = static_cast<int>(p.get_int("cache_min_samples", cache_options_.min_samples, 2, 1 << 16));
    cache_options_.uniform_depth = static_cast<int>(p.get_int("cache_uniform_depth", cache_options_.uniform_depth, 0, 12));
    cache_options_.max_depth = static_cast<int>(p.get_int("cache_max_depth", cache_options_.max_depth, 0, 12));
    cache_options_.max_relative_spread =
        static_cast<float>(p.get_float("cache_spread", cache_options_.max_relative_spread, 0, 1e9));
    fill_spp_ = static_cast<int>(p.get_int("cache_fill_spp", 4, 1, 1 << 16));
    fill_stride_ = static_cast<int>(p.get_int("cache_fill_stride", 2, 1, 64));
    if (cache_options_.max_depth < cache_options_.uniform_depth)
      throw ParamError("pathtrace: cache_max_depth must be at least cache_uniform_depth");
  }

  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    if (learned_) {
      co_await LightSelection::build(ctx, selection_options_, selection_, "pathtrace");
      options_.light_selection = &selection_;
    }
    if (use_cache_) co_await fill_cache();
  }

  // Lights are learned, and the directional cache filled, where the camera looks.
  bool setup_sees_camera() const override { return learned_ || use_cache_; }
  // Learned lights alone are carried over a job's frames as `direct` carries them (`reuse`); a directional cache
  // is filled anew for each view.
  bool carries_views() const override { return learned_ && !use_cache_ && reuse_; }
  Task extend_to_view(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    co_await selection_.extend(ctx, selection_options_, "pathtrace");
  }
  std::unique_ptr<LightOp> fork_view() const override {
    if (use_cache_) return nullptr;
    auto copy = std::make_unique<PathTrace>(*this);
    if (options_.light_selection) copy->options_.light_selection = &copy->selection_;  // its own, not this one's
    return copy;
  }
  std::string carried_state() const override { return selection_.state(); }
  void restore_carried(std::string_view state) override {
    selection_.restore(state, *ctx_.scene, "pathtrace");
  }

  // Every path of up to max_depth events (Russian roulette ends paths without leaving any out).
  std::optional<LightPaths> paths(std::span<const LightPaths>) const override {
    return LightPaths::every(1, options_.max_depth);
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    co_await trace_paths(ctx_, points, radiance, options_, &tally_);
  }

  Value stats() const override {
    Value::Map m{{"paths", static_cast<int64_t>(tally_.paths)},
                 {"mean_path_vertices", tally_.paths ? static_cast<double>(tally_.vertices) / tally_.paths : 0.0}};
    if (learned_) selection_.add_stats(m);
    if (cache_) {
      // Seed 002's Table 3, for the render (the fill pass's own rays apart).
      const double far = static_cast<double>(tally_.global_rays + tally_.cache_lookups);
      m["diffuse_rays"] = static_cast<int64_t>(tally_.diffuse_rays);
      m["local_rays"] = static_cast<int64_t>(tally_.local_rays);
      m["global_rays"] = static_cast<int64_t>(tally_.global_rays);
      m["cache_lookups"] = static_cast<int64_t>(tally_.cache_lookups);
      m["cache_hit_ratio"] = far > 0 ? static_cast<double>(tally_.cache_lookups) / far : 0.0;
      m["cache_cells"] = static_cast<int64_t>(cache_->cells_used());
      m["cache_nodes"] = static_cast<int64_t>(cache_->nodes());
      m["fill_global_rays"] = static_cast<int64_t>(fill_tally_.global_rays);
      m["fill_cache_lookups"] = static_cast<int64_t>(fill_tally_.cache_lookups);
    }
    return m;
  }

 private:
  // The cache is filled before rendering, from paths started where the camera looks (the first hit through every
  // `cache_fill_stride`-th pixel, `cache_fill_spp` paths each), batch after batch in pixel order, recording as it
  // goes and answering where it already can (the paper's on-the-fly filling); then it is frozen, so that rendering
  // only reads it and no pixel depends on another, or on the farm's layout.
  Task fill_cache() {
    if (!ctx_.camera) throw LightOpError("pathtrace: directional_cache needs the farm's camera");
    cache_ = std::make_unique<DirectionalCache>(*ctx_.scene, cache_options_);
    PathOptions fill = options_;
    fill.cache = cache_.get();
    fill.samples = fill_spp_;
    fill.stream = options_.stream ^ 0x6c0ffee5u;  // numbers of their own, apart from the render's
    const Scene& scene = *ctx_.scene;
    std::vector<Ray> rays;
    std::vector<uint64_t> pixels;
    for (int y = 0; y < ctx_.height; y += fill_stride_)
      for (int x = 0; x < ctx_.width; x += fill_stride_) {
        rays.push_back(ctx_.camera->ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f));
        pixels.push_back(static_cast<uint64_t>(y) * static_cast<uint64_t>(ctx_.width) + static_cast<uint64_t>(x));
      }
    std::vector<Hit> hits(rays.size());
    co_await trace_intersect(ctx_, rays, hits);
    ShadingPoints batch;
    std::vector<RGB> ignored;
    constexpr size_t kBatch = 1024;
    for (size_t i = 0; i <= rays.size(); ++i) {
      if (i < rays.size() && hits[i].valid()) {
        const uint32_t tri = hits[i].triangle;
        const Vec3 wo = -rays[i].direction;
        const Vec3 p = rays[i].origin + rays[i].direction * hits[i].t;
        const SurfacePoint sp = surface_at(scene, tri, p, wo);
        batch.push_back(p, sp.ns, wo, scene.material_of(tri), pixel_sample_key(ctx_.sampler, pixels[i], 0), tri);
      }
      if (batch.size() == kBatch || (i == rays.size() && batch.size() > 0)) {
        ignored.assign(batch.size(), RGB{});
        co_await trace_paths(ctx_, batch, ignored, fill, &fill_tally_);
        batch.clear();
      }
      if (i % 4096 == 0) ctx_.report("filling the directional cache", i, rays.size());
    }
    cache_->freeze();
    options_.cache = cache_.get();
  }

  PathOptions options_;
  PathTally tally_, fill_tally_;
  SceneContext ctx_;
  bool use_cache_ = false;
  bool learned_ = false;
  bool reuse_ = true;
  LightSelectionOptions selection_options_;
  LightSelection selection_;
  DirectionalCacheOptions cache_options_;
  int fill_spp_ = 4, fill_stride_ = 2;
  std::shared_ptr<DirectionalCache> cache_;  // a copy (fork_view) has none: a cache is never carried
};

}  // namespace

extern const LightOpKind pathtrace_kind{
    .name = "pathtrace",
    .summary = "unbiased path tracing with next-event estimation, MIS and Russian roulette",
    .min_inputs = 0,
    .max_inputs = 0,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<PathTrace>(p); },
    .traces_through_context = true,
    .shares_setup_with = learns_lights};

}  // namespace lf
