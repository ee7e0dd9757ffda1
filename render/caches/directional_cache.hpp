#pragma once
// The directional irradiance cache of Jansen & Reinhard ("Data Locality in Parallel Rendering", §2.4 and §3.2): for
// each cell of space, a picture of the radiance arriving from beyond the cell's surroundings, so that a diffuse ray
// that would leave them can often be answered here instead of being traced through the rest of the scene (in a
// partitioned farm: instead of travelling to other parts).
//
// Space is cut into a grid of cubic cells (the paper uses octree leaves; a grid gives every point its cell with no
// tree to build or ship, and cells of one size). Each cell holds a quadtree over the sphere of directions, in the
// equal-area cylindrical map (u = (z + 1) / 2, v = azimuth / 2 pi), so every node at one depth spans the same solid
// angle. A node keeps the mean radiance of the rays recorded in its solid angle, their count and the variance of
// their luminance. A leaf is split when it has `min_samples` rays, first unconditionally down to `uniform_depth`
// (the solid angle becomes small enough that its mean is mostly its own directions' light), then only where its
// luminance varies by more than `max_relative_spread` (standard deviation over mean), down to `max_depth`. A new
// child starts from its parent's mean with a count of one (the paper's footnote). A direction is answered when its
// leaf is at least `uniform_depth` deep, has `min_samples` rays, and is either smooth or as deep as allowed.
//
// Determinism (an image must not depend on the farm's layout): the cache is filled in a setup pass in a fixed order and
// then frozen; while rendering it only answers, so a pixel never depends on what was traced before it.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "render/math.hpp"
#include "render/scene/scene.hpp"

namespace lf {

struct DirectionalCacheOptions {
  int cells = 8;                    // cells along the scene's longest side
  int min_samples = 8;              // rays a leaf needs to be split, or to answer
  int uniform_depth = 3;            // depth every answering leaf reaches at least (4^3 = 64 directions per cell)
  int max_depth = 4;                // deepest a leaf may go
  // Split a leaf deeper than uniform_depth while its rays' luminance varies more than this (standard deviation over
  // mean). One path's estimate of the light along a ray is itself noisy (a spread of ~1 in a furnace), so only
  // light that varies well beyond that noise splits a leaf.
  float max_relative_spread = 2.0;
  float radius = 1.5;               // the local neighbourhood: a sphere of radius * the cell's half-diagonal
};

class DirectionalCache {
 public:
  DirectionalCache(const Scene& scene, const DirectionalCacheOptions& options);

  // The cell a point lies in (points outside the scene's box go to the nearest cell).
  uint32_t cell_of(Vec3 p) const;
  Vec3 centre_of(uint32_t cell) const;
  float radius() const { return radius_; }
  // How far along a ray from `origin` (inside `cell`) in direction `d` the local neighbourhood ends: where the ray
  // leaves the sphere of radius() about the cell's centre.
  float local_reach(uint32_t cell, Vec3 origin, Vec3 d) const;

  // The radiance the cache holds for rays leaving `cell` in direction `d`, if it is good enough to answer.
  bool lookup(uint32_t cell, Vec3 d, RGB& radiance) const;
  // Adds a ray's radiance (splitting leaves as the rule says). Ignored once frozen.
  void record(uint32_t cell, Vec3 d, RGB radiance);
  void freeze() { frozen_ = true; }
  bool frozen() const { return frozen_; }

  size_t cells_used() const { return trees_.size(); }
  size_t nodes() const;

 private:
  struct Node {
    RGB mean;
    float luminance_mean = 0, luminance_m2 = 0;  // Welford's running variance of luminance
    uint32_t count = 0;
    int32_t first_child = -1;                    // four children from here, or -1 for a leaf
    uint8_t depth = 0;
  };
  // Descends to the leaf holding direction (u, v); returns its index.
  static uint32_t leaf_of(const std::vector<Node>& tree, float u, float v);
  bool answers(const Node& leaf) const;

  DirectionalCacheOptions options_;
  Vec3 origin_;
  float cell_size_ = 1;
  int dims_[3] = {1, 1, 1};
  float radius_ = 1;
  bool frozen_ = false;
  std::unordered_map<uint32_t, std::vector<Node>> trees_;
};

// Directions to the equal-area map and back (u, v in [0, 1)).
void direction_to_map(Vec3 d, float& u, float& v);

}  // namespace lf
