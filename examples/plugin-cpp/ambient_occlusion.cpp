// ambient_occlusion: a LightOp that lives outside lightfarm's source tree and is built against its SDK.
//
// Each point casts `samples` cosine-distributed rays into its hemisphere; rays that travel `radius` without
// hitting anything count as open sky. The point reflects Kd * ambient * (open fraction). It uses the scene and
// the Embree tracer the SDK hands to every LightOp, and draws its random numbers from the point's sample key, so
// its image is the same on any farm layout.
#include <actors/runtime/sdk.hpp>
#include <render/shading/sampler.hpp>

#include <cmath>

namespace {

class AmbientOcclusion final : public lf::LightOp {
 public:
  explicit AmbientOcclusion(const lf::ParamTable& p)
      : samples_(static_cast<int>(p.get_int("samples", 16, 1, 4096))),
        radius_(static_cast<float>(p.get_float("radius", 1e30, 0, 1e30))),
        ambient_(static_cast<float>(p.get_float("ambient", 1.0, 0, 1e6))) {}

  lf::Task setup(lf::SceneContext ctx, lf::Inputs&) override {
    ctx_ = ctx;
    co_return;
  }

  lf::Task shade(const lf::ShadingPoints& points, std::span<lf::RGB> radiance, lf::Inputs&) override {
    const lf::Scene& scene = *ctx_.scene;
    std::vector<lf::Ray> rays;
    rays.reserve(points.size() * static_cast<size_t>(samples_));
    for (size_t i = 0; i < points.size(); ++i) {
      const lf::Vec3 n = points.normal[i];
      // An orthonormal basis around n (Duff et al.'s branchless construction).
      const float sign = std::copysign(1.0f, n.z);
      const float a = -1.0f / (sign + n.z), b = n.x * n.y * a;
      const lf::Vec3 t{1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
      const lf::Vec3 s{b, sign + n.y * n.y * a, -n.y};
      lf::Rng rng(points.key[i], kStream);
      // Rays leave just above the face (the scene works out how far above from the point's triangle).
      const lf::Vec3 origin = scene.ray_origin(points.triangle_of(i), points.position[i], points.face_normal(i, scene));
      for (int k = 0; k < samples_; ++k) {
        const float u = rng.uniform(), v = rng.uniform();
        const float r = std::sqrt(u), phi = 2.0f * lf::kPi * v;
        const lf::Vec3 d = t * (r * std::cos(phi)) + s * (r * std::sin(phi)) + n * std::sqrt(1.0f - u);
        rays.push_back(lf::Ray{origin, d, 0.0f, radius_});
      }
    }
    std::vector<uint8_t> blocked(rays.size());
    ctx_.tracer->occluded(rays, blocked);
    for (size_t i = 0; i < points.size(); ++i) {
      int open = 0;
      for (int k = 0; k < samples_; ++k) open += !blocked[i * static_cast<size_t>(samples_) + static_cast<size_t>(k)];
      const lf::RGB kd = scene.material(points.material[i]).kd;
      radiance[i] = kd * (ambient_ * static_cast<float>(open) / static_cast<float>(samples_));
    }
    co_return;
  }

 private:
  static constexpr uint64_t kStream = 0xa0;
  int samples_;
  float radius_, ambient_;
  lf::SceneContext ctx_;
};

const lf::LightOpKind kAmbientOcclusion{
    "ambient_occlusion", "ambient occlusion from the scene's geometry", 0, 0,
    [](const lf::ParamTable& p) -> std::unique_ptr<lf::LightOp> { return std::make_unique<AmbientOcclusion>(p); }};

}  // namespace

int main(int argc, char** argv) { return lf::serve_lightop(kAmbientOcclusion, argc, argv); }
