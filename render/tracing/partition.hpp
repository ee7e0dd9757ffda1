#pragma once
// A scene split by space into parts of about equal estimated ray cost, for data-parallel tracing (data partitioning
// as in Jansen & Reinhard, "Data Locality in Parallel Rendering", section 2.1): each part is what one `geometry` actor holds, and a ray is traced part by part
// along its way, nearest part first, until a hit is nearer than the next part's box.
//
// The split is a BSP by recursive bisection: a set of triangles that must become k parts is cut across the longest
// axis of its centroids' box, at the centroid where the running cost reaches floor(k/2)/k of the set's cost, and
// each side is split again. A triangle goes whole to the side of its centroid, so parts' boxes may overlap a little;
// the routing below allows for that. Why bisection rather than the paper's octree with region growing: it gives
// equal costs for any count of parts (not only where octree cells happen to fall) and keeps each part one compact
// region, the coherence the paper wants; docs/decisions.md.
//
// Cost of a triangle (what a part's share of ray work is estimated from): half its share of the scene's surface
// area (the chance that a ray ends on it), half its share of the triangle count (intersection tests grow with
// the triangles a ray passes), unless the caller measured better weights (e.g. from probe rays, the paper's [26]).
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "render/tracing/camera.hpp"
#include "render/tracing/tied_hits.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

struct ScenePart {
  std::vector<uint32_t> triangles;  // scene triangle ids, ascending
  Bounds bounds;                    // around its triangles' corners
  double cost = 0;                  // its share of the estimated cost (the parts' costs sum to 1)
};

// `parts` >= 1 parts, none empty (fewer when the scene has fewer triangles). `weights`: a cost per triangle to use
// instead of the area-and-count estimate (empty: the estimate).
std::vector<ScenePart> partition_scene(const Scene& scene, int parts, std::span<const double> weights = {});

// A cost per triangle measured the paper's other way (its [26]: from the rays the farm will trace): the camera's
// rays at a coarse resolution and one diffuse bounce from each point they hit, traced through the whole scene; a
// triangle's weight is the probe rays that end on it, plus a floor from the area-and-count estimate spread over the
// scene, so that geometry no probe reached still counts a little. Same scene, camera and size: same weights.
std::vector<double> probe_weights(const Scene& scene, const RayTracer& tracer, const Camera& camera, int width,
                                  int height);
// The split from probe weights, then `rounds` of rebalancing by what the probe rays would do in it: each ray visits
// the parts whose boxes it enters before its hit, so a part's visits are its share of ray work; parts above the mean
// get heavier weights (a smaller box) and the scene is split again. Returns, of the splits whose parts are even (the
// busiest at most 1.2x the mean), else of all, the one whose busiest part has the fewest visits (what bounds a
// frame's time when each part has a host), of equals the one with the fewest visits in all (docs/decisions.md).
std::vector<ScenePart> partition_by_probes(const Scene& scene, const RayTracer& tracer, const Camera& camera,
                                           int width, int height, int parts, int rounds = 4);

// Where a ray passes a part's box: [enter, exit] along it, within the ray's [tnear, tfar].
struct PartCrossing {
  uint32_t part;
  float enter, exit;
};
// The parts' boxes widened by a small margin, so that rounding never skips a part a hit lies in (a needless visit
// costs only time). What parts_along takes, computed once per split rather than per ray.
std::vector<Bounds> padded_boxes(std::span<const ScenePart> parts);
std::vector<Bounds> padded_boxes(std::vector<Bounds> boxes);
// The parts whose (padded) boxes the ray passes, nearest entry first (ties by part index).
void parts_along(const Ray& ray, std::span<const Bounds> boxes, std::vector<PartCrossing>& out);

// A batch of rays on its way through a split's parts, round by round (PartitionedTracer here, RemoteTracing in a
// farm): each round every ray still searching visits the next part along it, in parts_along's order, and goes on to
// the part after unless what it found ends its search.
class RayRoutes {
 public:
  RayRoutes(std::span<const Ray> rays, std::span<const Bounds> boxes);
  bool done() const { return active_.empty(); }
  // This round's rays (indices into the batch), grouped by the part each visits: one list per part, empty where none.
  const std::vector<std::vector<uint32_t>>& round();
  // After a round. A nearest hit ends the search once it is nearer than the next part's entry; an occlusion test once
  // the ray is blocked.
  void advance(std::span<const Hit> hits);
  void advance(std::span<const uint8_t> blocked);

 private:
  template <class Ends>
  void advance_unless(Ends&& ends);
  std::vector<std::vector<PartCrossing>> crossings_;
  std::vector<uint32_t> active_;
  std::vector<size_t> next_;  // index into crossings_[i] of the part ray i visits this round
  std::vector<std::vector<uint32_t>> by_part_;
};

// Tracing through every part in this process: what the geometry actors do together, used to check them and the
// split. A ray visits parts in the order parts_along gives and stops once its hit is nearer than the next part's
// entry, so it finds the whole scene's nearest hit; coplanar overlapping faces are settled by the same rule as the
// whole scene's tracer (render/tracing/tied_hits.hpp), so the hit is the same.
class PartitionedTracer {
 public:
  PartitionedTracer(const Scene& scene, std::vector<ScenePart> parts);
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const;
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const;
  const std::vector<ScenePart>& parts() const { return parts_; }
  // Rays traced in each part so far (a ray counts once in every part it visits).
  const std::vector<uint64_t>& rays_per_part() const { return rays_per_part_; }

 private:
  // Each round of RayRoutes, `trace(part, indices)` traces those rays in that part and keeps what they found.
  template <class Trace>
  void route(std::span<const Ray> rays, Trace&& trace, auto found) const;

  std::vector<ScenePart> parts_;
  std::vector<Bounds> boxes_;  // padded
  std::vector<std::unique_ptr<RayTracer>> tracers_;
  TiedHits ties_;
  mutable std::vector<uint64_t> rays_per_part_;
};

}  // namespace lf
