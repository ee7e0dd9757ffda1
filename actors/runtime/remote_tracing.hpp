#pragma once
// Tracing through a partitioned scene's geometry actors (partition { parts = N }; render/tracing/partition.hpp): the
// Tracing a LightOp co_awaits in a farm whose scene is split. Each ray visits the parts whose boxes its path
// crosses, nearest first, in rounds: per round one batched `trace` request per part (actors/codecs/trace_codec.hpp),
// until its hit is nearer than the next part's box. Then ties between coplanar faces are settled as the whole
// scene's tracer settles them, so the answer is RayTracer::intersect's on the whole scene, bit for bit.
#include <cstdint>
#include <memory>
#include <vector>

#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/runtime.hpp"
#include "core/value.hpp"
#include "render/tracing/tied_hits.hpp"
#include "render/lightops/lightop.hpp"
#include "render/tracing/partition.hpp"

namespace lf {

class RemoteTracing final : public Tracing {
 public:
  // `boxes`: each part's box as the director sent it, in the order of the runtime's geometry actors. `batch`: rays
  // per request at most.
  RemoteTracing(Runtime& rt, const Scene& scene, std::vector<Bounds> boxes, size_t batch);
  // This process holds part `part` itself (a BVH of `tracer`'s triangles, the same as its geometry actor's): rays
  // that visit it are traced here, and only the other parts are asked.
  void hold_part(size_t part, std::unique_ptr<RayTracer> tracer);
  // The tracing a CONFIG's `geometry` and `part_boxes` describe (4096 rays a request), holding `local_part` itself
  // when the CONFIG gives one; null without them.
  static std::unique_ptr<RemoteTracing> for_config(const ActorConfig& config, Runtime& rt, const Scene& scene);
  Task intersect(std::span<const Ray> rays, std::span<Hit> hits) override;
  // As intersect, and which part's triangle each hit was found on (kNoPart for a miss): where a point lies, for
  // sending it to a replica that holds its part (partition { colocate = true }). A tie settled onto a coplanar twin
  // keeps the part of the face that was found.
  static constexpr uint32_t kNoPart = UINT32_MAX;
  Task intersect(std::span<const Ray> rays, std::span<Hit> hits, std::span<uint32_t> hit_part);
  Task occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) override;
  // What went to the parts: rays asked about, part visits (a ray in n parts' boxes makes up to n), of them those
  // traced in the part this process holds, requests, the rays' and answers' bytes that crossed to other processes
  // (payload, both ways, without message headers); and whether the asking process holds a BVH of the whole scene
  // anyway (a host agent's).
  Value stats(bool whole_scene_bvh) const;
  size_t parts() const { return boxes_.size(); }
  // What stats() reports: rays asked about, part visits, of them in the part held here, requests sent, payload bytes.
  struct Counts {
    uint64_t rays = 0, visits = 0, local_visits = 0, requests = 0, payload_bytes = 0;
  };

 private:
  Runtime& rt_;
  const Scene& scene_;
  std::vector<Bounds> boxes_;  // padded (render/tracing/partition.hpp)
  TiedHits ties_;
  size_t batch_;
  size_t local_part_ = SIZE_MAX;
  std::unique_ptr<RayTracer> local_tracer_;
  Counts counts_;
};

}  // namespace lf
