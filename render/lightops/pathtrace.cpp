// pathtrace: an unbiased path tracer — next-event estimation with multiple importance sampling at every vertex,
// BSDF sampling through diffuse, glossy, mirror and glass surfaces, Russian roulette (render/path_kernel.cpp).
// The reference the other LightOps are checked against. No inputs.
#include "render/lightop_registry.hpp"
#include "render/path_kernel.hpp"
#include "render/sampler.hpp"

namespace lf {
namespace {

class PathTrace final : public LightOp {
 public:
  explicit PathTrace(const ParamTable& p) {
    options_.max_depth = static_cast<int>(p.get_int("max_depth", 8, 1, 1024));
    options_.rr_depth = static_cast<int>(p.get_int("rr_depth", 3, 1, 1024));
    options_.samples = static_cast<int>(p.get_int("samples", 1, 1, 1 << 16));
    options_.light_tree = p.get_string("light_sampling", "tree", {"tree", "power"}) == "tree";
    options_.stream = streams::pathtrace ^ (static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX)) << 8);
  }

  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    co_return;
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    co_await trace_paths(ctx_, points, radiance, options_, &tally_);
  }

  Value stats() const override {
    return Value::Map{{"paths", static_cast<int64_t>(tally_.paths)},
                      {"mean_path_vertices", tally_.paths ? static_cast<double>(tally_.vertices) / tally_.paths : 0.0}};
  }

 private:
  PathOptions options_;
  PathTally tally_;
  SceneContext ctx_;
};

}  // namespace

extern const LightOpKind pathtrace_kind{
    "pathtrace", "unbiased path tracing with next-event estimation, MIS and Russian roulette", 0, 0,
    [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<PathTrace>(p); }};

}  // namespace lf
