// glossy: indirect light reflected by a glossy lobe. At a point whose material has one (a Phong lobe, Ks > 0, or a
// metal_rough material's specular lobe and rough glass, refraction included: its base and its conductor's multiply
// scattered light are diffuse lobes, the caches'),
// `samples` directions drawn in proportion to that lobe; where each lands, the input is asked (in one batch) for
// the light leaving that surface back towards the point. The answer is the lobe's share of the reflected light:
// ks (ns + 2) / (ns + 1) cos(wi) times what arrives, averaged. One input.
//
// The emitters a sample lands on add nothing: `direct` already counts light straight from them at glossy points
// (with multiple importance sampling between its light samples and its own lobe samples), so this op counts only
// what its input says leaves the landing, i.e. light that has scattered at least once more. The two split the
// lobe's light by path (L G for direct, L ... X G for this op), not by estimator, so neither needs the other's
// densities.
//
// A lobe that reflects a small share of a point's light (a dielectric's coat: 5-15 %) gets few samples: each is
// kept with chance q = twice the lobe's share of what the point reflects (at most 1) and weighted by 1 / q (Russian
// roulette, unbiased). Its noise is a small part of the pixel's, and a path per lit sample was most of a coated
// scene's rendering (`roulette = false`: every sample).
//
// The diffuse part of the same material is the caches' or the path tracer's (irradiance: L ... D), unless
// `lobes = "all"`: then this op follows every lobe but mirrors and glass, the diffuse ones too (L ... X (D|G)),
// for scenes where the light that bounces off diffuse surfaces is too little to be worth a cache's pre-pass (an
// object under an open sky).
#include "render/shading/bsdf.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/surface.hpp"

