#pragma once
// The global BSP tree (Stürzlinger et al. §4): the upper levels of an axis-aligned BSP over the scene, the same on
// every node; each leaf stands for a subtree that one ring position holds. A segment's processor vector is the set of
// positions whose leaves it crosses: only they can hold something that blocks it.
#include <cstdint>
#include <vector>

#include "radiosity/mesh.hpp"

namespace lf::radiosity {

struct Box {
  Vec3 lo, hi;
  bool overlaps(const Box& b, float slack) const;
};

class GlobalBsp {
 public:
  // `balanced` (static load balancing of visibility complexity, Stürzlinger et al. §5.2): the depth and the dealing of
  // leaves chosen so that the busiest position has the least visibility work. The paper weighs a leaf by its
  // polygons; with Embree a ray's cost hardly depends on how many polygons a node holds, but on whether the node
  // has to cast it at all, so work is measured with a fixed probe of segments (between facing surfaces, half of
  // them ending on an emitter) counted once per position they cross. Otherwise: one level per doubling of
  // positions, planes through the middle of the box, leaves dealt round-robin.
  static GlobalBsp build(const Mesh& mesh, int positions, bool balanced);

  int positions() const { return positions_; }
  size_t leaf_count() const { return leaves_.size(); }
  int depth() const { return depth_; }
  // Bit p set: the segment crosses a leaf of position p (conservatively: touching counts).
  uint64_t route(Vec3 a, Vec3 b) const;
  // The surfaces position p holds: those overlapping any of its leaves (a surface can be in several).
  const std::vector<uint32_t>& surfaces_of(int position) const { return held_[static_cast<size_t>(position)]; }
  // Per position, how many of the mesh's probe segments cross its space (the balanced tree's cost model).
  std::vector<size_t> probe_load(const Mesh& mesh) const;
  // The leaf that contains point p, and its position (for tests).
  int position_of_point(Vec3 p) const;

 private:
  struct Node {
    int axis = -1;  // -1: leaf
    float split = 0;
    int left = -1, right = -1;
    int leaf = -1;
  };
  int build_node(const Mesh& mesh, const std::vector<uint32_t>& surfaces, Box box, int depth, int max_depth);
  template <class Visit>
  void walk(int node, Vec3 a, Vec3 d, float t0, float t1, Visit&& visit) const;

  std::vector<Node> nodes_;
  std::vector<Box> leaf_box_;
  std::vector<std::vector<uint32_t>> leaves_;  // surfaces overlapping each leaf
  std::vector<int> owner_;                     // position of each leaf
  std::vector<std::vector<uint32_t>> held_;
  int positions_ = 1;
  int depth_ = 0;
  float slack_ = 0;
};

Box bounds(const Polygon& p);
// Segments between random points (area-weighted, fixed seed) of surfaces that face each other: a stand-in for the
// visibility rays a solve will cast, the same in every process.
std::vector<std::pair<Vec3, Vec3>> probe_segments(const Mesh& mesh, size_t count);

}  // namespace lf::radiosity
