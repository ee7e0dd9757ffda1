// renderer: traces camera rays for tiles the render master hands out and asks the lighting network to shade them.
//
// Sends to the director (the render master):
//   REQUEST op="tile"       { count? }                -> REPLY { tile: {...} } ({ tiles: [...] }) or {} when none remain
//   REQUEST op="tile_done"  { id, pixels: f32[3wh], next? } or { tiles: [{id, pixels}, ...], next?, count? }
//                                                      -> REPLY {}, or with next: true a tile request's reply
// Sends to its one input (the MasterLightOp): REQUEST op="shade" batches, several in flight (the input's window).
// PHASE frame (a job's next frame) brings a new camera. In flight (the frame before still rendering) the last
// frame's camera stays for the tiles that name its frame; every shade request names its tile's frame (`view`).
// Ready for "render" once configured (scene loaded, BVH built); in a partitioned farm (partition { parts = N }) its
// camera rays go to the geometry actors instead, through RemoteTracing. Answers READY render when the master has no tiles
// left and every finished tile was acknowledged. Keeps up to `tiles_in_flight` tiles going, so it traces the next
// tile while the lighting network shades the last. With tiles_per_message > 1 a finished tile waits for the next
// to finish (while another is going) and both go in one tile_done that asks for as many: fewer messages at a
// director serving thousands of renderers with fast tiles (docs/SCALE.md).
#include "actors/codecs/control_codec.hpp"
#include "actors/kinds/renderer_actor.hpp"

#include <deque>

#include "actors/codecs/shade_codec.hpp"
#include "actors/kinds/renderer_views.hpp"
#include "actors/kinds/tile_plan.hpp"
#include "actors/runtime/frame_scene.hpp"
#include "actors/runtime/lean_points.hpp"
#include "actors/runtime/remote_tracing.hpp"
#include "farm/kind_params.hpp"
#include "core/log.hpp"
#include "render/tracing/camera.hpp"
#include "render/scene/loaded_scene.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {
namespace {

class RendererActor final : public Actor {
 public:
  Status configure(const ActorConfig& config, Runtime& rt) override {
    try {
      ParamTable p(config.params, "renderer '" + rt.name() + "'");
      params_ = RendererParams::read(p);  // window is applied by the runtime to the input connection
      p.report_unused();
    } catch (const ParamError& e) {
      return make_error(e.what());
    }
    if (rt.input_count() != 1) return make_error("a renderer needs exactly one input (its lighting)");
    // In a partitioned farm camera rays go to the parts' geometry actors, and this process builds no BVH of the
    // whole scene (unless a host agent shares one anyway).
    auto loaded = load_scene_for_actor(config.scene, /*with_tracer=*/config.geometry.empty());
    if (!loaded) return loaded.error();
    frame_scene_ = FrameScene(std::move(loaded->scene));
    if (auto taken = frame_scene_.take(config.frame_materials, "the job's first frame"); !taken) return taken.error();
    tracer_ = std::move(loaded->tracer);
    image_ = config.image;
    sampler_ = sampler_of(image_);
    views_.take(scene(), config.camera, image_, config.frame, false);
    tracing_ = RemoteTracing::for_config(config, rt, frame_scene_.shipped());
    colocate_ = tracing_ && rt.input_holds_parts(0);
    return Ok{};
  }

  Value extra_stats() const override {
    Value::Map stats;
    if (tracing_) stats = tracing_->stats(tracer_ != nullptr).as_map();
    if (image_.adaptive_spp > 0) {
      stats["adaptive_pixels"] = static_cast<int64_t>(adaptive_pixels_);
      stats["adaptive_samples"] = static_cast<int64_t>(adaptive_samples_);
    }
    if (stats.empty()) return Value();
    return stats;
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup) {
      rt.phase_done(wire::Phase::setup);
    } else if (phase == wire::Phase::render) {
      rendering_ = true;
      ask_for_tiles(rt);
    }
  }

  // A job's next frame: its tiles are traced from the new camera. The last frame's are all done and acknowledged
  // (this renderer said READY render), or, in flight, some are still going: they keep the view they began with.
  void on_frame(const FrameView& view, Runtime& rt) override {
    auto changed = frame_scene_.take(view.materials, "frame " + std::to_string(view.frame));
    if (!changed) return rt.fail(changed.error().message);
    if (*changed && view.in_flight) return rt.fail("PHASE frame in flight where the materials change");
    views_.take(scene(), view.camera, image_, view.frame, view.in_flight.has_value());
    no_more_tiles_ = false;
    rt.phase_done(wire::Phase::frame);
  }

