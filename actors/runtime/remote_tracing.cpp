#include "actors/runtime/remote_tracing.hpp"

#include <algorithm>
#include <memory>

#include "actors/codecs/trace_codec.hpp"

namespace lf {

RemoteTracing::RemoteTracing(Runtime& rt, const Scene& scene, std::vector<Bounds> boxes, size_t batch)
    : rt_(rt), scene_(scene), boxes_(padded_boxes(std::move(boxes))), ties_(scene), batch_(std::max<size_t>(1, batch)) {}

std::unique_ptr<RemoteTracing> RemoteTracing::for_config(const ActorConfig& config, Runtime& rt, const Scene& scene) {
  if (config.geometry.empty()) return nullptr;
  std::vector<Bounds> boxes;
  for (size_t p = 0; p < config.geometry.size(); ++p) {
    const float* b = config.part_boxes.data() + 6 * p;
    boxes.push_back(Bounds{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}});
  }
  auto tracing = std::make_unique<RemoteTracing>(rt, scene, std::move(boxes), 4096);
  if (config.local_part >= 0)
    tracing->hold_part(static_cast<size_t>(config.local_part), std::make_unique<RayTracer>(scene, config.part_triangles));
  return tracing;
}

void RemoteTracing::hold_part(size_t part, std::unique_ptr<RayTracer> tracer) {
  local_part_ = part;
  local_tracer_ = std::move(tracer);
}

namespace {

// One round's answers from one part: where each ray of the round stands in the caller's arrays, and what came back.
struct PartRound {
  std::vector<uint32_t> rays;  // indices into the caller's rays
  std::vector<Hit> hits;
  std::vector<uint8_t> blocked;
};

}  // namespace

