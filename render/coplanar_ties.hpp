#pragma once
// Coplanar faces that overlap (a face and its back-to-back twin, a table top's two sides, a decal on a wall) are
// hit at the same distance, and a BVH reports whichever it happens to test last: the whole scene's BVH and the BVH
// of one part of a partitioned scene (render/partition.hpp) can report different faces for the same ray, with
// different normals, so different light. Both therefore settle such a hit by one rule, from the scene alone:
// among the faces coplanar with and overlapping the one hit that contain the hit point, the one facing the ray
// (a viewer sees the side turned towards it), then the lower triangle id; and its distance computed here, by one
// formula, whichever face the BVH reported. Found once per scene: faces within 1e-4 of the same plane (normal and
// offset) whose areas overlap (sharing only an edge is not overlapping).
#include <cstdint>
#include <vector>

#include "render/scene.hpp"
#include "render/tracer.hpp"

namespace lf {

class CoplanarTies {
 public:
  explicit CoplanarTies(const Scene& scene);
  // Triangles that have at least one overlapping coplanar face.
  size_t tied_triangles() const;
  // The rule's hit for `ray`, given the hit a BVH found (unchanged when that face overlaps no other).
  Hit settle(const Ray& ray, Hit hit) const;
  // The faces overlapping triangle t (for tests).
  std::vector<uint32_t> partners(uint32_t t) const;

 private:
  const Scene& scene_;
  std::vector<uint32_t> first_;     // partners of t: partners_[first_[t]] .. partners_[first_[t + 1] - 1]
  std::vector<uint32_t> partners_;
};

}  // namespace lf
