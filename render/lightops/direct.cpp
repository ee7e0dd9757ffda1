// direct: light arriving straight from the lights (area, point, and the environment and sun).
//
// `light_samples` samples per point. Each draws a light through the scene's light tree (by what each light can give
// the point: power, distance, orientation; render/lights/light_tree.hpp), or with `light_sampling = "power"` by power
// alone, or with `light_sampling = "learned"` partly from the lights found before rendering to light the point's
// cell where the camera looks (render/lights/light_selection.hpp); then a uniform point on it, and a shadow ray. On glossy
// surfaces it also samples the BSDF, and the two are combined by multiple importance sampling
// (render/shading/path_kernel.cpp with one vertex). Diffuse surfaces get the BSDF sample too where `mis` says: it
// tames points close to a light (a uniform point on a light seen under a wide angle has a 1/d^2 weight; a cosine
// direction does not). `true`: everywhere; `false`: nowhere; unset: everywhere in a scene with an environment
// (render/lights/environment.hpp), otherwise only within `mis_reach` radii of a light (render/lights/near_lights.hpp),
// the only places it pays for its ray. In a job the learned lights are carried over the
// frames (`reuse`, default true): a frame learns only the cells its view finds new or sees much better
// (LightSelection::extend). Emitters emit on the side their winding faces.
// Mirrors and glass get nothing here: that is `specular`'s job.
#include <memory>

#include "render/lightops/lightop_registry.hpp"
#include "render/lights/near_lights.hpp"
#include "render/shading/path_kernel.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

class DirectLight final : public LightOp {
 public:
  explicit DirectLight(const ParamTable& p)
      : light_samples_(static_cast<int>(p.get_int("light_samples", 1, 1, 1 << 20))),
        light_sampling_(read_light_sampling(p)),
        light_point_(p.get_string("light_point", "area", {"area", "solid_angle"}) == "solid_angle" ? LightPoint::solid_angle
                                                                                                : LightPoint::area),
        mis_set_(p.has("mis")),
        mis_(p.get_bool("mis", false)),
        mis_reach_(static_cast<float>(p.get_float("mis_reach", 4, 0, 1e6))),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))),
        selection_options_(light_selection_options(p, seed_)),
        reuse_(p.get_bool("reuse", true)) {}

  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    // Unset, MIS on diffuse surfaces follows the scene: with an environment, light samples drawn by the sky's
    // brightness go to a sun below a surface's horizon as often as to one above it, and the cosine sample is what
    // lights the surface then (bench/environment_bench: MIS is never far from the better of the two).
    if (!mis_set_) mis_ = ctx.scene->environment() && ctx.scene->environment()->emits();
    // Unset, and without an environment, diffuse points near a light get the BSDF sample and the rest do not.
    near_.reset();
    if (!mis_set_ && !mis_ && mis_reach_ > 0) near_ = std::make_shared<const NearLights>(*ctx.scene, mis_reach_);
    if (light_sampling_ == LightSampling::learned) co_await LightSelection::build(ctx, selection_options_, selection_, "direct");
  }

  Value stats() const override {
    if (light_sampling_ != LightSampling::learned) return Value();
    Value::Map m;
    selection_.add_stats(m);
    return m;
  }

  // Lights are learned where the camera looks.
  bool setup_sees_camera() const override { return light_sampling_ == LightSampling::learned; }
  // Over a job's frames the learned cells are kept and each view learns only the cells it finds new or sees much
  // better; `reuse = false`: lights learned anew for each frame's view.
  bool carries_views() const override { return light_sampling_ == LightSampling::learned && reuse_; }
  Task extend_to_view(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    co_await selection_.extend(ctx, selection_options_, "direct");
  }
  std::unique_ptr<LightOp> fork_view() const override { return std::make_unique<DirectLight>(*this); }
  std::string carried_state() const override { return selection_.state(); }
  void restore_carried(std::string_view state) override {
    selection_.restore(state, *ctx_.scene, "direct");
  }

  // Light straight from an emitter, scattered at the point by its diffuse or glossy lobe.
  std::optional<LightPaths> paths(std::span<const LightPaths>) const override {
    return LightPaths::every(1, 1, Lobes::of({Lobe::diffuse, Lobe::glossy}));
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    PathOptions o;
    o.max_depth = 1;
    o.samples = light_samples_;
    o.stream = streams::direct ^ (seed_ << 8);
    o.light_only_on_diffuse = !mis_;
    o.mis_near = near_.get();
    o.dark_on_specular = true;
    o.light_tree = light_sampling_ != LightSampling::power;
    o.light_selection = light_sampling_ == LightSampling::learned ? &selection_ : nullptr;
    o.light_point = light_point_;
    co_await trace_paths(ctx_, points, radiance, o);
  }

 private:
  int light_samples_;
  LightSampling light_sampling_;
  LightPoint light_point_;
  bool mis_set_, mis_;
  float mis_reach_;
  std::shared_ptr<const NearLights> near_;  // shared by the views a job forks
  uint64_t seed_;
  LightSelectionOptions selection_options_;
  LightSelection selection_;
  bool reuse_;
  SceneContext ctx_;
};

}  // namespace

extern const LightOpKind direct_kind{
    .name = "direct",
    .summary = "direct light from area lights: light sampling, with MIS on glossy surfaces",
    .min_inputs = 0,
    .max_inputs = 0,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<DirectLight>(p); },
    .traces_through_context = true,
    .shares_setup_with = learns_lights};

}  // namespace lf
