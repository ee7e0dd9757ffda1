#pragma once
// LightSelection: which lights a shading point should sample, learned where the camera looks. The light tree
// (render/lights/light_tree.hpp) weighs a light by power, distance and orientation; it cannot know whether the light is
// hidden. In an interior lit by many small lights most of them are: on Lost Empire 70 % of the tree's shadow rays
// from camera points are blocked. So before rendering, the first hits of camera rays through a grid of pixel
// centres are put in cells (a cube of the scene plus the axis the surface faces), each cell draws light samples
// through the tree from its points, shadow rays included, and keeps how much each light gave it. At a point in a
// learned cell a light is then drawn from the cell's distribution with probability `share`, else through the tree:
// the tree's share keeps every light that can reach the point drawable, so the estimate stays unbiased wherever the
// few samples of the pre-pass missed a light, and the density of the mixture is what multiple importance sampling
// weighs against. Outside learned cells (points the camera does not see) the tree alone is used.
//
// Determinism: a pure function of the scene, the camera, the image size and the options: the candidate points in
// pixel order, the cells by key, every sample seeded by its cell and index. Every process that builds it builds the
// same thing, so images do not depend on the farm's layout.
//
// Over a job's frames it can be carried (extend): a new view learns the cells no earlier view learned, and learns
// again a cell it sees with at least kRelearnPoints times the points it was learned from, or whose points' centre
// lies more than kRelearnMoved of a cell's edge from the centre of those it was learned from (a cell first seen
// from afar was learned from a corner of it, and one seen from elsewhere may be lit by other lights: on Lost
// Empire's walk keeping such cells left the direct light of frame 24 1.29x noisier than a farm of that frame alone,
// and with the points rule alone frame 13 was 1.08x); every other cell stays as it was. A frame's selection is a pure
// function of the job's views up to it. As bytes (state, restore) it is a tag and the options it was learned with,
// then one block a view, so a later view's bytes begin with an earlier's (a job's record keeps only what each view
// added); a cell learned again is in a later block under the same key.
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "render/lightops/lightop.hpp"
#include "render/math.hpp"

namespace lf {

struct LightSelectionOptions {
  float cell = 0.02f;           // a cell's edge, as a share of the scene's diagonal
  int samples = 4096;           // light samples per cell in the pre-pass
  int stride = 2;               // camera points at every stride-th pixel in x and y
  float share = 0.5f;           // chance a point in a learned cell draws from the cell's lights
  uint64_t seed = 0;
};

// The options from an op's parameters (`learned_cell`, `learned_samples`, `learned_stride`, `learned_share`).
LightSelectionOptions light_selection_options(const ParamTable& p, uint64_t seed);
// How an op picks the light to sample (its `light_sampling`): by the light tree (power, distance, orientation), by
// power alone, or partly from the lights learned before rendering. Read here for every op that has it.
enum class LightSampling { tree, power, learned };
LightSampling read_light_sampling(const ParamTable& p);
// Whether an op with these parameters learns lights (light_sampling = "learned"): replicas of such a `direct` or
// `pathtrace` pool share the learning (LightOpKind::shares_setup_with).
bool learns_lights(const Value::Map& params);

class LightSelection {
 public:
  // Learns the cells (traces through ctx, so a partitioned farm works too). Needs ctx.camera: without one, a
  // LightOpError names `op` (the LightOp asking) and says so. Replicas of a pool (ctx.replica_count > 1) each learn
  // every replica_count-th cell and exchange what they learned (ctx.exchange): every replica ends up with what one
  // process learning alone would have, bit for bit, in 1/replica_count of the time.
  static Task build(const SceneContext& ctx, const LightSelectionOptions& options, LightSelection& out,
                    const char* op = "light_selection");
  // Learns the cells of ctx's view that no earlier view learned (nor found dark), and those learns_again() says the
  // view sees better, as build() would; every other cell stays as it is. On a selection build() made, with the same
  // options.
  // Whether a view with `points` in a cell, centred at `centre`, learns again a cell learned from `learned` points
  // centred at `learned_centre`: at least kRelearnPoints times the points, or centres more than kRelearnMoved cell
  // edges apart (`inverse_size`: one over a cell's edge).
  static constexpr double kRelearnPoints = 1.5;
  static constexpr float kRelearnMoved = 0.25f;
  static bool learns_again(uint64_t points, Vec3 centre, uint32_t learned, Vec3 learned_centre, float inverse_size) {
    return static_cast<double>(points) >= kRelearnPoints * static_cast<double>(learned) ||
           length(centre - learned_centre) * inverse_size > kRelearnMoved;
  }
  Task extend(const SceneContext& ctx, const LightSelectionOptions& options, const char* op = "light_selection");
  // What was learned, as bytes; restore() on a selection built with the same options and scene makes it answer as
  // this one, bit for bit. restore() throws LightOpError naming `op` on bytes it cannot use, and then leaves the
  // selection as it was.
  std::string state() const;
  void restore(std::string_view state, const Scene& scene, const char* op = "light_selection");

