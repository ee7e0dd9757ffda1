// direct: light arriving straight from the area lights, reflected by a diffuse BRDF.
//
// Estimator: for each point, `light_samples` samples pick an emitter triangle with probability proportional to its
// power and a uniform point on it; a shadow ray checks visibility. Per sample the contribution is
//   f * Le * cos(theta_x) * cos(theta_y) / d^2 / pdf_area,   f = Kd / pi,  pdf_area = P(triangle) / area.
// Emitters emit on the side their winding faces. Shadow rays of a whole batch go to Embree as one stream.
#include "render/lightop_registry.hpp"
#include "render/sampler.hpp"

namespace lf {
namespace {

class DirectLight final : public LightOp {
 public:
  explicit DirectLight(const ParamTable& p)
      : light_samples_(static_cast<int>(p.get_int("light_samples", 1, 1, 1 << 20))),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))) {}

  Task setup(const SceneContext& ctx, Inputs&) override {
    ctx_ = ctx;
    co_return;
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    const Scene& scene = *ctx_.scene;
    const size_t n = points.size();
    const size_t per = static_cast<size_t>(light_samples_);
    rays_.clear();
    weights_.clear();
    owners_.clear();
    rays_.reserve(n * per);
    for (size_t i = 0; i < n; ++i) {
      radiance[i] = RGB{};
      const Material& m = scene.material(points.material[i]);
      if (is_black(m.kd)) continue;
      const Vec3 x = points.position[i];
      const Vec3 nx = points.normal[i];
      const RGB f = m.kd * (1.0f / kPi);
      Rng rng(points.key[i], streams::direct ^ (seed_ << 8));
      for (size_t s = 0; s < per; ++s) {
        float p_tri = 0;
        const size_t e = scene.pick_emitter(rng.uniform(), p_tri);
        const uint32_t tri = scene.emitters()[e];
        // Uniform point on the triangle (square-root parameterisation).
        const float su = std::sqrt(rng.uniform());
        const float v = rng.uniform();
        const Vec3 y = scene.vertex(tri, 0) * (1 - su) + scene.vertex(tri, 1) * (su * (1 - v)) +
                       scene.vertex(tri, 2) * (su * v);
        const Vec3 d = y - x;
        const float dist2 = dot(d, d);
        if (!(dist2 > 0)) continue;
        const float dist = std::sqrt(dist2);
        const Vec3 wi = d / dist;
        const float cos_x = dot(nx, wi);
        const float cos_y = -dot(scene.normal(tri), wi);
        if (cos_x <= 0 || cos_y <= 0) continue;
        const float pdf_area = p_tri / scene.area(tri);
        const RGB le = scene.material(scene.material_of(tri)).ke;
        weights_.push_back(f * le * (cos_x * cos_y / (dist2 * pdf_area * static_cast<float>(per))));
        owners_.push_back(static_cast<uint32_t>(i));
        // Leave the surface by eps and stop eps short of the light, measured from the shifted origin.
        const float eps = scene.epsilon();
        const Vec3 origin = x + nx * eps;
        const Vec3 to_light = y - origin;
        const float span = length(to_light);
        rays_.push_back(Ray{origin, to_light / span, 0.0f, span - eps});
      }
    }
    blocked_.resize(rays_.size());
    if (!rays_.empty()) ctx_.tracer->occluded(rays_, blocked_);
    // Sum in sample order per point, so the result does not depend on the batch it came in.
    for (size_t r = 0; r < rays_.size(); ++r)
      if (!blocked_[r]) radiance[owners_[r]] += weights_[r];
    co_return;
  }

 private:
  int light_samples_;
  uint64_t seed_;
  SceneContext ctx_;
  std::vector<Ray> rays_;
  std::vector<RGB> weights_;
  std::vector<uint32_t> owners_;
  std::vector<uint8_t> blocked_;
};

}  // namespace

extern const LightOpKind direct_kind{
    "direct", "direct light from area lights: light sampling with shadow rays, diffuse BRDF", 0, 0,
    [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<DirectLight>(p); }};

}  // namespace lf