namespace lf {
namespace {

class Glossy final : public LightOp {
 public:
  explicit Glossy(const ParamTable& p)
      : samples_(static_cast<int>(p.get_int("samples", 1, 1, 1 << 16))),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))),
        all_lobes_(p.get_string("lobes", "glossy", {"glossy", "all"}) == "all"),
        roulette_(p.get_bool("roulette", true)) {}

  Task setup(SceneContext ctx, Inputs& inputs) override {
    if (inputs.count() != 1) throw LightOpError("glossy needs one input");
    ctx_ = ctx;
    co_return;
  }

  bool setup_sees_camera() const override { return false; }

  std::optional<LightPaths> paths(std::span<const LightPaths> inputs) const override {
    if (inputs.empty()) return LightPaths();
    return all_lobes_ ? inputs[0].then(Lobe::glossy) + inputs[0].then(Lobe::diffuse) : inputs[0].then(Lobe::glossy);
  }

  Value stats() const override {
    return Value::Map{{"glossy_points", static_cast<int64_t>(points_)}, {"rays", static_cast<int64_t>(rays_)},
                      {"landed", static_cast<int64_t>(landed_)}};
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs& inputs) override {
    const Scene& scene = *ctx_.scene;
    std::vector<Ray> rays;
    std::vector<RGB> weights;
    std::vector<size_t> owners;
    std::vector<uint32_t> sample_of;
    for (size_t i = 0; i < points.size(); ++i) {
      radiance[i] = RGB{};
      const Material& m = scene.material(points.material[i]);
      const bool microfacet = m.type == Material::Type::metal_rough;
      // A microfacet material's base colour, and a diffuse lobe's, may be a texture's; a Phong lobe needs none.
      const float footprint = ctx_.pixel_footprint(points.position[i]);
      float metallic = 0, roughness = 0;
      if (microfacet) points.metal_rough(i, scene, footprint, metallic, roughness);
      const Bsdf bsdf = microfacet || all_lobes_
                            ? Bsdf(m, points.albedo(i, scene, footprint), metallic, roughness, points.outside(i, scene))
                            : Bsdf(m);
      if (!bsdf.has_glossy_lobe() && !(all_lobes_ && bsdf.has_diffuse_lobe())) continue;
      ++points_;
      // The chance each of its samples is followed (every lobe, with lobes = "all").
      const float keep = roulette_ && !all_lobes_ ? std::min(1.0f, 2 * bsdf.glossy_share(points.normal[i], points.wo[i])) : 1.0f;
      if (!(keep > 0)) continue;
      const Vec3 ng = points.face_normal(i, scene);
      const Vec3 origin = scene.ray_origin(points.triangle_of(i), points.position[i], ng);
      for (int s = 0; s < samples_; ++s) {
        Sampler sampler(ctx_.sampler, points.key[i], streams::glossy ^ (seed_ << 8), static_cast<uint32_t>(s),
                        static_cast<uint32_t>(samples_));
        const Uniform2 u = sampler.uniform2();
        // The microfacet model's choice between its parts takes one more number (after the pair, so a Phong
        // lobe's directions stay what they were).
        const float part = microfacet || all_lobes_ ? sampler.uniform() : 0.5f;
        // Every lobe: the whole BSDF's sample, its mirror term's left to `specular` (a sample that takes it is
        // dropped, which leaves the other lobes' estimate as it is: sample() weighs them by their chance).
        auto sample = all_lobes_ ? bsdf.sample(points.normal[i], points.wo[i], true, part, u.u, u.v)
                                 : bsdf.sample_glossy(points.normal[i], points.wo[i], u.u, u.v, part);
        if (sample && sample->delta) continue;
        if (keep < 1 && sampler.uniform() >= keep) continue;
        // A reflection the shading normal allows below the face would leave through the surface: no light. Rough
        // glass sends its refractions through, below both normals, from beneath the face.
        if (!sample) continue;
        const bool through = bsdf.transmits() && above_both(-sample->wi, points.normal[i], ng);
        if (!through && dot(sample->wi, ng) <= 0) continue;
        rays.push_back(Ray{through ? scene.ray_origin(points.triangle_of(i), points.position[i], -ng) : origin, sample->wi});
        weights.push_back(keep < 1 ? sample->weight * (1.0f / keep) : sample->weight);
        owners.push_back(i);
        sample_of.push_back(static_cast<uint32_t>(s));
      }
    }
    rays_ += rays.size();
    std::vector<Hit> hits(rays.size());
    if (!rays.empty()) co_await trace_intersect(ctx_, rays, hits);
    ShadingPoints landings;
    std::vector<size_t> landing_ray;
    for (size_t r = 0; r < rays.size(); ++r) {
      if (!hits[r].valid()) continue;
      const uint32_t tri = hits[r].triangle;
      const Vec3 wo = -rays[r].direction;
      const Vec3 x = rays[r].origin + rays[r].direction * hits[r].t;
      landings.push_back(x, surface_at(scene, tri, x, wo).ns, wo, scene.material_of(tri),
                         splitmix64(points.key[owners[r]] ^ (0x6105500000ull + sample_of[r])), tri);
      landing_ray.push_back(r);
    }
    landed_ += landings.size();
    std::vector<RGB> arriving;
    if (landings.size() > 0) co_await inputs.shade(0, landings, arriving);
    const float per_sample = 1.0f / static_cast<float>(samples_);
    for (size_t j = 0; j < landing_ray.size(); ++j) {
      const size_t r = landing_ray[j];
      radiance[owners[r]] += weights[r] * arriving[j] * per_sample;
    }
  }

 private:
  int samples_;
  uint64_t seed_;
  bool all_lobes_, roulette_;
  SceneContext ctx_;
  uint64_t points_ = 0, rays_ = 0, landed_ = 0;
};

}  // namespace

extern const LightOpKind glossy_kind{
    .name = "glossy",
    .summary = "indirect light reflected by glossy lobes, asking its input where each lobe sample lands",
    .min_inputs = 1,
    .max_inputs = 1,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Glossy>(p); },
    .traces_through_context = true};

}  // namespace lf
