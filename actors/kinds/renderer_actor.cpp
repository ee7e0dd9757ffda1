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
#include "actors/kinds/renderer_actor.hpp"

#include <deque>

#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/remote_tracing.hpp"
#include "farm/kind_params.hpp"
#include "core/log.hpp"
#include "render/camera.hpp"
#include "render/loaded_scene.hpp"
#include "render/tile_kernel.hpp"

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
    return Ok{};
  }

  Value extra_stats() const override {
    return tracing_ ? tracing_->stats(tracer_ != nullptr) : Value();
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
    std::vector<uint32_t> pixel;      // when folding: each point's pixel in the tile
    size_t batches_left = 0;
  };

  void ask_for_tiles(Runtime& rt) {
    while (rendering_ && !no_more_tiles_ &&
           jobs_.size() + tile_requests_out_ < static_cast<size_t>(params_.tiles_in_flight)) {
      ++tile_requests_out_;
      rt.ask_director(wire::Op::tile, Value::Map{}, [this, &rt](Result<wire::Message> r) {
        --tile_requests_out_;
        if (!r) return rt.fail("the render master refused a tile request: " + r.error().message);
        const Value* tile = r->body.find("tile");
        if (!tile) {
          no_more_tiles_ = true;
          check_finished(rt);
          return;
        }
        start_tile(*tile, rt);
        ask_for_tiles(rt);
      });
    }
  }

  void start_tile(const Value& tile, Runtime& rt) {
    auto get = [&](const char* k) {
      const Value* v = tile.find(k);
      return v && v->is_int() && v->as_int() >= 0 && v->as_int() <= INT32_MAX ? static_cast<int>(v->as_int()) : -1;
    };
    TileRect rect{get("x0"), get("y0"), get("x1"), get("y1")};
    if (get("id") < 0 || rect.x0 < 0 || rect.y0 < 0 || rect.x1 > image_.width || rect.y1 > image_.height || rect.width() <= 0 ||
        rect.height() <= 0)
      return rt.fail("the render master sent a tile outside the image");
    auto job = std::make_shared<TileJob>();
    job->id = static_cast<uint64_t>(get("id"));
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
    try {
      co_await tracing_->intersect(rays, hits);
    } catch (const std::exception& e) {
      rt.fail(std::string("tracing camera rays through the scene's parts failed: ") + e.what());
      co_return;
    }
    tile_points(*scene_, *camera_, image_, rect, rays, hits, keys, job->work);
    shade_tile(job, rt);
  }

  void shade_tile(const std::shared_ptr<TileJob>& job, Runtime& rt) {
    rt.stats().points += job->work.points.size();
    const TileWork& work = job->work;
    const size_t n = work.points.size();
    // A built-in LightOp rebuilds positions, normals, materials and keys from the scene and the tile, and can sum a
    // pixel's radiance itself: a reply then holds a value a pixel, not a point. Batches then end between pixels, and
    // one with a pixel that sees an emitter is not folded: that pixel's samples are summed with their emission.
    const bool lean = rt.input_is_lean(0), fold = lean && params_.batch > 1;
    const size_t pixels = static_cast<size_t>(work.rect.pixel_count());
    job->radiance.assign(n, RGB{});
    job->pixel_radiance.assign(fold ? pixels : 0, RGB{});
    job->folded.assign(fold ? pixels : 0, 0);
    std::vector<uint8_t> sees_emitter(fold ? pixels : 0);
    for (size_t p = 0; p < sees_emitter.size(); ++p) sees_emitter[p] = pixel_sees_emitter(work, p);
    if (n == 0) return finish_tile(job, rt);
    if (fold) {
      const uint32_t spp = static_cast<uint32_t>(work.spp);
      job->pixel.resize(n);
      for (size_t j = 0; j < n; ++j) job->pixel[j] = work.sample_of_point[j] / spp;
    }
    const std::vector<uint32_t>& pixel = job->pixel;
    for (size_t begin = 0, end = 0; begin < n; begin = end) {
      end = std::min(begin + static_cast<size_t>(params_.batch), n);
      while (fold && end < n && pixel[end] == pixel[end - 1]) ++end;
      // The batch's pixels (runs of points), and whether any of them sees an emitter.
      size_t runs = 0;
      bool foldable = fold;
      for (size_t j = begin; fold && j < end; ++j)
        if (j == begin || pixel[j] != pixel[j - 1]) {
          ++runs;
          foldable = foldable && !sees_emitter[pixel[j]];
        }
      ++job->batches_left;
      ++rt.stats().requests;
      Value body = lean ? encode_camera_request(work, begin, end, *scene_, sampler_, image_.width, foldable)
                        : encode_shade_request(work.points, begin, end);
      const bool folded = body.find("fold") != nullptr;
      const size_t values = folded ? runs : end - begin;
      rt.ask_input(0, wire::Op::shade, std::move(body),
                   [this, job, begin, end, folded, values, &rt](Result<wire::Message> r) {
                     if (!r) return rt.fail("lighting failed: " + r.error().message);
                     auto radiance = decode_radiance(r->body, values);
                     if (!radiance) return rt.fail("lighting '" + rt.input_name(0) + "': " + radiance.error().message);
                     take_radiance(*job, begin, end, folded, *radiance);
                     if (--job->batches_left == 0) finish_tile(job, rt);
                   });
    }
  }

  static void take_radiance(TileJob& job, size_t begin, size_t end, bool folded, const std::vector<RGB>& radiance) {
    if (!folded) {
      std::copy(radiance.begin(), radiance.end(), job.radiance.begin() + static_cast<ptrdiff_t>(begin));
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
    std::vector<RGB> pixels;
    resolve_tile(job->work, job->radiance, job->pixel_radiance, job->folded, pixels);
    ++rt.stats().tiles;
    ++done_acks_out_;
    std::erase(jobs_, job);
    rt.ask_director(wire::Op::tile_done,
                    map_of("id", job->id,
                           "pixels", floats_to_bytes(std::span<const float>(
                                         reinterpret_cast<const float*>(pixels.data()), 3 * pixels.size()))),
                    [this, &rt](Result<wire::Message> r) {
                      --done_acks_out_;
                      if (!r) log_warn("the render master did not take a tile: " + r.error().message);
                      check_finished(rt);
                    });
    ask_for_tiles(rt);
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
};

}  // namespace

std::unique_ptr<Actor> make_renderer_actor() { return std::make_unique<RendererActor>(); }

}  // namespace lf
