// radiosity: shades with a converged radiosity solution. In setup it fetches the solution the farm's radiosity ring
// published (a RadiosityField); a point's outgoing radiance is its reflected radiosity (B - E) interpolated from the
// vertices of the element under it, divided by pi (diffuse). It composes like any op, e.g.
// irradiance { input = radiosity } as a final gather. No inputs, no parameters.
#include <algorithm>

#include "render/lightops/lightop_registry.hpp"
#include "render/caches/radiosity_field.hpp"

namespace lf {
namespace {

class Radiosity final : public LightOp {
 public:
  explicit Radiosity(const ParamTable&) {}

  Task setup(SceneContext ctx, Inputs&) override {
    // The ring's solution has the scene's emitting triangles as its sources; light from beyond the scene would be
    // missing from every diffuse bounce it computes, silently.
    if (const Environment* env = ctx.scene->environment(); env && env->emits())
      throw LightOpError("radiosity: the scene's environment and sun are not sources of the radiosity solution; light "
                         "this scene with irradiance caching or pathtrace");
    std::string blob;
    co_await ctx.exchange->fetch("radiosity", &blob);
    auto field = RadiosityField::from_bytes(blob);
    if (!field) throw LightOpError(field.error().message);
    field_ = std::move(*field);
    const uint32_t any = mesh_.add_material({"solution", {}, {}});
    for (const auto& t : field_.triangles)
      mesh_.add_triangle(field_.position[t[0]], field_.position[t[1]], field_.position[t[2]], any);
    if (mesh_.triangle_count() > 0) tracer_ = std::make_unique<RayTracer>(mesh_);
    offset_ = 20 * ctx.scene->epsilon();
  }

  // The solution is the whole scene's.
  bool setup_sees_camera() const override { return false; }

  // Reflected radiosity: light after one or more diffuse reflections, and only those (the solution treats every
  // surface as diffuse with its Kd: mirrors and glass absorb).
  std::optional<LightPaths> paths(std::span<const LightPaths>) const override {
    return LightPaths::every(1, LightPaths::kMaxEvents, Lobes::of({Lobe::diffuse}));
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    std::fill(radiance.begin(), radiance.end(), RGB{});
    if (!tracer_) co_return;
    // Find the solution's triangle under each point: a short ray down the normal from just above it.
    std::vector<Ray> rays(points.size());
    for (size_t i = 0; i < points.size(); ++i)
      rays[i] = {points.position[i] + points.normal[i] * offset_, -points.normal[i], 0.0f, 2 * offset_};
    std::vector<Hit> hits(points.size());
    tracer_->intersect(rays, hits);
    for (size_t i = 0; i < points.size(); ++i) {
      if (!hits[i].valid()) continue;
      const uint32_t t = hits[i].triangle;
      if (dot(mesh_.normal(t), points.normal[i]) <= 0) continue;  // the back of a one-sided surface
      const auto& tri = field_.triangles[t];
      const Vec3 a = field_.position[tri[0]], b = field_.position[tri[1]], c = field_.position[tri[2]];
      const Vec3 p = rays[i].origin + rays[i].direction * hits[i].t;
      // Barycentric weights of p in the triangle.
      const Vec3 n = cross(b - a, c - a);
      const float area2 = dot(n, n);
      const float wa = dot(cross(c - b, p - b), n) / area2, wb = dot(cross(a - c, p - c), n) / area2;
      const float wc = 1 - wa - wb;
      RGB reflected;
      for (int k = 0; k < 3; ++k) {
        const float w = k == 0 ? wa : (k == 1 ? wb : wc);
        reflected += (field_.radiosity[tri[static_cast<size_t>(k)]] - field_.emission[tri[static_cast<size_t>(k)]]) * w;
      }
      radiance[i] = RGB{std::max(0.0f, reflected.x), std::max(0.0f, reflected.y), std::max(0.0f, reflected.z)} / kPi;
    }
  }

 private:
  RadiosityField field_;
  Scene mesh_;
  std::unique_ptr<RayTracer> tracer_;
  float offset_ = 1e-3f;
};

}  // namespace

extern const LightOpKind radiosity_kind{
    .name = "radiosity",
    .summary = "the converged solution of the farm's radiosity ring, interpolated",
    .min_inputs = 0,
    .max_inputs = 0,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Radiosity>(p); }};

}  // namespace lf
