// renderer: traces camera rays for tiles the render master hands out and asks the lighting network to shade them.
//
// Sends to the director (the render master):
//   REQUEST op="tile"       {}                        -> REPLY { tile: {id, x0, y0, x1, y1} } or {} when none remain
//   REQUEST op="tile_done"  { id, pixels: f32[3wh] }  -> REPLY {}
// Sends to its one input (the MasterLightOp): REQUEST op="shade" batches, several in flight (the input's window).
// Ready for "render" once configured (scene loaded, BVH built); in a partitioned farm (partition { parts = N }) its
// camera rays go to the geometry actors instead, through RemoteTracing. Answers READY render when the master has no tiles
// left and every finished tile was acknowledged. Keeps up to `tiles_in_flight` tiles going, so it traces the next
// tile while the lighting network shades the last.
#include "actors/codecs/control_codec.hpp"
#include "actors/kinds/renderer_actor.hpp"

#include <deque>

#include "actors/codecs/shade_codec.hpp"
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
    scene_ = std::move(loaded->scene);
    tracer_ = std::move(loaded->tracer);
    image_ = config.image;
    sampler_ = sampler_of(image_);
    camera_ = std::make_unique<Camera>(config.camera, image_.width, image_.height);
    tracing_ = RemoteTracing::for_config(config, rt, *scene_);
    colocate_ = tracing_ && rt.input_holds_parts(0);
    if (image_.adaptive_spp > 0 && tracing_)
      return make_error("image: adaptive_spp is not available with partition (a tile's second round traces here)");
    return Ok{};
  }

  Value extra_stats() const override {
    if (tracing_) return tracing_->stats(tracer_ != nullptr);
    if (image_.adaptive_spp == 0) return Value();
    return Value::Map{{"adaptive_pixels", static_cast<int64_t>(adaptive_pixels_)},
                      {"adaptive_samples", static_cast<int64_t>(adaptive_samples_)}};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup) {
      rt.phase_done(wire::Phase::setup);
    } else if (phase == wire::Phase::render) {
      rendering_ = true;
      ask_for_tiles(rt);
    }
  }

  void on_request(const std::string& peer, wire::Op, wire::Message& m, Runtime& rt) override {
    rt.reply_unknown_op(peer, m, "a renderer serves no requests");
  }

 private:
  struct TileJob {
    uint64_t id = 0;
    TileWork work;
    std::vector<RGB> radiance;        // one value a point, from replies that came that way
    std::vector<RGB> pixel_radiance;  // a pixel's points' radiance summed (fold_by_pixel), from folded replies
    std::vector<uint8_t> folded;      // which pixels came folded
    std::vector<uint32_t> pixel;      // when folding: each point's pixel in the tile (in sending order)
    // Points sent grouped by part (partition { colocate = true }): the part each camera sample's hit was found in,
    // and the index in `work` of each point as sent (empty: sent in point order).
    std::vector<uint32_t> sample_part;
    std::vector<uint32_t> order;
    size_t batches_left = 0;
    // Adaptive sampling: the first round's points and radiance while the second round's are out, and each
    // pixel's count of shaded samples (empty: no second round).
    TileWork first;
    std::vector<RGB> first_radiance;
    std::vector<uint32_t> shaded_of_pixel;
  };

  void ask_for_tiles(Runtime& rt) {
    while (rendering_ && !no_more_tiles_ &&
           jobs_.size() + tile_requests_out_ < static_cast<size_t>(params_.tiles_in_flight)) {
      ++tile_requests_out_;
      rt.ask_director(wire::Op::tile, Value::Map{}, [this, &rt](Result<wire::Message> r) {
        --tile_requests_out_;
        if (!r) return rt.fail("the render master refused a tile request: " + r.error().message);
        auto tile = control::decode_tile_reply(r->body, image_.width, image_.height);
        if (!tile) return rt.fail(tile.error().message);
        if (!*tile) {
          no_more_tiles_ = true;
          check_finished(rt);
          return;
        }
        start_tile(**tile, rt);
        ask_for_tiles(rt);
      });
    }
  }

  void start_tile(const control::Tile& tile, Runtime& rt) {
    const TileRect rect = tile.rect;
    auto job = std::make_shared<TileJob>();
    job->id = tile.id;
    jobs_.push_back(job);
    if (tracing_) {
      std::erase_if(tracing_tasks_, [](const Task& t) { return t.done(); });
      tracing_tasks_.push_back(trace_through_parts(job, rect, rt));
      return;
    }
    trace_tile(*scene_, *tracer_, *camera_, image_, rect, job->work);
    shade_tile(job, rt);
  }

  // A partitioned scene's camera rays, answered by its geometry actors; the tile is shaded once they are.
  Task trace_through_parts(std::shared_ptr<TileJob> job, TileRect rect, Runtime& rt) {
    std::vector<Ray> rays;
    std::vector<uint64_t> keys;
    tile_camera_rays(*camera_, image_, rect, rays, keys);
    std::vector<Hit> hits(rays.size());
    if (colocate_) job->sample_part.resize(rays.size());
    try {
      co_await tracing_->intersect(rays, hits, job->sample_part);
    } catch (const std::exception& e) {
      rt.fail(std::string("tracing camera rays through the scene's parts failed: ") + e.what());
      co_return;
    }
    tile_points(*scene_, *camera_, image_, rect, rays, hits, keys, job->work);
    shade_tile(job, rt);
  }

  void shade_tile(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    rt.stats().points += job->work.points.size();
    const size_t n = job->work.points.size();
    // A pool whose replicas hold scene parts themselves (partition { colocate = true }) gets each part's points
    // apart, to a replica holding it: the tile's points are sent grouped by part (in point order within a part),
    // and their radiance put back in point order, so the pixels sum it exactly as they would unsent.
    std::vector<size_t> part_end{n};  // where each group of points ends, in sending order
    std::vector<int64_t> group_part{-1};
    TileWork grouped;                  // the tile as sent, when grouped
    std::vector<uint8_t> split_pixel;  // then: per pixel, whether its points lie in more than one part
    if (colocate_ && n > 0) group_by_part(*job, grouped, split_pixel, part_end, group_part);
    const TileWork& work = job->order.empty() ? job->work : grouped;
    // A built-in LightOp rebuilds positions, normals, materials and keys from the scene and the tile, and can sum a
    // pixel's radiance itself: a reply then holds a value a pixel, not a point. Batches then end between pixels, and
    // one with a pixel that sees an emitter is not folded: that pixel's samples are summed with their emission. Nor
    // is one with a pixel whose points lie in two parts, as it is answered in two replies.
    // Adaptive sampling reads each point's radiance: nothing is folded.
    const bool lean = rt.input_is_lean(0), fold = lean && params_.batch > 1 && image_.adaptive_spp == 0;
    const size_t pixels = static_cast<size_t>(work.rect.pixel_count());
    job->radiance.assign(n, RGB{});
    job->pixel_radiance.assign(fold ? pixels : 0, RGB{});
    job->folded.assign(fold ? pixels : 0, 0);
    std::vector<uint8_t> unfoldable(fold ? pixels : 0);
    for (size_t p = 0; p < unfoldable.size(); ++p)
      unfoldable[p] = pixel_sees_emitter(work, p) || (!split_pixel.empty() && split_pixel[p]);
    if (n == 0) return finish_tile(job, rt);
    if (fold) {
      const uint32_t spp = static_cast<uint32_t>(work.spp);
      job->pixel.resize(n);
      for (size_t j = 0; j < n; ++j) job->pixel[j] = work.sample_of_point[j] / spp;
    }
    const std::vector<uint32_t>& pixel = job->pixel;
    for (size_t g = 0, begin = 0; g < part_end.size(); ++g) {
      for (size_t end = begin; begin < part_end[g]; begin = end) {
        end = std::min(begin + static_cast<size_t>(params_.batch), part_end[g]);
        while (fold && end < part_end[g] && pixel[end] == pixel[end - 1]) ++end;
        // The batch's pixels (runs of points), and whether any of them cannot be folded.
        size_t runs = 0;
        bool foldable = fold;
        for (size_t j = begin; fold && j < end; ++j)
          if (j == begin || pixel[j] != pixel[j - 1]) {
            ++runs;
            foldable = foldable && !unfoldable[pixel[j]];
          }
        ++job->batches_left;
        ++rt.stats().requests;
        Value body = lean ? encode_camera_request(work, begin, end, *scene_, sampler_, image_.width, foldable)
                          : encode_shade_request(work.points, begin, end);
        const bool folded = body.find("fold") != nullptr;
        const size_t values = folded ? runs : end - begin;
        rt.ask_input(
            0, wire::Op::shade, std::move(body),
            [this, job, begin, end, folded, values, &rt](Result<wire::Message> r) {
              if (!r) return rt.fail("lighting failed: " + r.error().message);
              auto radiance = decode_radiance(r->body, values);
              if (!radiance) return rt.fail("lighting '" + rt.input_name(0) + "': " + radiance.error().message);
              take_radiance(*job, begin, end, folded, *radiance);
              if (--job->batches_left == 0) finish_tile(job, rt);
            },
            group_part[g]);
      }
    }
  }

  // The tile's points regrouped by the part their camera ray's hit was found in (job.sample_part), into `grouped`,
  // in point order within a part; job.order says where each came from.
  void group_by_part(TileJob& job, TileWork& grouped, std::vector<uint8_t>& split_pixel, std::vector<size_t>& part_end,
                     std::vector<int64_t>& group_part) const {
    const TileWork& work = job.work;
    const size_t n = work.points.size(), parts = tracing_->parts();
    std::vector<uint32_t> part(n);
    std::vector<size_t> count(parts + 1, 0);
    for (size_t i = 0; i < n; ++i) {
      part[i] = std::min<uint32_t>(job.sample_part[work.sample_of_point[i]], static_cast<uint32_t>(parts));
      ++count[part[i]];
    }
    std::vector<size_t> next(parts + 1, 0);
    part_end.clear();
    group_part.clear();
    for (size_t k = 0, at = 0; k <= parts; ++k) {
      next[k] = at;
      at += count[k];
      if (count[k] == 0) continue;
      part_end.push_back(at);
      group_part.push_back(k < parts ? static_cast<int64_t>(k) : -1);
    }
    job.order.resize(n);
    for (size_t i = 0; i < n; ++i) job.order[next[part[i]]++] = static_cast<uint32_t>(i);
    reorder_points(work, job.order, grouped);
    const uint32_t spp = static_cast<uint32_t>(work.spp);
    // A pixel's points are consecutive in point order; in another part's group they may come back later.
    std::vector<int64_t> seen_in(static_cast<size_t>(work.rect.pixel_count()), -1);
    split_pixel.assign(seen_in.size(), 0);
    for (size_t i = 0; i < n; ++i) {
      const uint32_t px = work.sample_of_point[i] / spp;
      if (seen_in[px] >= 0 && seen_in[px] != part[i]) split_pixel[px] = 1;
      seen_in[px] = part[i];
    }
  }

  static void take_radiance(TileJob& job, size_t begin, size_t end, bool folded, const std::vector<RGB>& radiance) {
    if (!folded) {
      if (job.order.empty()) std::copy(radiance.begin(), radiance.end(), job.radiance.begin() + static_cast<ptrdiff_t>(begin));
      else
        for (size_t j = begin; j < end; ++j) job.radiance[job.order[j]] = radiance[j - begin];
      return;
    }
    const auto& pixel = job.pixel;
    for (size_t j = begin, run = 0; j < end; ++j)
      if (j == begin || pixel[j] != pixel[j - 1]) {
        job.pixel_radiance[pixel[j]] = radiance[run++];
        job.folded[pixel[j]] = 1;
      }
  }

  void finish_tile(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    if (image_.adaptive_spp > 0 && job->shaded_of_pixel.empty() && shade_more(job, rt)) return;
    std::vector<RGB> pixels;
    if (job->shaded_of_pixel.empty()) resolve_tile(job->work, job->radiance, job->pixel_radiance, job->folded, pixels);
    else resolve_adaptive_tile(job->first, job->first_radiance, job->work, job->radiance, job->shaded_of_pixel, pixels);
    ++rt.stats().tiles;
    ++done_acks_out_;
    std::erase(jobs_, job);
    rt.ask_director(wire::Op::tile_done,
                    control::encode_tile_done(job->id, std::span<const float>(
                                                           reinterpret_cast<const float*>(pixels.data()), 3 * pixels.size())),
                    [this, &rt](Result<wire::Message> r) {
                      --done_acks_out_;
                      if (!r) log_warn("the render master did not take a tile: " + r.error().message);
                      check_finished(rt);
                    });
    ask_for_tiles(rt);
  }

  // Adaptive sampling's second round for a tile whose first is in: true when points went out for it.
  bool shade_more(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    auto counts = adaptive_shaded_counts(image_, job->work, job->radiance);
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
    job->first_radiance = std::move(job->radiance);
    job->work = TileWork{};
    trace_more_samples(*scene_, *tracer_, *camera_, image_, job->first.rect, job->shaded_of_pixel, job->work);
    shade_tile(job, rt);
    return true;
  }

  void check_finished(Runtime& rt) {
    if (rendering_ && no_more_tiles_ && jobs_.empty() && done_acks_out_ == 0 && tile_requests_out_ == 0) {
      rendering_ = false;
      rt.phase_done(wire::Phase::render);
    }
  }

  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const RayTracer> tracer_;       // none in a partitioned farm
  std::unique_ptr<RemoteTracing> tracing_;        // a partitioned scene's geometry actors, or none
  bool colocate_ = false;                         // the lighting pool's replicas hold parts: send points by part
  std::vector<Task> tracing_tasks_;               // tiles whose camera rays are out at the parts (finished ones kept until the next tile)
  std::unique_ptr<Camera> camera_;
  ImageSpec image_;
  SamplerKind sampler_ = SamplerKind::independent;
  RendererParams params_;
  bool rendering_ = false;
  bool no_more_tiles_ = false;
  size_t tile_requests_out_ = 0;
  size_t done_acks_out_ = 0;
  std::vector<std::shared_ptr<TileJob>> jobs_;
  uint64_t adaptive_pixels_ = 0;   // pixels that got a second round
  uint64_t adaptive_samples_ = 0;  // the shaded samples those rounds added
};

}  // namespace

std::unique_ptr<Actor> make_renderer_actor() { return std::make_unique<RendererActor>(); }

}  // namespace lf