  // The learned cell of a point at x facing n, or -1.
  int32_t cell_of(Vec3 x, Vec3 n) const;
  // Picks one of cell's lights with u in [0, 1): its index in Scene's light numbering and the chance the cell's
  // distribution gives it; `remainder` as LightTree::pick.
  void pick(int32_t cell, float u, size_t& light, float& probability, float* remainder) const;
  // The chance cell's distribution gives light (0 for one it never saw).
  float probability(int32_t cell, size_t light) const;
  float share() const { return share_; }
  // The environment's share of light samples at a point in `cell`, where it is `base` otherwise
  // (Scene::environment_share): the learned share mixed with `base` as the lights are mixed with the tree, so
  // neither side is ever left without samples.
  float environment_share(int32_t cell, float base) const {
    const float learned = cells_[static_cast<size_t>(cell)].environment;
    return learned < 0 ? base : share_ * learned + (1 - share_) * base;
  }
  // The chance of light at a point in `cell` under the mixture: the cell's distribution with chance share(), the
  // tree (which gives the light p_tree) otherwise.
  float mixture(int32_t cell, size_t light, float p_tree) const {
    return share_ * probability(cell, light) + (1 - share_) * p_tree;
  }

  size_t cell_count() const { return cells_.size(); }  // every cell learned, a cell learned again included
  uint32_t cell_points(int32_t cell) const { return cells_[static_cast<size_t>(cell)].points; }
  Vec3 cell_centre(int32_t cell) const { return cells_[static_cast<size_t>(cell)].centre; }
  float inverse_cell_size() const { return inverse_size_; }
  size_t entry_count() const { return lights_.size(); }
  // Pre-pass figures for STATS: its shadow rays and how many were blocked.
  uint64_t shadow_rays() const { return shadow_rays_; }
  uint64_t blocked_rays() const { return blocked_rays_; }
  // Those figures as STATS entries (learned_cells, learned_lights_per_cell, learned_blocked).
  void add_stats(Value::Map& m) const;

 private:
  uint64_t key_of(Vec3 x, Vec3 n) const;
  // The cell `key`'s distribution from each light's second moment (its lights in index order); a cell whose
  // samples all came back dark learns nothing (it is noted dark).
  void add_cell(uint64_t key, uint32_t points, Vec3 centre, std::map<uint32_t, double>& moment);
  // Appends a learned cell (it replaces one learned before under its key): its lights ascending, the running sums
  // pick() compares u with (the last 1), and how many points it was learned from and their centre.
  void append_cell(uint64_t key, uint32_t points, Vec3 centre, float environment, std::span<const uint32_t> lights,
                   std::span<const float> cdf);
  // Notes a cell whose samples all came back dark (it replaces one learned before under its key).
  void append_dark(uint64_t key, uint32_t points, Vec3 centre);
  struct Cell {
    uint32_t first = 0, count = 0;  // its lights in lights_ / cdf_, sorted by light
    float environment = -1;         // the environment's learned share of the cell's light (-1: not learned)
    uint32_t points = 0;            // the view's points it was learned from
    Vec3 centre{};                  // and their mean position
  };
  struct Known {
    int32_t cell = -1;  // its index in cells_, -1: learned dark
    uint32_t points = 0;
    Vec3 centre{};
  };
  struct Dark {
    uint64_t key = 0;
    uint32_t points = 0;
    Vec3 centre{};
  };
  // What one view added: the cells and dark keys up to these ends, and its pre-pass's rays.
  struct View {
    uint32_t cells_end = 0, dark_end = 0;
    uint64_t shadow_rays = 0, blocked_rays = 0;
  };
  float inverse_size_ = 1, share_ = 0.5f;
  std::unordered_map<uint64_t, Known> index_;  // what each key's cell was last learned as
  std::vector<Cell> cells_;
  std::vector<uint64_t> keys_;                      // each cell's key
  std::vector<Dark> dark_;  // the keys found dark, with their points and centre, in the order found
  std::vector<uint32_t> lights_;
  std::vector<float> probability_, cdf_;  // per entry: its chance, and the running sum up to and including it
  std::vector<View> views_;
  uint64_t shadow_rays_ = 0, blocked_rays_ = 0;
};

}  // namespace lf
