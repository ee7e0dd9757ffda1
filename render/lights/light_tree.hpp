#pragma once
// LightTree: chooses among many lights by how much each can give a particular shading point, not by power alone
// (Conty Estevez & Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018). A tree
// over the scene's lights (emitter triangles and point lights, in Scene's light numbering); each node bounds its
// lights' positions (a box), their emitting directions (a cone around an axis) and holds their power. A descent
// from the root goes to one of a node's children with probability proportional to each child's importance at the
// point:
// power x (bounded) cosine at the light x (bounded) cosine at the point / distance². The bounds are conservative,
// so a light that can reach the point always has a non-zero probability; the probability of the light picked is
// the product along the way, and probability() walks the same path again (for MIS when a BSDF ray hits a light).
//
// The binary tree is built by halving at the median and then collapsed into a tree of four-way nodes (each child's
// bounds held side by side), so that a descent weighs four children at once in 4-lane vector arithmetic and has
// half the levels: the walk is the largest cost of a direct-light sample among thousands of lights.
//
// A pure function of the scene: every process that loads the same scene builds the same tree.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "render/math.hpp"

namespace lf {

class Scene;

class LightTree {
 public:
  explicit LightTree(const Scene& scene);

  // Picks a light for point x whose surface faces n (unit, or zero for a point that takes light from every side,
  // such as rough glass). Returns false when no light can reach x's side;
  // otherwise `light` is an index in Scene's numbering (below emitters().size() a triangle, above a point light)
  // and `probability` the chance this call picked it.
  // With `remainder`, also where u fell within the picked light's share, rescaled to [0, 1): a number as uniform as
  // u, for a sampler that draws the light and the point on it from one 2D point.
  bool pick(Vec3 x, Vec3 n, float u, size_t& light, float& probability, float* remainder = nullptr) const;
  // Whether any light may reach x's side at all (the root's importance there is not 0): else pick() finds none.
  bool reaches(Vec3 x, Vec3 n) const;
  // The chance that pick() at (x, n) returns `light`.
  float probability(Vec3 x, Vec3 n, size_t light) const;

  size_t light_count() const { return trail_.size(); }
  size_t node_count() const { return nodes_.size(); }
  int depth() const { return depth_; }  // levels of four-way nodes below the root

 private:
  static constexpr int kWidth = 4;
  // Four children's bounds, lane by lane (a child whose power is 0 is an empty slot).
  struct alignas(16) Wide {
    float cx[kWidth], cy[kWidth], cz[kWidth];  // centre of the box around the child's lights
    float radius[kWidth];                      // of the sphere around that box
    float ax[kWidth], ay[kWidth], az[kWidth];  // emitting directions lie within cos_spread of this axis
    float cos_spread[kWidth], sin_spread[kWidth];  // (cos_spread -1: any direction)
    float power[kWidth];
    int32_t child[kWidth];  // >= 0: a four-way node; < 0: the leaf of light ~child
  };
  // The binary tree, only while building.
  struct Node {
    Vec3 lo, hi, axis;
    float cos_spread = 1, power = 0;
    uint32_t right = 0;  // interior: the right child (the left is the next node)
    uint32_t light = 0;  // leaf: the light
    bool leaf = false;
  };
  struct Item {
    Vec3 lo, hi, centroid, axis;
    float cos_spread, power;
    uint32_t light;
  };

  static uint32_t build(std::vector<Node>& nodes, std::vector<Item>& items, size_t first, size_t last);
  int32_t collapse(const std::vector<Node>& binary, uint32_t at, int depth, uint64_t trail);
  // Each child's importance at x: an upper bound, up to a constant, of what its lights can give x.
  void importance(const Wide& node, Vec3 x, Vec3 n, float out[kWidth]) const;
  // The children's importances into `weight`, and their sum.
  float weigh(const Wide& node, Vec3 x, Vec3 n, float weight[kWidth]) const;

  std::vector<Wide> nodes_;
  std::vector<uint64_t> trail_;  // per light: the slots from the root to its leaf, 2 bits per level
  int depth_ = 0;
};

}  // namespace lf
