// specular: light that reaches a point along a chain of perfect reflections and refractions, from a mirror or glass
// surface or through the mirror term of a diffuse or glossy one. From such a point it follows the chain (choosing
// reflection or refraction at glass by Fresnel, `samples` chains per point) until it lands on a non-specular
// surface, then asks its input, in one batch, for the light leaving that surface back along the chain; where that
// surface has a mirror term too, the chain also goes on through it. An emitter the chain lands on adds its own
// emission (the input returns reflected light only), and so does the environment where a chain leaves the scene. The other lobes of a point are the other ops' job. One input.
//
// `emission_samples` chains per point look only for emitters: a flame seen in a window or in water is as small as
// one seen directly, and needs as many chains as the camera gives it samples, while what the chain lands on
// (asking the input: the expensive part) is smooth enough for `samples`. The emission is the mean over all
// chains, the landing light the mean over the first `samples`: both unbiased. Unset, 4 x `samples`: on Lost
// Empire's network (16 spp) error 0.226 -> 0.190 at the same time, on cornell_glass the seed-pair noise 0.0109 ->
// 0.0061 (docs/decisions.md).
//
// `emitters = false`: chains add nothing for the emitters they meet (L S+), for a network in which another op counts
// that light, e.g. a cache whose hemisphere sees mirrors beside a caustic photon map that holds L S+ D.
#include <algorithm>

#include "render/shading/bsdf.hpp"
#include "render/scene/surface.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

// Emitter-only chains a point traces for each chain whose landing is shaded, when `emission_samples` is unset.
constexpr int kEmissionChainsPerChain = 4;