  void on_request(const std::string& peer, wire::Op, wire::Message& m, Runtime& rt) override {
    rt.reply_unknown_op(peer, m, "a renderer serves no requests");
  }

 private:
  struct TileJob {
    uint64_t id = 0;
    std::shared_ptr<const RendererView> view;  // the frame's the tile is of
    TileWork work;
    std::vector<uint32_t> sample_part;  // partition { colocate = true }: the part each camera sample's hit is in
    TilePlan plan;                      // how the points went out, and where their replies go
    TileRadiance radiance;
    size_t batches_left = 0;
    // Adaptive sampling: the first round's points and radiance while the second round's are out, and each
    // pixel's count of shaded samples (empty: no second round).
    TileWork first;
    std::vector<RGB> first_radiance;
    std::vector<uint32_t> shaded_of_pixel;
  };

  // Finished tiles sent together, and tiles asked for together (a count); 1: the one-tile forms.
  size_t tiles_per_message() const {
    return static_cast<size_t>(std::min(params_.tiles_per_message, params_.tiles_in_flight));
  }
  // Tiles this renderer could take now: tiles_in_flight less those going, finished and not yet sent, and asked for.
  size_t free_slots() const {
    const size_t used = jobs_.size() + finished_.size() + tiles_asked_;
    return rendering_ && !no_more_tiles_ && used < static_cast<size_t>(params_.tiles_in_flight)
               ? static_cast<size_t>(params_.tiles_in_flight) - used
               : 0;
  }

  void ask_for_tiles(Runtime& rt) {
    while (size_t free = free_slots()) {
      // One request for every free slot, or one a tile in the one-tile form.
      const size_t count = tiles_per_message() > 1 ? std::min<size_t>(free, control::kMaxTilesPerMessage) : 1;
      tiles_asked_ += count;
      rt.ask_director(wire::Op::tile, control::encode_tile_request(tiles_per_message() > 1 ? static_cast<int>(count) : 0),
                      [this, count, &rt](Result<wire::Message> r) {
                        tiles_asked_ -= count;
                        if (!r) return rt.fail("the render master refused a tile request: " + r.error().message);
                        take_tiles(r->body, rt);
                      });
    }
  }

  // A tile request's reply (or a tile_done's that asked for the next tiles): the tiles started, or none left.
  void take_tiles(const Value& reply, Runtime& rt) {
    auto tiles = control::decode_tile_reply(reply, image_.width, image_.height);
    if (!tiles) return rt.fail(tiles.error().message);
    if (tiles->empty()) {
      no_more_tiles_ = true;
      check_finished(rt);
      return;
    }
    for (const control::Tile& tile : *tiles) start_tile(tile, rt);
    ask_for_tiles(rt);
  }

  void start_tile(const control::Tile& tile, Runtime& rt) {
    TileRect rect = tile.rect;
    rect.first_sample = tile.first_sample;  // a time-limited frame's pass
    auto job = std::make_shared<TileJob>();
    job->id = tile.id;
    job->view = views_.for_tile(tile.frame);
    jobs_.push_back(job);
    if (tracing_) {
      std::erase_if(tracing_tasks_, [](const Task& t) { return t.done(); });
      tracing_tasks_.push_back(trace_through_parts(job, rect, rt));
      return;
    }
    trace_tile(scene(), *tracer_, job->view->camera, image_, rect, job->work, job->view->edges);
    shade_tile(job, rt);
  }

  // A partitioned scene's camera rays, answered by its geometry actors; the tile is shaded once they are.
  Task trace_through_parts(std::shared_ptr<TileJob> job, TileRect rect, Runtime& rt) {
    std::vector<Ray> rays;
    std::vector<uint64_t> keys;
    tile_camera_rays(job->view->camera, image_, rect, rays, keys, job->view->edges);
    std::vector<Hit> hits(rays.size());
    if (colocate_) job->sample_part.resize(rays.size());
    try {
      co_await tracing_->intersect(rays, hits, job->sample_part);
    } catch (const std::exception& e) {
      rt.fail(std::string("tracing camera rays through the scene's parts failed: ") + e.what());
      co_return;
    }
    tile_points(scene(), job->view->camera, image_, rect, rays, hits, keys, job->work, job->view->edges);
    shade_tile(job, rt);
  }

