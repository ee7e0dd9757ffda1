#pragma once
// LightTree: chooses among many lights by how much each can give a particular shading point, not by power alone
// (Conty Estevez & Kulla, "Importance Sampling of Many Lights with Adaptive Tree Splitting", 2018). A binary tree
// over the scene's lights (emitter triangles and point lights, in Scene's light numbering); each node bounds its
// lights' positions (a box), their emitting directions (a cone around an axis) and holds their power. A descent
// from the root goes left or right with probability proportional to each child's importance at the point:
// power x (bounded) cosine at the light x (bounded) cosine at the point / distance². The bounds are conservative,
// so a light that can reach the point always has a non-zero probability; the probability of the light picked is
// the product along the way, and probability() walks the same path again (for MIS when a BSDF ray hits a light).
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

  // Picks a light for point x whose surface faces n (unit). Returns false when no light can reach x's side;
  // otherwise `light` is an index in Scene's numbering (below emitters().size() a triangle, above a point light)
  // and `probability` the chance this call picked it.
  // With `remainder`, also where u fell within the picked light's share, rescaled to [0, 1): a number as uniform as
  // u, for a sampler that draws the light and the point on it from one 2D point.
  bool pick(Vec3 x, Vec3 n, float u, size_t& light, float& probability, float* remainder = nullptr) const;
  // The chance that pick() at (x, n) returns `light`.
  float probability(Vec3 x, Vec3 n, size_t light) const;

  size_t light_count() const { return trail_.size(); }
  size_t node_count() const { return nodes_.size(); }
  int depth() const { return depth_; }

 private:
  struct Node {
    Vec3 lo, hi;         // box around the lights' points
    Vec3 centre;         // of the box, and the radius of the sphere around it (precomputed for importance())
    float radius = 0;
    Vec3 axis;           // emitting directions lie within `cos_spread` of it (cos_spread -1: any direction)
    float cos_spread = 1, sin_spread = 0;
    float power = 0;
    uint32_t right = 0;  // interior: the right child (the left is the next node); leaf: unused
    uint32_t light = 0;  // leaf: the light
    bool leaf = false;
  };
  struct Item {
    Vec3 lo, hi, centroid, axis;
    float cos_spread, power;
    uint32_t light;
  };

  uint32_t build(std::vector<Item>& items, size_t first, size_t last, int depth, uint64_t trail);
  static void finish(Node& node);  // the precomputed fields, from the box and cone
  float importance(const Node& node, Vec3 x, Vec3 n) const;

  std::vector<Node> nodes_;
  std::vector<uint64_t> trail_;  // per light: the turns from the root to its leaf (bit d set: right at depth d)
  int depth_ = 0;
};

}  // namespace lf
