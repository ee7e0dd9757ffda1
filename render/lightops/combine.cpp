// combine: the weighted sum of its inputs, asked concurrently — e.g. combine { direct, caustics, indirect }.
// Parameters: weights = {w1, w2, ...} (default: all 1; one per input).
#include "render/lightops/lightop_registry.hpp"

namespace lf {
namespace {

class Combine final : public LightOp {
 public:
  explicit Combine(const ParamTable& p) {
    for (double w : p.get_numbers("weights", {}, -1e6, 1e6)) weights_.push_back(static_cast<float>(w));
  }

  Task setup(SceneContext, Inputs& inputs) override {
    if (!weights_.empty() && weights_.size() != inputs.count())
      throw LightOpError("combine has " + std::to_string(weights_.size()) + " weights for " +
                         std::to_string(inputs.count()) + " inputs");
    co_return;
  }

  bool setup_sees_camera() const override { return false; }

  std::optional<LightPaths> paths(std::span<const LightPaths> inputs) const override {
    LightPaths sum;
    for (size_t i = 0; i < inputs.size(); ++i) sum += inputs[i] * (weights_.empty() ? 1.0f : weights_[i]);
    return sum;
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs& inputs) override {
    std::vector<std::vector<RGB>> parts(inputs.count());
    std::vector<InputQuery> queries;
    for (size_t i = 0; i < parts.size(); ++i) queries.push_back({i, &points, &parts[i]});
    co_await inputs.gather(std::move(queries));
    for (size_t p = 0; p < points.size(); ++p) {
      RGB sum{};
      for (size_t i = 0; i < parts.size(); ++i) sum += parts[i][p] * (weights_.empty() ? 1.0f : weights_[i]);
      radiance[p] = sum;
    }
  }

 private:
  std::vector<float> weights_;
};

}  // namespace

extern const LightOpKind combine_kind{
    .name = "combine",
    .summary = "the weighted sum of its inputs",
    .min_inputs = 1,
    .max_inputs = -1,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<Combine>(p); }};

}  // namespace lf