// The rounds of intersect and occluded, which differ only in what a part answers and when a ray is done.
// The part this process holds, if any, is traced in place, exactly as its geometry actor would trace it.
template <bool Any>
static Task trace_rounds(Runtime& rt, const Scene& scene, const std::vector<Bounds>& boxes, size_t batch,
                         size_t local_part, const RayTracer* local_tracer, std::span<const Ray> rays,
                         std::span<Hit> hits, std::span<uint8_t> blocked, std::span<uint32_t> hit_part,
                         RemoteTracing::Counts& counts) {
  const size_t parts = boxes.size();
  // The rays of a round's part from `begin` to `end`, each searching only as near as its best hit so far (only as
  // near or nearer can replace it).
  auto rays_of = [&](const PartRound& r, size_t begin, size_t end) {
    std::vector<Ray> out;
    out.reserve(end - begin);
    for (size_t k = begin; k < end; ++k) {
      Ray ray = rays[r.rays[k]];
      if (!Any && hits[r.rays[k]].valid()) ray.tfar = hits[r.rays[k]].t;
      out.push_back(ray);
    }
    return out;
  };
  RayRoutes routes(rays, boxes);
  while (!routes.done()) {
    const auto& by_part = routes.round();
    std::vector<std::shared_ptr<PartRound>> round(parts);
    for (size_t p = 0; p < parts; ++p)
      if (!by_part[p].empty()) round[p] = std::make_shared<PartRound>(PartRound{by_part[p], {}, {}});
    auto state = std::make_shared<GatherState>();
    for (size_t p = 0; p < parts; ++p) {
      if (!round[p]) continue;
      auto r = round[p];
      if constexpr (Any) r->blocked.resize(r->rays.size());
      else r->hits.resize(r->rays.size());
      counts.visits += r->rays.size();
      if (p == local_part) continue;  // after the requests are out, so that both run at once
      // A ray goes as 8 floats and comes back as a hit (triangle and distance) or one byte (trace_codec.hpp).
      counts.payload_bytes += r->rays.size() * (8 * sizeof(float) + (Any ? 1 : sizeof(uint32_t) + sizeof(float)));
      for (size_t begin = 0; begin < r->rays.size(); begin += batch) {
        const size_t end = std::min(begin + batch, r->rays.size());
        const std::vector<Ray> chunk = rays_of(*r, begin, end);
        ++state->remaining;
        ++counts.requests;
        const std::string part_name = rt.geometry_name(p);
        const size_t triangles = scene.triangle_count();
        rt.geometry(p).request(wire::Op::trace, encode_trace_request(chunk, Any),
                               [state, r, begin, end, part_name, triangles](Result<wire::Message> reply) {
                                 if (!reply) return state->complete_one(reply.error().message);
                                 if constexpr (Any) {
                                   auto got = decode_occlusion(reply->body, end - begin);
                                   if (!got) return state->complete_one(part_name + ": " + got.error().message);
                                   std::copy(got->begin(), got->end(), r->blocked.begin() + static_cast<ptrdiff_t>(begin));
                                 } else {
                                   auto got = decode_hits(reply->body, end - begin, triangles);
                                   if (!got) return state->complete_one(part_name + ": " + got.error().message);
                                   std::copy(got->begin(), got->end(), r->hits.begin() + static_cast<ptrdiff_t>(begin));
                                 }
                                 state->complete_one();
                               });
      }
    }
    if (local_part < parts && round[local_part]) {
      PartRound& r = *round[local_part];
      counts.local_visits += r.rays.size();
      const std::vector<Ray> local = rays_of(r, 0, r.rays.size());
      if constexpr (Any) local_tracer->occluded(local, r.blocked);
      else local_tracer->intersect_unsettled(local, r.hits);
    }
    co_await Gather(state);
    for (size_t p = 0; p < parts; ++p) {
      if (!round[p]) continue;
      const PartRound& r = *round[p];
      for (size_t k = 0; k < r.rays.size(); ++k) {
        if constexpr (Any) {
          blocked[r.rays[k]] |= r.blocked[k];
        } else {
          if (r.hits[k].valid()) {
            hits[r.rays[k]] = r.hits[k];
            if (!hit_part.empty()) hit_part[r.rays[k]] = static_cast<uint32_t>(p);
          }
        }
      }
    }
    if constexpr (Any) routes.advance(std::span<const uint8_t>(blocked));
    else routes.advance(std::span<const Hit>(hits));
  }
}

Task RemoteTracing::intersect(std::span<const Ray> rays, std::span<Hit> hits) {
  return intersect(rays, hits, {});
}

Task RemoteTracing::intersect(std::span<const Ray> rays, std::span<Hit> hits, std::span<uint32_t> hit_part) {
  std::fill(hits.begin(), hits.end(), Hit{});
  std::fill(hit_part.begin(), hit_part.end(), kNoPart);
  counts_.rays += rays.size();
  co_await trace_rounds<false>(rt_, scene_, boxes_, batch_, local_part_, local_tracer_.get(), rays, hits, {}, hit_part,
                               counts_);
  for (size_t i = 0; i < rays.size(); ++i) hits[i] = ties_.settle(rays[i], hits[i]);
}

Task RemoteTracing::occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) {
  std::fill(occluded.begin(), occluded.end(), uint8_t{0});
  counts_.rays += rays.size();
  co_await trace_rounds<true>(rt_, scene_, boxes_, batch_, local_part_, local_tracer_.get(), rays, {}, occluded, {},
                              counts_);
}

Value RemoteTracing::stats(bool whole_scene_bvh) const {
  return Value::Map{{"traced_rays", static_cast<int64_t>(counts_.rays)},
                    {"part_visits", static_cast<int64_t>(counts_.visits)},
                    {"local_part_visits", static_cast<int64_t>(counts_.local_visits)},
                    {"trace_requests", static_cast<int64_t>(counts_.requests)},
                    {"ray_bytes_to_parts", static_cast<int64_t>(counts_.payload_bytes)},
                    {"whole_scene_bvh", whole_scene_bvh}};
}

}  // namespace lf
