#pragma once
// Helpers for render/ tests: closed forms and an in-process stand-in for a pool's all-gather.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "render/lightops/lightop.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/scene/scene.hpp"

namespace lf::test {

// n points with every field set and told apart by its index: point i at (i, i+1, i+2), material i % 3, key 1000 + i.
inline ShadingPoints numbered_points(size_t n) {
  ShadingPoints p;
  for (size_t i = 0; i < n; ++i) {
    const float f = static_cast<float>(i);
    p.push_back({f, f + 1, f + 2}, {0, 1, 0}, {0, 0, 1}, static_cast<uint32_t>(i % 3), 1000 + i);
  }
  return p;
}

// `direct` run in-process on pts (no inputs), `samples` light samples a point drawn as `sampling` says.
inline std::vector<RGB> shade_direct(const SceneContext& ctx, const ShadingPoints& pts, const std::string& sampling,
                                     int samples) {
  auto op = create_lightop(*find_lightop_kind("direct"),
                           ParamTable(Value::Map{{"light_samples", samples}, {"light_sampling", sampling}}, "direct"));
  LocalInputs none;
  run_to_completion(op->setup(ctx, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  return out;
}

// Lambert's contour formula: the form factor from a differential area at p with normal n to a polygon,
// F = 1/(2 pi) sum_i angle(r_i, r_i+1) n . unit(r_i x r_i+1), r_i unit vectors to the corners. In double: for a small
// polygon far away the angles are tiny and float's acos of a cosine near 1 is off by percents.
inline double form_factor(Vec3 p, Vec3 n, const std::vector<Vec3>& polygon) {
  using D3 = std::array<double, 3>;
  auto unit_to = [&](Vec3 q) {
    const D3 d{static_cast<double>(q.x) - p.x, static_cast<double>(q.y) - p.y, static_cast<double>(q.z) - p.z};
    const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return D3{d[0] / l, d[1] / l, d[2] / l};
  };
  double sum = 0;
  for (size_t i = 0; i < polygon.size(); ++i) {
    const D3 a = unit_to(polygon[i]), b = unit_to(polygon[(i + 1) % polygon.size()]);
    const D3 c{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const double sine = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (sine == 0) continue;
    const double cosine = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const double angle = std::atan2(sine, cosine);  // accurate for small angles, unlike acos
    sum += angle * (n.x * c[0] + n.y * c[1] + n.z * c[2]) / sine;
  }
  return std::abs(sum) / (2 * M_PI);
}

// A closed box from the origin to `size` (a unit cube unless said) whose six faces, wound inwards, all have
// material m (the furnace, a room).
inline void add_closed_box(Scene& s, uint32_t m, Vec3 size = {1, 1, 1}) {
  const float x = size.x, y = size.y, z = size.z;
  const Vec3 c[8] = {{0, 0, 0}, {x, 0, 0}, {x, y, 0}, {0, y, 0}, {0, 0, z}, {x, 0, z}, {x, y, z}, {0, y, z}};
  s.add_quad(c[0], c[1], c[2], c[3], m);
  s.add_quad(c[4], c[7], c[6], c[5], m);
  s.add_quad(c[0], c[4], c[5], c[1], m);
  s.add_quad(c[3], c[2], c[6], c[7], m);
  s.add_quad(c[0], c[3], c[7], c[4], m);
  s.add_quad(c[1], c[5], c[6], c[2], m);
}

// An all-gather among n in-process replicas: once every part is in, each waiting replica gets all of them.
struct Board {
  explicit Board(size_t n) : parts(n), in(n, false) {}
  std::vector<std::string> parts;
  std::vector<bool> in;
  std::vector<std::pair<std::shared_ptr<GatherState>, std::vector<std::string>*>> waiting;
};

class BoardExchange final : public Exchange {
 public:
  BoardExchange(Board& b, size_t index) : board_(b), index_(index) {}
  Gather all_gather(std::string part, std::vector<std::string>* out) override {
    auto state = std::make_shared<GatherState>();
    state->remaining = 1;
    board_.parts[index_] = std::move(part);
    board_.in[index_] = true;
    board_.waiting.emplace_back(state, out);
    if (std::find(board_.in.begin(), board_.in.end(), false) == board_.in.end()) {
      auto waiting = std::move(board_.waiting);
      board_.waiting.clear();
      std::fill(board_.in.begin(), board_.in.end(), false);  // ready for the next round
      for (auto& [s, o] : waiting) *o = board_.parts;
      // The others resume now; the caller finds its gather complete through await_ready.
      for (auto& [s, o] : waiting)
        if (s != state) s->complete_one();
      state->remaining = 0;
    }
    return Gather(state);
  }

 private:
  Board& board_;
  size_t index_;
};

// Lost Empire from ../shared/scenes with its torches emitting (its MTL has their Ke commented out); empty when the
// scenes are not there (the caller skips, naming kLostEmpireObj).
inline const std::string kLostEmpireObj =
    std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/lost_empire/lost_empire.obj";
inline std::optional<Result<Scene>> lost_empire_with_torches() {
  if (!std::filesystem::exists(kLostEmpireObj)) return std::nullopt;
  SceneSpec spec;
  spec.file = kLostEmpireObj;
  spec.materials.push_back(Value::Map{{"name", "Torch"}, {"emission", Value::Array{9.0, 9.0, 6.0}}});
  return Scene::load(spec);
}

}  // namespace lf::test
