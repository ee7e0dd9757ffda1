// geometry: one part of a partitioned scene (partition { parts = N }; render/tracing/partition.hpp), the data-parallel half
// of Jansen & Reinhard: rays come to the part that holds the triangles.
//
// Accepts on the data socket:
//   REQUEST op="trace" { n, r, any }  ->  REPLY { n, tri, t } (nearest hit in this part; tri 0xffffffff: none)
//                                         or, with any = true, { n, hit } (anything of this part on the ray)
//   (actors/codecs/trace_codec.hpp). Ties and the order of parts are the asker's (actors/runtime/remote_tracing).
// CONFIG: the scene as every actor gets it, and 'part_triangles', this part's triangles; the BVH holds those only.
// Ready for setup and render at once. STATS detail: the part's triangles, rays traced, requests.
#include "actors/kinds/geometry_actor.hpp"

#include "actors/codecs/trace_codec.hpp"
#include "render/scene/loaded_scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {
namespace {

class GeometryActor final : public Actor {
 public:
  Status configure(const ActorConfig& config, Runtime& rt) override {
    if (config.part_triangles.empty()) return make_error("geometry actor '" + rt.name() + "' was given no triangles");
    auto loaded = load_scene_for_actor(config.scene, /*with_tracer=*/false);
    if (!loaded) return loaded.error();
    scene_ = std::move(loaded->scene);
    for (uint32_t t : config.part_triangles)
      if (t >= scene_->triangle_count())
        return make_error("geometry actor '" + rt.name() + "': triangle " + std::to_string(t) +
                          " is not in the scene (" + std::to_string(scene_->triangle_count()) + " triangles)");
    triangles_ = config.part_triangles.size();
    tracer_ = std::make_unique<RayTracer>(*scene_, config.part_triangles);
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override { rt.phase_done(phase); }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (op != wire::Op::trace) return rt.reply_unknown_op(peer, m, "this actor serves 'trace'");
    if (!tracer_) {
      rt.reply_error(peer, m.header.id, ErrorCode::not_ready, "'" + rt.name() + "' is not configured yet");
      return;
    }
    auto request = decode_trace_request(m.body, kMaxRays);
    if (!request) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, request.error().message);
      return;
    }
    ++rt.stats().requests;
    rt.stats().points += request->rays.size();
    rays_ += request->rays.size();
    if (request->any) {
      std::vector<uint8_t> blocked(request->rays.size());
      tracer_->occluded(request->rays, blocked);
      rt.reply(peer, m.header.id, encode_occlusion(blocked));
    } else {
      std::vector<Hit> hits(request->rays.size());
      tracer_->intersect_unsettled(request->rays, hits);
      rt.reply(peer, m.header.id, encode_hits(hits));
    }
  }

  Value extra_stats() const override {
    return Value::Map{{"triangles", static_cast<int64_t>(triangles_)}, {"rays", static_cast<int64_t>(rays_)}};
  }

 private:
  static constexpr size_t kMaxRays = 1 << 20;
  std::shared_ptr<const Scene> scene_;
  std::unique_ptr<RayTracer> tracer_;
  size_t triangles_ = 0;
  uint64_t rays_ = 0;
};

}  // namespace

std::unique_ptr<Actor> make_geometry_actor() { return std::make_unique<GeometryActor>(); }

}  // namespace lf
