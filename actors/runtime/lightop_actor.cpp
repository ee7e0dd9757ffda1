// The LightOp wrapper (the wrapper pattern of Kipfer & Slusallek): turns a plain LightOp class into an actor.
//
// Accepts on the data socket:
//   REQUEST op="shade" { n, p, nrm, wo, m, k }  ->  REPLY { n, L }   (header q = requests waiting here)
//   anything else / malformed                  ->  ERROR { code, message }; the actor carries on
// Control: CONFIG builds the op from its parameters and loads the scene; PHASE setup runs op.setup() and answers
// READY setup when it finishes; PHASE render is answered READY render at once; PHASE finish / BYE stop it.
// Requests that arrive before setup finished wait.
// Requests queue in arrival order and start one per loop turn, so heartbeats and replies keep flowing. A request
// whose op asks its inputs suspends (a coroutine) while the runtime sends those batches asynchronously; other
// requests run meanwhile. The LightOp class sees none of this.
#include "actors/runtime/lightop_actor.hpp"

#include <chrono>
#include <deque>

#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/remote_tracing.hpp"
#include "core/log.hpp"
#include "render/loaded_scene.hpp"
#include "render/lightop_registry.hpp"

namespace lf {
namespace {

// Predecessors reached over the wire: each query becomes one or more batched, asynchronous requests.
class RemoteInputs final : public Inputs {
 public:
  RemoteInputs(Runtime& rt, size_t batch) : rt_(rt), batch_(batch) {}
  size_t count() const override { return rt_.input_count(); }

  Gather gather(std::vector<InputQuery> queries) override {
    auto state = std::make_shared<GatherState>();
    for (const auto& q : queries) {
      if (q.input >= rt_.input_count()) {
        state->error = "input " + std::to_string(q.input) + " does not exist";
        continue;
      }
      q.radiance->assign(q.points->size(), RGB{});
      for (size_t begin = 0; begin < q.points->size(); begin += batch_) {
        const size_t end = std::min(begin + batch_, q.points->size());
        ++state->remaining;
        auto* out = q.radiance;
        const std::string input_name = rt_.input_name(q.input);
        rt_.input(q.input).request(
            wire::Op::shade, encode_shade_request(*q.points, begin, end),
            [state, out, begin, end, input_name](Result<wire::Message> r) {
              if (!r) return state->complete_one(r.error().message);
              auto radiance = decode_radiance(r->body, end - begin);
              if (!radiance) return state->complete_one(input_name + ": " + radiance.error().message);
              std::copy(radiance->begin(), radiance->end(), out->begin() + static_cast<ptrdiff_t>(begin));
              state->complete_one();
            });
      }
    }
    return Gather(state);
  }

 private:
  Runtime& rt_;
  size_t batch_;
};

// All-gather among the replicas of a pool, through the director (which knows the pool).
class DirectorExchange final : public Exchange {
 public:
  // `alone`: not one of several replicas, so the gather is this op's own part (a pool of one, or no pool): a
  // photon map's tens of MB need not go to the director and back.
  DirectorExchange(Runtime& rt, bool alone) : rt_(rt), alone_(alone) {}
  Gather all_gather(std::string part, std::vector<std::string>* parts) override {
    if (alone_) return SoloExchange().all_gather(std::move(part), parts);
    auto state = std::make_shared<GatherState>();
    state->remaining = 1;
    // This replica keeps its own part and the director answers nil in its place: its bytes do not come back.
    auto own = std::make_shared<std::string>(part);
    rt_.ask_director(wire::Op::all_gather, map_of("part", Bytes{std::move(part)}, "keep", true),
                     [state, parts, own](Result<wire::Message> r) {
      if (!r) return state->complete_one("all_gather: " + r.error().message);
      Value* all = r->body.find("parts");
      if (!all || !all->is_array()) return state->complete_one("all_gather: the director sent no parts");
      parts->clear();
      size_t own_places = 0;
      for (auto& p : all->as_array()) {
        if (p.is_nil() && own_places++ == 0) {
          parts->push_back(std::move(*own));
          continue;
        }
        if (!p.is_bytes()) return state->complete_one("all_gather: a part is not bytes");
        parts->push_back(std::move(p.as_bytes().data));  // shares can be tens of MB: moved, not copied
      }
      if (own_places != 1) return state->complete_one("all_gather: the director's answer has no place for this part");
      state->complete_one();
    });
    return Gather(state);
  }

