// emission: the light a point itself emits towards wo (Ke on an emitter's front side, else nothing). The renderer
// adds emission the camera sees; inside a network, e.g. at the end of a mirror chain, this is how a LightOp asks
// "is this a light?". No inputs, no parameters.
#include "render/lightops/lightop_registry.hpp"

namespace lf {
namespace {

class Emission final : public LightOp {
 public:
  explicit Emission(const ParamTable&) {}
  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    co_return;
  }
  bool setup_sees_camera() const override { return false; }

  std::optional<LightPaths> paths(std::span<const LightPaths>) const override { return LightPaths::emission(); }
  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    const Scene& scene = *ctx_.scene;
    for (size_t i = 0; i < points.size(); ++i) {
      const uint32_t t = points.triangle_of(i);
      // Without a triangle (a point that names none), the material's own ke: no place on an emission map.
      radiance[i] = !points.outside(i, scene) ? RGB{}
                    : t == UINT32_MAX || t >= scene.triangle_count() ? scene.material(points.material[i]).ke
                                                                     : scene.emission_at(t, points.position[i]);
    }
    co_return;
  }

 private:
  SceneContext ctx_;
};

}  // namespace

extern const LightOpKind emission_kind{
    .name = "emission",
    .summary = "the light the point itself emits",
    .min_inputs = 0,
    .max_inputs = 0,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Emission>(p); }};

}  // namespace lf
