#pragma once
// Hits that two BVHs may report differently, settled by one rule from the scene alone. A ray that meets several
// faces at the same distance is answered by whichever face a BVH happens to test last: the whole scene's BVH, the
// BVH of one part of a partitioned scene (render/tracing/partition.hpp), and Embree's packet and single-ray traversals can
// each report a different one, with a different normal, offset or texture, so different light. Two cases:
//  - coplanar faces that overlap (a face and its back-to-back twin, a table top's two sides, a decal on a wall);
//  - a hit on or next to an edge or corner that neighbouring faces share (a quad's diagonal, a cube's edge, a fan's
//    centre): within kEdgeBand of an edge, in the reported face's barycentrics.
// Among the faces of that neighbourhood that contain the hit point (the reported face's overlapping partners, and
// the faces with a corner at the near edge's ends, and their partners, where the ray meets them at the same
// distance, on their own edge for the former), the rule picks the one facing the ray (a viewer
// sees the side turned towards it), then the lower triangle id, and computes its distance here by one formula,
// whichever face the BVH reported. Neighbours are faces with a corner at the same position (vertices are compared by
// value, so a mesh written with repeated vertices is still one surface); a T-junction (a corner lying on another
// face's edge) is not a neighbourhood, and neither are faces that cross each other.
#include <cstdint>
#include <vector>

#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

class TiedHits {
 public:
  // A hit this close to an edge of its face (the smallest barycentric) is settled among the faces around it. Wide
  // against rounding: a face can only be reported for a ray that passes within float precision of it (~1e-7).
  static constexpr float kEdgeBand = 1e-4f;
  // A BVH's own barycentrics and this class's are two float computations of one value, expected to differ by float
  // rounding (not measured), far less than kCoarseBand - kEdgeBand: a hit farther than kCoarseBand from its face's
  // edges by them is then farther than kEdgeBand by this class's, and is left alone at once.
  static constexpr float kCoarseBand = 1e-3f;
  // A neighbour ties only at the reported face's distance, within this share of it (two faces' distances to the
  // point they share differ by float rounding only; on tied_hits.test's Lost Empire ray both read 1.24278975).
  static constexpr float kSameDistance = 1e-4f;

  explicit TiedHits(const Scene& scene);
  // Triangles that have at least one overlapping coplanar face.
  size_t tied_triangles() const;
  // The rule's hit for `ray`, given the hit a BVH found (unchanged when it is inside a face that overlaps no other).
  Hit settle(const Ray& ray, Hit hit) const;
  // The same, given the BVH's own barycentrics of the hit (u, v: the weights of the face's corners 1 and 2): a hit
  // that is nowhere near an edge by them (kCoarseBand) is left as it is without working its barycentrics out here.
  // The answer is settle(ray, hit)'s either way.
  Hit settle(const Ray& ray, Hit hit, float u, float v) const;
  // The faces overlapping triangle t (for tests).
  std::vector<uint32_t> partners(uint32_t t) const;
  // The faces with a corner where triangle t has its corner `corner`, t among them (for tests).
  std::vector<uint32_t> fan(uint32_t t, int corner) const;

 private:
  // u, v, distance: the reported face's barycentrics and distance by this class's formula.
  Hit settle_among_neighbours(const Ray& ray, Hit hit, float u, float v, float distance) const;

  const Scene& scene_;
  std::vector<uint32_t> first_;     // partners of t: partners_[first_[t]] .. partners_[first_[t + 1] - 1]
  std::vector<uint32_t> partners_;
  std::vector<uint32_t> position_of_vertex_;  // a vertex's position id (vertices with equal coordinates share one)
  std::vector<uint32_t> fan_first_;           // faces at position p: fan_[fan_first_[p]] .. fan_[fan_first_[p + 1] - 1]
  std::vector<uint32_t> fan_;
};

}  // namespace lf