  Gather fetch(const std::string& key, std::string* blob) override {
    auto state = std::make_shared<GatherState>();
    state->remaining = 1;
    rt_.ask_director(wire::Op::fetch, Value::Map{{"key", key}}, [state, blob, key](Result<wire::Message> r) {
      if (!r) return state->complete_one("fetch '" + key + "': " + r.error().message);
      Value* b = r->body.find("blob");
      if (!b || !b->is_bytes()) return state->complete_one("fetch '" + key + "': the director sent no blob");
      *blob = std::move(b->as_bytes().data);
      state->complete_one();
    });
    return Gather(state);
  }

 private:
  Runtime& rt_;
  bool alone_;
};

class LightOpActor final : public Actor {
 public:
  explicit LightOpActor(const LightOpKind& kind) : kind_(kind) {}

  Status configure(const ActorConfig& config, Runtime& rt) override {
    try {
      op_ = create_lightop(kind_, ParamTable(config.params, "lightop '" + rt.name() + "'"));
    } catch (const ParamError& e) {
      return make_error(e.what());
    }
    // In a partitioned farm an op that traces only through the parts builds no BVH of the whole scene (unless a host
    // agent shares one anyway).
    const bool parts_trace = !config.geometry.empty() && kind_.traces_through_context;
    auto loaded = load_scene_for_actor(config.scene, /*with_tracer=*/!parts_trace);
    if (!loaded) return loaded.error();
    scene_ = std::move(loaded->scene);
    tracer_ = std::move(loaded->tracer);
    camera_ = std::make_unique<Camera>(config.camera, config.image.width, config.image.height);
    width_ = config.image.width;
    height_ = config.image.height;
    sampler_ = config.image.sampler == "sobol" ? SamplerKind::sobol : SamplerKind::independent;
    inputs_ = std::make_unique<RemoteInputs>(rt, 4096);
    if (config.pool) {
      replica_index_ = static_cast<int>(config.pool->index);
      replica_count_ = static_cast<int>(config.pool->count);
    }
    exchange_ = std::make_unique<DirectorExchange>(rt, replica_count_ <= 1);
    if (!config.geometry.empty()) {
      // A partitioned scene: rays go to the parts' geometry actors (ops that trace through ctx.tracing do).
      std::vector<Bounds> boxes;
      for (size_t p = 0; p < config.geometry.size(); ++p) {
        const float* b = config.part_boxes.data() + 6 * p;
        boxes.push_back(Bounds{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}});
      }
      tracing_ = std::make_unique<RemoteTracing>(rt, *scene_, std::move(boxes), 4096);
    }
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup) {
      SceneContext ctx{scene_.get(), tracer_.get(), replica_index_, replica_count_, exchange_.get()};
      ctx.camera = camera_.get();
      ctx.width = width_;
      ctx.height = height_;
      ctx.sampler = sampler_;
      ctx.tracing = tracing_.get();
      ctx.progress = [&rt](const char* what, uint64_t done, uint64_t total) { rt.report_progress(what, done, total); };
      setup_ = op_->setup(std::move(ctx), *inputs_);
      setup_running_ = true;
      on_progress(rt);
    } else if (phase == wire::Phase::render) {
      rt.phase_done(wire::Phase::render);  // a LightOp renders by answering requests
    }
  }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (op != wire::Op::shade) return rt.reply_unknown_op(peer, m, "this actor serves 'shade'");
    if (!op_) {
      rt.reply_error(peer, m.header.id, ErrorCode::not_ready, "'" + rt.name() + "' is not configured yet");
      return;
    }
    // Requests that arrive before this op's setup finished (another op's setup may ask it, e.g. an irradiance
    // pre-pass) wait in the queue until it has.
    auto points = decode_shade_request(m.body, scene_->materials().size(), scene_->triangle_count());
    if (!points) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, points.error().message);
      return;
    }
    auto job = std::make_unique<Job>();
    job->peer = peer;
    job->id = m.header.id;
    job->points = std::move(*points);
    waiting_.push_back(std::move(job));
  }

  void on_progress(Runtime& rt) override {
    if (setup_running_ && setup_.done()) {
      setup_running_ = false;
      try {
        setup_.rethrow_if_failed();
      } catch (const std::exception& e) {
        rt.fail("setup failed: " + std::string(e.what()));
        return;
      }
      set_up_ = true;
      rt.phase_done(wire::Phase::setup);
    }
    if (!set_up_) return;
    // Start one waiting request per turn; the loop polls sockets between requests.
    if (!waiting_.empty() && running_.size() < kMaxRunning) {
      auto job = std::move(waiting_.front());
      waiting_.pop_front();
      job->radiance.assign(job->points.size(), RGB{});
      job->task = op_->shade(job->points, job->radiance, *inputs_);
      running_.push_back(std::move(job));
    }
    for (size_t i = 0; i < running_.size();) {
      Job& job = *running_[i];
      if (!job.task.done()) {
        ++i;
        continue;
      }
      try {
        job.task.rethrow_if_failed();
        rt.stats().requests += 1;
        rt.stats().points += job.points.size();
        rt.reply(job.peer, job.id, encode_radiance(job.radiance));
      } catch (const std::exception& e) {
        rt.reply_error(job.peer, job.id, ErrorCode::shade_failed, e.what());
      }
      running_.erase(running_.begin() + static_cast<ptrdiff_t>(i));
    }
  }

  size_t queue_length() const override { return waiting_.size(); }
  bool has_local_work() const override { return set_up_ && !waiting_.empty(); }
  // The op's own figures (cache hits, photons, ...) under STATS "detail".
  Value extra_stats() const override {
    Value stats = op_ ? op_->stats() : Value();
    if (tracing_) {
      if (!stats.is_map()) stats = Value::Map{};
      Value tracing = tracing_->stats();  // held: a range-for over a temporary's map would dangle
      for (auto& [key, value] : tracing.as_map()) stats.as_map()[key] = std::move(value);
      stats.as_map()["whole_scene_bvh"] = tracer_ != nullptr;  // false: this process holds no BVH of the scene
    }
    return stats;
  }

 private:
  struct Job {
    std::string peer;
    uint64_t id = 0;
    ShadingPoints points;
    std::vector<RGB> radiance;
    Task task;
  };
  static constexpr size_t kMaxRunning = 16;

  const LightOpKind& kind_;
  std::unique_ptr<LightOp> op_;
  std::shared_ptr<const Scene> scene_;
  std::shared_ptr<const RayTracer> tracer_;
  SamplerKind sampler_ = SamplerKind::independent;
  std::unique_ptr<Camera> camera_;
  int width_ = 0, height_ = 0;
  std::unique_ptr<RemoteInputs> inputs_;
  std::unique_ptr<Exchange> exchange_;
  std::unique_ptr<RemoteTracing> tracing_;  // a partitioned scene's geometry actors, or none
  int replica_index_ = 0, replica_count_ = 1;
  Task setup_;
  bool setup_running_ = false;
  bool set_up_ = false;  // setup finished: requests may start
  std::deque<std::unique_ptr<Job>> waiting_;
  std::vector<std::unique_ptr<Job>> running_;
};

}  // namespace

std::unique_ptr<Actor> make_lightop_actor(const std::string& kind) {
  const LightOpKind* k = find_lightop_kind(kind);
  if (!k) return nullptr;
  return std::make_unique<LightOpActor>(*k);
}

std::unique_ptr<Actor> make_lightop_actor(const LightOpKind& kind) { return std::make_unique<LightOpActor>(kind); }

}  // namespace lf
