#include "render/lightops/lightop.hpp"

#include <cmath>
#include <cstdint>

namespace lf {

void ShadingPoints::reserve(size_t n) {
  position.reserve(n);
  normal.reserve(n);
  wo.reserve(n);
  material.reserve(n);
  key.reserve(n);
  triangle.reserve(n);
}

void ShadingPoints::clear() {
  position.clear();
  normal.clear();
  wo.clear();
  material.clear();
  key.clear();
  triangle.clear();
}

void ShadingPoints::push_back(Vec3 p, Vec3 n, Vec3 w, uint32_t m, uint64_t k) {
  position.push_back(p);
  normal.push_back(n);
  wo.push_back(w);
  material.push_back(m);
  key.push_back(k);
}

static bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void ShadingPoints::push_back(Vec3 p, Vec3 n, Vec3 w, uint32_t m, uint64_t k, uint32_t tri) {
  push_back(p, n, w, m, k);
  triangle.push_back(tri);
}

std::string ShadingPoints::check(size_t material_count, size_t triangle_count) const {
  const size_t n = position.size();
  if (normal.size() != n || wo.size() != n || material.size() != n || key.size() != n)
    return "shading point arrays have different lengths";
  if (!triangle.empty() && triangle.size() != n) return "shading point arrays have different lengths";
  for (size_t i = 0; i < triangle.size(); ++i)
    if (triangle[i] >= triangle_count)
      return "point " + std::to_string(i) + " lies on triangle " + std::to_string(triangle[i]) + " but the scene has " +
             std::to_string(triangle_count);
  for (size_t i = 0; i < n; ++i) {
    if (material[i] >= material_count)
      return "point " + std::to_string(i) + " has material " + std::to_string(material[i]) + " but the scene has " +
             std::to_string(material_count);
    if (!finite(position[i]) || !finite(normal[i]) || !finite(wo[i]))
      return "point " + std::to_string(i) + " has a non-finite coordinate";
  }
  return {};
}

void GatherState::complete_one(std::string failure) {
  if (!failure.empty() && error.empty()) error = std::move(failure);
  if (remaining > 0 && --remaining == 0 && waiter) {
    auto h = std::exchange(waiter, {});
    if (before_resume) before_resume();
    h.resume();
  }
}

Task trace_intersect(const SceneContext& ctx, std::span<const Ray> rays, std::span<Hit> hits) {
  if (ctx.tracing) co_await ctx.tracing->intersect(rays, hits);
  else ctx.tracer->intersect(rays, hits);
}

Task trace_occluded(const SceneContext& ctx, std::span<const Ray> rays, std::span<uint8_t> occluded) {
  if (ctx.tracing) co_await ctx.tracing->occluded(rays, occluded);
  else ctx.tracer->occluded(rays, occluded);
}

void run_to_completion(Task task) {
  if (!task.done()) throw LightOpError("an in-process LightOp waited for something that never came");
  task.rethrow_if_failed();
}

Gather LocalInputs::gather(std::vector<InputQuery> queries) {
  auto state = std::make_shared<GatherState>();
  for (const auto& q : queries) {
    if (q.input >= ops_.size()) {
      state->error = "input " + std::to_string(q.input) + " does not exist";
      continue;
    }
    q.radiance->assign(q.points->size(), RGB{});
    auto [op, inputs] = ops_[q.input];
    try {
      run_to_completion(op->shade(*q.points, *q.radiance, *inputs));
    } catch (const std::exception& e) {
      if (state->error.empty()) state->error = e.what();
    }
  }
  return Gather(state);
}

Gather Exchange::fetch(const std::string& key, std::string*) {
  auto state = std::make_shared<GatherState>();
  state->remaining = 1;
  state->complete_one("nothing named '" + key + "' is published here");
  return Gather(state);
}

}  // namespace lf
