#pragma once
// Every LightOp kind, by name. Each kind's file ends with its LightOpKind; registry.cpp lists them all in one
// place (an explicit list, because self-registering statics vanish from static libraries).
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "core/params.hpp"
#include "render/lightops/lightop.hpp"

namespace lf {

struct LightOpKind {
  std::string_view name;
  std::string_view summary;
  int min_inputs;
  int max_inputs;  // -1: any number
  // Reads its parameters from the table; throws ParamError on a bad value. The caller reports unused ones.
  std::unique_ptr<LightOp> (*create)(const ParamTable& params);
  // Replicas in a pool pool their setup (all_gather): one lost during setup takes a share nobody else has.
  bool shares_setup = false;
  // Every ray it traces goes through SceneContext::tracing when that is set (render/lightops/lightop.hpp): in a partitioned
  // farm such an op needs no BVH of its own, and its process builds none.
  bool traces_through_context = false;
  // For a kind that shares only with some parameters (`direct` learning lights): whether these do. Null: always
  // as shares_setup says.
  bool (*shares_setup_with)(const Value::Map& params) = nullptr;
  bool shares_setup_for(const Value::Map& params) const {
    return shares_setup_with ? shares_setup_with(params) : shares_setup;
  }
  // "lightop 'combine' takes at least 1 input, got 0" when `count` inputs are too few or too many; else empty.
  std::string input_count_error(int count) const;
};

std::span<const LightOpKind* const> lightop_kinds();
const LightOpKind* find_lightop_kind(std::string_view name);
// "direct, ..." for error messages.
std::string lightop_kind_list();
// Creates the op and reports unknown parameters (ParamError).
std::unique_ptr<LightOp> create_lightop(const LightOpKind& kind, const ParamTable& params);

}  // namespace lf