class Specular final : public LightOp {
 public:
  explicit Specular(const ParamTable& p)
      : samples_(static_cast<int>(p.get_int("samples", 1, 1, 1 << 16))),
        emission_samples_(static_cast<int>(p.get_int("emission_samples", std::min(kEmissionChainsPerChain * samples_, 1 << 16), samples_, 1 << 16))),
        max_depth_(static_cast<int>(p.get_int("max_depth", 8, 1, 256))),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))),
        emitters_(p.get_bool("emitters", true)) {}

  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    co_return;
  }

  bool setup_sees_camera() const override { return false; }

  // Chains of 1..max_depth specular events from where they land: an emitter's own light there (added here), or what
  // the input gives at a diffuse or glossy landing (its emission too, should it return that).
  std::optional<LightPaths> paths(std::span<const LightPaths> inputs) const override {
    LightPaths landing = emitters_ ? LightPaths::emission() : LightPaths();
    if (!inputs.empty()) landing += inputs[0].ending_in(Lobes::of({Lobe::diffuse, Lobe::glossy}), true);
    return landing.then_repeated(Lobe::specular, 1, max_depth_);
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs& inputs) override {
    const Scene& scene = *ctx_.scene;
    struct Chain {
      size_t owner;
      int sample;  // which of the point's chains
      Vec3 x, n, wo;
      Vec3 ng;  // the face's normal on n's side (n is the shading normal)
      uint32_t material;
      uint32_t triangle;  // UINT32_MAX: a point that names none
      bool outside;
      bool asks_input;  // one of the first `samples` chains: its landings are shaded
      RGB weight{1, 1, 1};
      RGB emitted{};
      Rng rng;
    };
    // Where a chain reached a diffuse or glossy surface: the input's light there, times the chain's weight so far. A
    // chain that reaches one with a mirror term goes on through that term, and may land again further on.
    struct Landing {
      size_t chain;
      RGB weight;
    };
    auto reflects = [&](uint32_t material) {
      const Material& m = scene.material(material);
      return m.specular() || m.has_mirror_term();
    };
    std::vector<Chain> chains;
    for (size_t i = 0; i < points.size(); ++i) {
      radiance[i] = RGB{};
      if (!reflects(points.material[i])) continue;
      // Chains that only look for emitters have nothing to do when emitters count for nothing here.
      for (int s = 0; s < (emitters_ ? emission_samples_ : samples_); ++s)
        chains.push_back(Chain{i, s, points.position[i], points.normal[i], points.wo[i], points.face_normal(i, scene),
                               points.material[i], points.triangle_of(i), points.outside(i, scene), s < samples_,
                               {1, 1, 1}, {},
                               Rng(points.key[i], streams::specular ^ (seed_ << 8) ^ (uint64_t(s) << 32))});
    }
    ShadingPoints ends;
    std::vector<Landing> landings;  // one per entry of `ends`
    std::vector<size_t> active(chains.size());
    for (size_t c = 0; c < chains.size(); ++c) active[c] = c;
    std::vector<Ray> rays;
    std::vector<Hit> hits;
    for (int depth = 0; depth < max_depth_ && !active.empty(); ++depth) {
      rays.clear();
      std::vector<size_t> moving;
      for (size_t c : active) {
        Chain& ch = chains[c];
        const float u0 = ch.rng.uniform();
        const Material& m = scene.material(ch.material);
        const Bsdf bsdf(m);
        auto s = m.specular() ? bsdf.sample(ch.n, ch.wo, ch.outside, u0, 0.5f, 0.5f)
                              : bsdf.sample_mirror_term(ch.n, ch.wo);
        if (!s) continue;
        ch.weight = ch.weight * s->weight;
        const Vec3 side = dot(s->wi, ch.ng) > 0 ? ch.ng : -ch.ng;
        rays.push_back(Ray{scene.ray_origin(ch.triangle, ch.x, side), s->wi});
        moving.push_back(c);
      }
      hits.resize(rays.size());
      if (!rays.empty()) ctx_.tracer->intersect(rays, hits);
      active.clear();
      for (size_t r = 0; r < moving.size(); ++r) {
        if (!hits[r].valid()) {
          // Out of the scene: the environment is the emitter such a chain meets.
          if (emitters_ && scene.environment())
            chains[moving[r]].emitted += chains[moving[r]].weight * scene.environment()->radiance(rays[r].direction);
          continue;
        }
        Chain& ch = chains[moving[r]];
        const uint32_t tri = hits[r].triangle;
        const Vec3 wo = -rays[r].direction;
        const Vec3 x = rays[r].origin + rays[r].direction * hits[r].t;
        const SurfacePoint sp = surface_at(scene, tri, x, wo);
        const bool front = sp.front;
        const uint32_t m = scene.material_of(tri);
        const Material& hit = scene.material(m);
        if (emitters_ && hit.emissive() && front)
          ch.emitted += ch.weight * scene.emission_at(tri, x);
        if (!hit.specular() && ch.asks_input) {
          // Keyed by the point, the chain and the depth: the same on every batch and layout.
          const uint64_t chain = static_cast<uint64_t>(ch.sample) * 256 + static_cast<uint64_t>(depth);
          const uint64_t key = splitmix64(points.key[ch.owner] ^ (0x5bec0000ull + chain));
          ends.push_back(x, sp.ns, wo, m, key, tri);
          landings.push_back(Landing{moving[r], ch.weight});
        }
        if (reflects(m)) {
          ch.x = x;
          ch.n = sp.ns;
          ch.wo = wo;
          ch.ng = sp.ng;
          ch.material = m;
          ch.triangle = tri;
          ch.outside = front;
          active.push_back(moving[r]);
        }
      }
    }
    std::vector<RGB> arriving;
    if (ends.size() > 0 && inputs.count() > 0) co_await inputs.shade(0, ends, arriving);
    const float per_landing = 1.0f / static_cast<float>(samples_);
    const float per_emission = 1.0f / static_cast<float>(emission_samples_);
    for (const Chain& ch : chains) radiance[ch.owner] += ch.emitted * per_emission;
    if (!arriving.empty())
      for (size_t e = 0; e < landings.size(); ++e)
        radiance[chains[landings[e].chain].owner] += landings[e].weight * arriving[e] * per_landing;
  }

 private:
  int samples_, emission_samples_, max_depth_;
  uint64_t seed_;
  bool emitters_;
  SceneContext ctx_;
};

}  // namespace

extern const LightOpKind specular_kind{
    .name = "specular",
    .summary = "light along mirror and glass chains, asking its input where a chain lands",
    .min_inputs = 1,
    .max_inputs = 1,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Specular>(p); }};

}  // namespace lf
