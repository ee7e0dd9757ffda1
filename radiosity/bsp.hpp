#pragma once
// The global BSP tree (Stürzlinger et al. §4): the upper levels of an axis-aligned BSP over the scene, the same on
// every node; each leaf stands for a subtree that one ring position holds. A segment's processor vector is the set of
// positions whose leaves it crosses: only they can hold something that blocks it.
#include <cstdint>
#include <span>
#include <vector>

#include "radiosity/mesh.hpp"

namespace lf::radiosity {

struct Box {
  Vec3 lo, hi;
  bool overlaps(const Box& b, float slack) const;
};

// The leaves a shot leaves to each packet's home (GlobalBsp::plan_shot): every segment of the shot crossing one of
// them is tested there by the node the packet circulates for, against these surfaces, instead of by the leaf's
// position.
//
// Every segment of a shot ends just in front of the shooter's plane, so a surface lying wholly on or behind that
// plane (the ceiling around a light, the wall a lit patch is part of) can block none of them; a leaf holding only
// such surfaces is skipped. Only segments that start clear of the plane are routed so; the few that start almost in
// it keep the static route.
struct ShotPlan {
  std::vector<uint8_t> home_leaf;  // per leaf; empty: none
  std::vector<uint8_t> inert_leaf;  // per leaf: nothing in it can block a segment of the shot; empty: none
  std::vector<uint32_t> surfaces;  // the surfaces overlapping those leaves, sorted (none: nothing there can block)
  Vec3 plane_normal;               // the shooter's plane: dot(plane_normal, p) = plane_offset
  float plane_offset = 0;
  float clear = 0;                 // a segment starting nearer the plane than this is routed statically
};

// Where a segment must be tested: the positions owning the leaves it crosses, and whether it crosses a leaf left to
// the packet's home.
struct Crossing {
  uint64_t positions = 0;
  bool home = false;
};

class GlobalBsp {
 public:
  // `balanced` (static load balancing of visibility complexity, Stürzlinger et al. §5.2): the depth and the dealing of
  // leaves chosen so that the busiest position has the least visibility work. The paper weighs a leaf by its
  // polygons; with Embree a ray's cost hardly depends on how many polygons a node holds, but on whether the node
  // has to cast it at all, so work is measured with a fixed probe of segments (between facing surfaces, half of
  // them ending on an emitter) counted once per position they cross. Otherwise: one level per doubling of
  // positions, planes through the middle of the box, leaves dealt round-robin.
  // `patch_nodes`: the node that computes each patch (ring x positions + position: its packets start there and
  // circulate in its ring), if known.
  static GlobalBsp build(const Mesh& mesh, int positions, bool balanced, std::span<const int> patch_nodes = {});

  int positions() const { return positions_; }
  size_t leaf_count() const { return leaves_.size(); }
  int depth() const { return depth_; }
  // Bit p set: the segment crosses a leaf of position p (conservatively: touching counts).
  uint64_t route(Vec3 a, Vec3 b) const;
  // The same, with the shot's home leaves apart.
  Crossing cross(Vec3 a, Vec3 b, const ShotPlan& shot) const;
  // Static balancing of visibility per shot, for a balanced tree (else empty). Every segment of a shot ends on the
  // shooter, so whichever position holds the space around it tests nearly every segment of the shot, whatever the
  // dealing of leaves: a static split cannot even out a ring whose shooters keep moving. Once the shooter is known
  // (every node knows it, and nothing else is needed), the leaves that load some node most are left to each
  // packet's home instead, which spreads their tests over all positions as the samples are spread. The choice is
  // estimated with a probe (segments from the elements of each patch facing the shooter to its sub-areas) that each
  // node's packets would carry: tested at home, then at each position it crosses in ring order until one holds a
  // surface that blocks it. Leaves go home greedily, busiest first, while the busiest node's estimated work goes
  // down; then single leaves either way while that lowers it. Deterministic, so every node makes the same plan.
  // `estimate`, if given, gets the nodes' estimated work under the plan (per node: ring x positions + position).
  struct ShotEstimate {
    double busiest = 0, mean = 0;
    std::vector<double> per_node;
  };
  ShotPlan plan_shot(const Mesh& mesh, const Polygon& shooter, std::span<const Vec3> targets,
                     ShotEstimate* estimate = nullptr) const;
  // The surfaces position p holds: those overlapping any of its leaves (a surface can be in several).
  const std::vector<uint32_t>& surfaces_of(int position) const { return held_[static_cast<size_t>(position)]; }
  // Probe segments a tree is dealt by (probe_segments), and each shot's probe.
  static constexpr size_t kProbeSegments = 4000;
  // The balanced tree's cost model, per position: of segments [first, first + count) of probe_segments() (a tree
  // is dealt by the first kProbeSegments), how many it would test, each once: those crossing one of its leaves that
  // holds a surface in front of the plane of the surface the segment ends on.
  std::vector<size_t> probe_load(const Mesh& mesh, size_t first = 0, size_t count = kProbeSegments) const;
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
  // Whether the leaf holds a surface in front of the plane dot(n, p) = offset, where a segment ending just in front of
  // it can be blocked.
  bool leaf_can_block(const Mesh& mesh, size_t leaf, Vec3 n, float offset) const;
  // Visits the leaves segment a-b crosses that hold a surface in front of the plane of `end_surface`, which it ends
  // on: the leaves a ray of a shot from that surface is tested in (plan_shot).
  template <class Visit>
  void walk_blocking(const Mesh& mesh, Vec3 a, Vec3 b, uint32_t end_surface, Visit&& visit) const;
  template <class Visit>
  void walk(int node, Vec3 a, Vec3 d, float t0, float t1, Visit&& visit) const;

  std::vector<Node> nodes_;
  std::vector<Box> leaf_box_;
  std::vector<std::vector<uint32_t>> leaves_;  // surfaces overlapping each leaf
  std::vector<int> owner_;                     // position of each leaf
  std::vector<std::vector<uint32_t>> held_;
  int positions_ = 1;
  int depth_ = 0;
  bool balanced_ = false;
  std::vector<int> patch_node_;
  std::vector<std::vector<Vec3>> element_centres_;  // per patch (a balanced tree of 2 positions or more)
  int rings_ = 1;
  float slack_ = 0;
};

Box bounds(const Polygon& p);
// Segments between random points (area-weighted, fixed seed) of surfaces that face each other: a stand-in for the
// visibility rays a solve will cast, the same in every process.
// `end_surface`, if given, gets per segment the surface it ends on.
std::vector<std::pair<Vec3, Vec3>> probe_segments(const Mesh& mesh, size_t count,
                                                  std::vector<uint32_t>* end_surface = nullptr);

}  // namespace lf::radiosity
