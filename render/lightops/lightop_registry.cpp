#include "render/lightops/lightop_registry.hpp"

namespace lf {

extern const LightOpKind direct_kind;
extern const LightOpKind pathtrace_kind;
extern const LightOpKind combine_kind;
extern const LightOpKind emission_kind;
extern const LightOpKind specular_kind;
extern const LightOpKind glossy_kind;
extern const LightOpKind photonmap_kind;
extern const LightOpKind irradiance_kind;
extern const LightOpKind radiosity_kind;

static const LightOpKind* const kAllKinds[] = {
    &direct_kind,
    &pathtrace_kind,
    &combine_kind,
    &emission_kind,
    &specular_kind,
    &glossy_kind,
    &photonmap_kind,
    &irradiance_kind,
    &radiosity_kind,
};

std::span<const LightOpKind* const> lightop_kinds() { return kAllKinds; }

std::string LightOpKind::input_count_error(int count) const {
  if (count >= min_inputs && (max_inputs < 0 || count <= max_inputs)) return {};
  const std::string want = max_inputs == min_inputs ? std::to_string(min_inputs)
                           : max_inputs < 0         ? "at least " + std::to_string(min_inputs)
                                                    : std::to_string(min_inputs) + " to " + std::to_string(max_inputs);
  const int largest = max_inputs < 0 ? min_inputs : max_inputs;  // "1 input", "at least 1 input", "0 to 1 input"
  return "lightop '" + std::string(name) + "' takes " + want + (largest == 1 ? " input" : " inputs") + ", got " +
         std::to_string(count);
}

const LightOpKind* find_lightop_kind(std::string_view name) {
  for (const auto* k : kAllKinds)
    if (k->name == name) return k;
  return nullptr;
}

std::string lightop_kind_list() {
  std::string s;
  for (const auto* k : kAllKinds) s += (s.empty() ? "" : ", ") + std::string(k->name);
  return s;
}

std::unique_ptr<LightOp> create_lightop(const LightOpKind& kind, const ParamTable& params) {
  auto op = kind.create(params);
  params.report_unused();
  return op;
}

}  // namespace lf
