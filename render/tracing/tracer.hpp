#pragma once
// RayTracer: the scene in an Embree BVH. Rays are traced in streams (rtcIntersect1M / rtcOccluded1M), which is
// how Embree is fastest for the coherent batches renderers and LightOps produce.
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "render/math.hpp"
#include "render/scene/scene.hpp"

namespace lf {

struct Ray {
  Vec3 origin;
  Vec3 direction;
  float tnear = 0;
  float tfar = std::numeric_limits<float>::infinity();
};

struct Hit {
  static constexpr uint32_t kNone = 0xffffffffu;
  uint32_t triangle = kNone;
  float t = 0;
  bool valid() const { return triangle != kNone; }
};

class RayTracer {
 public:
  explicit RayTracer(const Scene& scene);
  // Only `triangles` of the scene (one part of a partitioned scene, render/tracing/partition.hpp), with only their own
  // vertices; hits still name scene triangles. A triangle's hit is the same arithmetic as in the whole scene's BVH.
  RayTracer(const Scene& scene, std::vector<uint32_t> triangles);
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  // `coherent` lets Embree trace the stream in SIMD packets, whose arithmetic depends on which rays share a packet: use
  // it only for batches that are the same on every farm layout (a tile's camera rays). Everything else is traced ray by
  // ray, so a ray's hit never depends on the batch it came in (images must not depend on the farm's layout). Coplanar
  // overlapping faces hit at the same distance are settled by a rule from the scene alone (render/tracing/tied_hits.hpp), so
  // the hit does not depend on which BVH found it.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, bool coherent = false) const;
  // The hit this BVH finds, ties unsettled (a part's own search; the partitioned tracer settles them after).
  void intersect_unsettled(std::span<const Ray> rays, std::span<Hit> hits, bool coherent = false) const;
  // occluded[i] = 1 when something lies on ray i between tnear and tfar.
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const;
  const Scene& scene() const { return scene_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const Scene& scene_;
};

}  // namespace lf