  void shade_tile(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    rt.stats().points += job->work.points.size();
    // A built-in LightOp (a lean input) rebuilds positions, normals, materials and keys from the scene and the
    // tile, and can sum a pixel's radiance itself. Adaptive sampling reads each point's radiance: nothing is folded.
    // A pool whose replicas hold scene parts gets each part's points apart (tile_plan.hpp).
    const bool lean = rt.input_is_lean(0);
    job->plan = plan_batches(job->work, job->sample_part,
                             {.batch = static_cast<size_t>(params_.batch),
                              .fold = lean && params_.batch > 1 && image_.adaptive_spp == 0,
                              .parts = colocate_ ? tracing_->parts() : 0});
    job->radiance = TileRadiance(job->plan);
    if (job->plan.batches.empty()) return finish_tile(job, rt);
    TileWork grouped;
    if (!job->plan.order.empty()) reorder_points(job->work, job->plan.order, grouped);
    const TileWork& sent = job->plan.order.empty() ? job->work : grouped;
    job->batches_left = job->plan.batches.size();
    for (size_t i = 0; i < job->plan.batches.size(); ++i) {
      const Batch& b = job->plan.batches[i];
      ++rt.stats().requests;
      // A lean input gets only what it cannot rebuild; a reply comes folded where the keys travel as samples.
      const PointFields fields =
          lean ? fields_to_send(sent, b.begin, b.end, scene(), sampler_, image_.width) : PointFields{};
      const bool folded = b.foldable && !fields.key;
      Value body = encode_tile_request(sent, b.begin, b.end, fields, folded);
      if (job->view->frame) set_shade_view(body, *job->view->frame);
      rt.ask_input(
          0, wire::Op::shade, std::move(body),
          [this, job, i, folded, &rt](Result<wire::Message> r) {
            if (!r) return rt.fail("lighting failed: " + r.error().message);
            const Batch& b = job->plan.batches[i];
            auto radiance = decode_radiance(r->body, job->plan.reply_size(b, folded));
            if (!radiance) return rt.fail("lighting '" + rt.input_name(0) + "': " + radiance.error().message);
            scatter_reply(job->plan, b, folded, *radiance, job->radiance);
            if (--job->batches_left == 0) finish_tile(job, rt);
          },
          b.part);
    }
  }

  void finish_tile(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    if (image_.adaptive_spp > 0 && job->shaded_of_pixel.empty() && shade_more(job, rt)) return;
    std::vector<RGB> pixels;
    const TileRadiance& r = job->radiance;
    if (job->shaded_of_pixel.empty()) resolve_tile(job->work, r.point, r.pixel, r.folded, pixels);
    else resolve_adaptive_tile(job->first, job->first_radiance, job->work, r.point, job->shaded_of_pixel, pixels);
    ++rt.stats().tiles;
    std::erase(jobs_, job);
    finished_.push_back(control::FinishedTile{
        job->id, std::vector<float>(reinterpret_cast<const float*>(pixels.data()),
                                    reinterpret_cast<const float*>(pixels.data()) + 3 * pixels.size())});
    // A finished tile waits for the next while another is going; the last goes as soon as nothing else is.
    if (finished_.size() < tiles_per_message() && !jobs_.empty()) return;
    send_finished(rt);
  }

  // The finished tiles to the director, asking for as many next as there are free slots then.
  void send_finished(Runtime& rt) {
    std::vector<control::FinishedTile> sending = std::move(finished_);
    finished_.clear();
    const size_t next = std::min<size_t>(free_slots(), control::kMaxTilesPerMessage);
    const bool one_tile_form = tiles_per_message() == 1;
    const size_t asked = one_tile_form ? std::min<size_t>(next, 1) : next;
    ++done_acks_out_;
    tiles_asked_ += asked;
    rt.ask_director(wire::Op::tile_done,
                    one_tile_form ? control::encode_tile_done(sending[0].id, sending[0].rgb, asked > 0)
                                  : control::encode_tile_done(sending, static_cast<int>(asked)),
                    [this, asked, &rt](Result<wire::Message> r) {
                      --done_acks_out_;
                      tiles_asked_ -= asked;
                      if (!r) {
                        log_warn("the render master did not take a tile: " + r.error().message);
                        ask_for_tiles(rt);  // the next tiles, asked for alone
                        return check_finished(rt);
                      }
                      if (asked > 0) return take_tiles(r->body, rt);
                      check_finished(rt);
                    });
    ask_for_tiles(rt);
  }

  // Adaptive sampling's second round for a tile whose first is in: true when points went out for it.
  bool shade_more(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    auto counts = adaptive_shaded_counts(image_, job->work, job->radiance.point);
    const int shaded = image_.shaded_per_pixel();
    size_t more = 0;
    for (uint32_t c : counts) {
      more += c - static_cast<size_t>(shaded);
      adaptive_pixels_ += c > static_cast<uint32_t>(shaded);
    }
    if (more == 0) return false;
    adaptive_samples_ += more;
    job->shaded_of_pixel = std::move(counts);
    job->first = std::move(job->work);
    job->first_radiance = std::move(job->radiance.point);
    job->work = TileWork{};
    if (tracing_) {
      std::erase_if(tracing_tasks_, [](const Task& t) { return t.done(); });
      tracing_tasks_.push_back(trace_more_through_parts(job, rt));
      return true;
    }
    trace_more_samples(scene(), *tracer_, job->view->camera, image_, job->first.rect, job->shaded_of_pixel, job->work);
    shade_tile(job, rt);
    return true;
  }

  // A partitioned scene's second round: its rays answered by the geometry actors, as the first round's.
  Task trace_more_through_parts(std::shared_ptr<TileJob> job, Runtime& rt) {
    const TileRect& rect = job->first.rect;
    const MoreSamples more = more_sample_rays(job->view->camera, image_, rect, job->shaded_of_pixel);
    std::vector<Hit> hits(more.rays.size());
    std::vector<uint32_t> parts(colocate_ ? more.rays.size() : 0);
    try {
      co_await tracing_->intersect(more.rays, hits, parts);
    } catch (const std::exception& e) {
      rt.fail(std::string("tracing camera rays through the scene's parts failed: ") + e.what());
      co_return;
    }
    more_sample_points(scene(), job->view->camera, image_, rect, more, hits, job->work);
    if (colocate_) {
      // Indexed as the second round's tile counts samples: max(spp, adaptive_spp) a pixel.
      job->sample_part.assign(static_cast<size_t>(rect.pixel_count()) * static_cast<size_t>(job->work.spp),
                              RemoteTracing::kNoPart);
      for (size_t j = 0; j < parts.size(); ++j) job->sample_part[more.sample[j]] = parts[j];
    }
    shade_tile(job, rt);
  }

  void check_finished(Runtime& rt) {
    if (rendering_ && no_more_tiles_ && jobs_.empty() && finished_.empty() && done_acks_out_ == 0 &&
        tiles_asked_ == 0) {
      rendering_ = false;
      rt.phase_done(wire::Phase::render);
    }
  }

  FrameScene frame_scene_;  // the shipped scene and the frame's, if it changes materials
  // The frame's: what the camera sees emit, and the points' materials.
  const Scene& scene() const { return *frame_scene_.scene(); }
  std::shared_ptr<const RayTracer> tracer_;       // none in a partitioned farm
  std::unique_ptr<RemoteTracing> tracing_;        // a partitioned scene's geometry actors, or none
  bool colocate_ = false;                         // the lighting pool's replicas hold parts: send points by part
  std::vector<Task> tracing_tasks_;               // tiles whose camera rays are out at the parts (finished ones kept until the next tile)
  RendererViews views_;
  ImageSpec image_;
  SamplerKind sampler_ = SamplerKind::independent;
  RendererParams params_;
  bool rendering_ = false;
  bool no_more_tiles_ = false;
  size_t tiles_asked_ = 0;  // tiles asked for and not yet answered (0: no tile request is out)
  size_t done_acks_out_ = 0;
  std::vector<control::FinishedTile> finished_;  // finished tiles waiting to go with the next
  std::vector<std::shared_ptr<TileJob>> jobs_;
  uint64_t adaptive_pixels_ = 0;   // pixels that got a second round
  uint64_t adaptive_samples_ = 0;  // the shaded samples those rounds added
};

}  // namespace

std::unique_ptr<Actor> make_renderer_actor() { return std::make_unique<RendererActor>(); }

}  // namespace lf
