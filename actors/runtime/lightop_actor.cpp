// The LightOp wrapper (the wrapper pattern of Kipfer & Slusallek): turns a plain LightOp class into an actor.
//
// Accepts on the data socket:
//   REQUEST op="shade" { n, p, nrm, wo, m, k }  ->  REPLY { n, L }   (header q = requests waiting here)
//   (L one value a point, or one a pixel when the request says fold: actors/codecs/shade_codec.hpp)
//   anything else / malformed                  ->  ERROR { code, message }; the actor carries on
// Control: CONFIG builds the op from its parameters and loads the scene; PHASE setup runs op.setup() and answers
// READY setup when it finishes; PHASE render is answered READY render at once; PHASE frame (a job's next frame)
// takes the new camera at once and, for an op whose setup depends on it (LightOp::setup_sees_camera), holds
// requests from then on; the PHASE setup that follows builds a new op for the view and sets it up, or, for an op
// that carries its setup over the views (LightOp::carries_views), extends it (any other op answers at once); with
// the frame's `keep` it then sends its setup to the director (REQUEST keep_setup), with `restore` it fetches the one
// the director kept instead of extending. Two steps, so that no op's new setup asks one that has not yet taken the
// view. PHASE finish / BYE stop it.
// A PHASE frame in flight (the frame before is still rendering): requests that name the last frame's view (shade
// `view`) go on to the op as it was, under that view's camera; this view's setup goes to a copy
// (LightOp::fork_view) or a new op, and the requests that name it wait for it.
// Requests that arrive before setup finished wait.
// Requests queue in arrival order and start one per loop turn, so heartbeats and replies keep flowing. A request
// whose op asks its inputs suspends (a coroutine) while the runtime sends those batches asynchronously; other
// requests run meanwhile. The LightOp class sees none of this.
#include "actors/runtime/lightop_actor.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <map>
#include <optional>

#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/answered_points.hpp"
#include "actors/runtime/frame_scene.hpp"
#include "actors/runtime/lean_points.hpp"
#include "actors/runtime/remote_tracing.hpp"
#include "actors/runtime/views_in_flight.hpp"
#include "core/log.hpp"
#include "render/scene/loaded_scene.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {
namespace {

// Predecessors reached over the wire: each query becomes one or more batched, asynchronous requests.
class RemoteInputs final : public Inputs {
 public:
  RemoteInputs(Runtime& rt, size_t batch, const FrameScene& frame_scene, ViewsInFlight& views)
      : rt_(rt), batch_(batch), scene_(frame_scene.shipped()), frame_scene_(frame_scene), views_(views) {}
  size_t count() const override { return rt_.input_count(); }

  Gather gather(std::vector<InputQuery> queries) override {
    auto state = std::make_shared<GatherState>();
    state->before_resume = views_.restorer();
    const std::optional<int> view = views_.active_frame();  // the asking request's, for what it asks in turn
    for (const auto& q : queries) {
      if (q.input >= rt_.input_count()) {
        state->error = "input " + std::to_string(q.input) + " does not exist";
        continue;
      }
      q.radiance->assign(q.points->size(), RGB{});
      // Only the points the input's answer can reach; the rest stay zero (answered_points.hpp).
      const ShadingPoints* asked = q.points;
      AnsweredPoints answered;
      std::shared_ptr<const std::vector<uint32_t>> places;  // null: the asked points are the points
      if (const auto& ends = rt_.input_answers(q.input)) {
        answered = answered_points(*q.points, frame_scene_.scene()->materials(), *ends);
        if (!answered.all) {
          asked = &answered.points;
          places = std::make_shared<const std::vector<uint32_t>>(std::move(answered.index));
        }
      }
      for (size_t begin = 0; begin < asked->size(); begin += batch_) {
        const size_t end = std::min(begin + batch_, asked->size());
        ++state->remaining;
        auto* out = q.radiance;
        const std::string input_name = rt_.input_name(q.input);
        Value body = encode_shade_request(
            *asked, begin, end, rt_.input_is_lean(q.input) ? fields_to_send(*asked, begin, end, scene_) : PointFields{});
        if (view) set_shade_view(body, *view);
        rt_.ask_input(
            q.input, wire::Op::shade, std::move(body),
            [state, out, begin, end, input_name, places](Result<wire::Message> r) {
              if (!r) return state->complete_one(r.error().message);
              auto radiance = decode_radiance(r->body, end - begin);
              if (!radiance) return state->complete_one(input_name + ": " + radiance.error().message);
              if (!places)
                std::copy(radiance->begin(), radiance->end(), out->begin() + static_cast<ptrdiff_t>(begin));
              else
                for (size_t k = 0; k < radiance->size(); ++k) (*out)[(*places)[begin + k]] = (*radiance)[k];
              state->complete_one();
            });
      }
    }
    return Gather(state);
  }

 private:
  Runtime& rt_;
  size_t batch_;
  const Scene& scene_;
  const FrameScene& frame_scene_;  // the frame's materials, which say what an input's answer reaches
  ViewsInFlight& views_;
};

// A LightOp alone (no pool, or a pool of one): its all_gather is its own part; fetch asks the director.
class DirectorExchange final : public Exchange {
 public:
  DirectorExchange(Runtime& rt, ViewsInFlight& views) : rt_(rt), views_(views) {}
  Gather all_gather(std::string part, std::vector<std::string>* parts) override {
    return SoloExchange().all_gather(std::move(part), parts);
  }

  Gather fetch(const std::string& key, std::string* blob) override {
    auto state = std::make_shared<GatherState>();
    state->remaining = 1;
    state->before_resume = views_.restorer();
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
  ViewsInFlight& views_;
};

// All-gather straight between the replicas of a pool (CONFIG pool.peers): each round, a replica sends its part to
// every other replica (REQUEST pool_part {round, index, part}, answered at once with an empty REPLY) and is done
// when every other part of that round has arrived and every peer has taken its own. A peer can be at most one round
// ahead (it cannot finish round r without this replica's part), so parts of the next round are kept until asked for.
// A lost peer fails the farm in the director (its share exists nowhere else); fetch still goes to the director.
class PeerExchange final : public Exchange {
 public:
  PeerExchange(Runtime& rt, size_t index, size_t count, ViewsInFlight& views)
      : rt_(rt), index_(index), count_(count), director_(rt, views), views_(views) {}

  Gather all_gather(std::string part, std::vector<std::string>* parts) override {
    const uint64_t round = next_round_++;
    Round& r = round_(round);
    r.state = std::make_shared<GatherState>();
    r.state->remaining = 1;
    r.state->before_resume = views_.restorer();
    r.out = parts;
    r.acks_left = count_ - 1;
    for (size_t k = 0; k + 1 < count_; ++k)
      rt_.pool_peer(k).request(
          wire::Op::pool_part,
          map_of("round", static_cast<int64_t>(round), "index", static_cast<int64_t>(index_), "part", Bytes{part}),
          [this, round](Result<wire::Message> reply) {
            auto it = rounds_.find(round);
            if (it == rounds_.end()) return;
            if (!reply) return fail(it->second, "all_gather: " + reply.error().message);
            --it->second.acks_left;
            finish_if_complete(round);
          });
    r.parts[index_] = std::move(part);
    return Gather(r.state);  // the acks of the sends above are yet to come, so the round cannot be over already
  }

  Gather fetch(const std::string& key, std::string* blob) override { return director_.fetch(key, blob); }

  // REQUEST pool_part from `sender`: its part of a round. Empty REPLY once kept; ERROR for what no peer would send.
  void on_part(const std::string& sender, wire::Message& m) {
    const Value* round = m.body.find("round");
    const Value* index = m.body.find("index");
    Value* part = m.body.find("part");
    const size_t peer_index = expected_index(sender);
    if (!round || !round->is_int() || !index || !index->is_int() || !part || !part->is_bytes())
      return rt_.reply_error(sender, m.header.id, ErrorCode::bad_request, "pool_part needs {round, index, part}");
    if (peer_index == count_ || index->as_int() != static_cast<int64_t>(peer_index))
      return rt_.reply_error(sender, m.header.id, ErrorCode::bad_request,
                             "pool_part from '" + sender + "', which is not replica " + std::to_string(index->as_int()) +
                                 " of this pool");
    // A peer may run one round ahead of this replica's own all_gather calls, never further.
    const int64_t r = round->as_int();
    if (r < static_cast<int64_t>(completed_) || static_cast<uint64_t>(r) > next_round_)
      return rt_.reply_error(sender, m.header.id, ErrorCode::bad_request,
                             "pool_part for round " + std::to_string(r) + " while this replica is at round " +
                                 std::to_string(next_round_));
    Round& slot = round_(static_cast<uint64_t>(r));
    if (slot.have[peer_index])
      return rt_.reply_error(sender, m.header.id, ErrorCode::bad_request,
                             "pool_part: replica " + std::to_string(peer_index) + " sent round " + std::to_string(r) + " twice");
    slot.parts[peer_index] = std::move(part->as_bytes().data);
    slot.have[peer_index] = true;
    rt_.reply(sender, m.header.id, Value::Map{});
    finish_if_complete(static_cast<uint64_t>(r));
  }

 private:
  struct Round {
    std::vector<std::string> parts;
    std::vector<bool> have;
    size_t acks_left = 0;
    std::vector<std::string>* out = nullptr;  // set once this replica's all_gather asked for the round
    std::shared_ptr<GatherState> state;
  };

  Round& round_(uint64_t round) {
    auto [it, fresh] = rounds_.try_emplace(round);
    if (fresh) {
      it->second.parts.resize(count_);
      it->second.have.assign(count_, false);
      it->second.have[index_] = true;  // filled in when this replica asks
    }
    return it->second;
  }

  // The replica index `sender` has in the pool, or count_ for a name that is not a peer.
  size_t expected_index(const std::string& sender) const {
    for (size_t k = 0; k < count_ - 1; ++k)
      if (rt_.pool_peer_name(k) == sender) return k < index_ ? k : k + 1;
    return count_;
  }

  void fail(Round& r, const std::string& why) {
    if (!r.state || r.state->remaining == 0) return;
    r.state->complete_one(why);
  }

  void finish_if_complete(uint64_t round) {
    auto it = rounds_.find(round);
    if (it == rounds_.end()) return;
    Round& r = it->second;
    if (!r.state || r.acks_left > 0) return;
    for (bool h : r.have)
      if (!h) return;
    r.out->clear();
    for (size_t i = 0; i < count_; ++i) r.out->push_back(std::move(r.parts[i]));
    auto state = std::move(r.state);
    rounds_.erase(it);
    completed_ = round + 1;  // rounds end in order: each all_gather waits for the one before
    state->complete_one();
  }

  Runtime& rt_;
  size_t index_, count_;
  DirectorExchange director_;
  ViewsInFlight& views_;
  uint64_t next_round_ = 0;
  uint64_t completed_ = 0;  // every round below this one is over
  std::map<uint64_t, Round> rounds_;
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
    params_ = config.params;
    // In a partitioned farm an op that traces only through the parts builds no BVH of the whole scene (unless a host
    // agent shares one anyway).
    const bool parts_trace = !config.geometry.empty() && kind_.traces_through_context;
    auto loaded = load_scene_for_actor(config.scene, /*with_tracer=*/!parts_trace);
    if (!loaded) return loaded.error();
    frame_scene_ = FrameScene(std::move(loaded->scene));
    if (auto taken = frame_scene_.take(config.frame_materials, "the job's first frame"); !taken) return taken.error();
    tracer_ = std::move(loaded->tracer);
    camera_ = std::make_unique<Camera>(config.camera, config.image.width, config.image.height);
    views_ = std::make_unique<ViewsInFlight>(*camera_, config.frame);
    width_ = config.image.width;
    height_ = config.image.height;
    sampler_ = sampler_of(config.image);
    lit_samples_ = config.image.shaded_per_pixel();
    inputs_ = std::make_unique<RemoteInputs>(rt, 4096, frame_scene_, *views_);
    if (config.pool) {
      replica_index_ = static_cast<int>(config.pool->index);
      replica_count_ = static_cast<int>(config.pool->count);
    }
    // Replicas that share their setup hold the same carried one: the first keeps it for all, and all restore it.
    carried_owner_ = config.pool && !config.pool->peers.empty() && replica_index_ > 0 ? config.pool->peers[0].name : rt.name();
    if (config.pool && !config.pool->peers.empty()) {
      auto peers = std::make_unique<PeerExchange>(rt, static_cast<size_t>(replica_index_), static_cast<size_t>(replica_count_), *views_);
      peer_exchange_ = peers.get();
      exchange_ = std::move(peers);
    } else if (replica_count_ > 1 && kind_.shares_setup_for(config.params)) {
      return make_error("CONFIG makes '" + rt.name() + "' replica " + std::to_string(replica_index_) + " of " +
                        std::to_string(replica_count_) + " without naming the others (pool.peers), with whom " +
                        std::string(kind_.name) + " shares its setup");
    } else {
      exchange_ = std::make_unique<DirectorExchange>(rt, *views_);
    }
    // A partitioned scene: rays go to the parts' geometry actors (ops that trace through ctx.tracing do).
    tracing_ = RemoteTracing::for_config(config, rt, frame_scene_.shipped());
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup) {
      if (renew_ || extend_ || restore_) setup_asked_ = true;  // a job's next frame: once nothing runs (on_progress)
      else if (setups_ > 0) return rt.phase_done(wire::Phase::setup);  // a job's next frame; the op is kept
      else start_setup(rt);
      on_progress(rt);
    } else if (phase == wire::Phase::render) {
      rt.phase_done(wire::Phase::render);  // a LightOp renders by answering requests
    }
  }

  void on_frame(const FrameView& view, Runtime& rt) override {
    ++frames_;
    // New materials: every op is made and set up anew over the frame's scene, carried or not, asked for by the view
    // or not (the director never restores a kept setup there: it takes the frame of the change first).
    auto changed = frame_scene_.take(view.materials, "frame " + std::to_string(view.frame));
    if (!changed) return rt.fail(changed.error().message);
    const bool anew = *changed || view.new_materials;
    if (anew && view.restore) return rt.fail("PHASE frame restores a kept setup where the materials change");
    if (anew && view.in_flight) return rt.fail("PHASE frame in flight where the materials change");
    // ctx.camera shows the new view from now on, and, in flight, the last one to the requests that name its frame.
    views_->take(view.frame, Camera(view.camera, width_, height_), view.in_flight);
    earlier_op_ = view.in_flight ? op_ : nullptr;
    // Requests from now on (another op's new setup asking this one) wait for this op's new setup. A carried setup is
    // extended to every view, replayed ones too; in flight, a copy of it is, while the op answers the last frame.
    if (op_->setup_sees_camera() && op_->carries_views()) {
      if (view.in_flight) {
        std::unique_ptr<LightOp> fork = op_->fork_view();
        if (!fork)
          return rt.fail("'" + rt.name() + "' (" + std::string(kind_.name) + ") cannot answer the last frame while it carries its "
                         "setup to the next: a job with this op renders one frame at a time");
        op_ = std::move(fork);
      }
      (view.restore ? restore_ : anew ? renew_ : extend_) = true, set_up_ = false;
      keep_frame_ = view.keep ? std::optional(view.frame) : std::nullopt;
    } else if (anew || (op_->setup_sees_camera() && view.renew)) {
      renew_ = true, set_up_ = false;
    }
    rt.phase_done(wire::Phase::frame);
  }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (op == wire::Op::pool_part && peer_exchange_) return peer_exchange_->on_part(peer, m);
    if (op != wire::Op::shade) return rt.reply_unknown_op(peer, m, "this actor serves 'shade'");
    if (!op_) {
      rt.reply_error(peer, m.header.id, ErrorCode::not_ready, "'" + rt.name() + "' is not configured yet");
      return;
    }
    // Requests that arrive before this op's setup finished (another op's setup may ask it, e.g. an irradiance
    // pre-pass) wait in the queue until it has.
    const PixelKeys keys{width_, sampler_};
    auto points = read_shade_request(m.body, scene().materials().size(), scene().triangle_count(), &scene(), &keys);
    if (!points) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, points.error().message);
      return;
    }
    auto fold = decode_pixel_fold(m.body);
    if (!fold) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, fold.error().message);
      return;
    }
    auto view = decode_shade_view(m.body);
    if (!view) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, view.error().message);
      return;
    }
    auto job = std::make_unique<Job>();
    job->peer = peer;
    job->id = m.header.id;
    job->points = std::move(*points);
    job->fold = std::move(*fold);
    job->view = *view;
    waiting_.push_back(std::move(job));
  }

  void on_progress(Runtime& rt) override {
    // PHASE setup after PHASE frame: a new op for the view, once the last one has answered what it started
    // (nothing, between frames).
    // In flight, requests still running answer the last frame with the op they hold: the new one need not wait.
    if ((renew_ || extend_ || restore_) && setup_asked_ && (running_.empty() || earlier_op_)) {
      if (renew_) op_ = create_lightop(kind_, ParamTable(params_, "lightop '" + rt.name() + "'"));
      if (restore_) setup_ = restore_setup("setup/" + carried_owner_), setup_running_ = true;
      else start_setup(rt, extend_);
      renew_ = extend_ = restore_ = setup_asked_ = false;
    }
    if (setup_running_ && setup_.done()) {
      setup_running_ = false;
      try {
        setup_.rethrow_if_failed();
      } catch (const std::exception& e) {
        rt.fail("setup failed: " + std::string(e.what()));
        return;
      }
      set_up_ = true;
      if (keep_frame_ && carried_owner_ == rt.name()) keep_setup(*keep_frame_, rt);
      keep_frame_.reset();
      rt.phase_done(wire::Phase::setup);
    }
    // Start one waiting request per turn (the loop polls sockets between requests): the oldest that can start, which
    // is any for the last frame's view in flight, and one for the latest view once it is set up.
    const auto startable = std::find_if(waiting_.begin(), waiting_.end(), [this](const auto& j) { return can_start(*j); });
    if (startable != waiting_.end() && running_.size() < kMaxRunning) {
      auto job = std::move(*startable);
      waiting_.erase(startable);
      job->radiance.assign(job->points.size(), RGB{});
      // Which view is the earlier is decided now: a request that came before PHASE frame may be for it now.
      job->op = views_->is_earlier(job->view) ? earlier_op_ : op_;
      views_->enter(job->view);
      job->task = job->op->shade(job->points, job->radiance, *inputs_);
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
        if (job.fold) {
          // The runtime folds, not the op: a LightOp returns one value a point whoever asks.
          std::vector<RGB> sums;
          fold_by_pixel(job.radiance, job.fold->samples, job.fold->spp, sums);
          rt.reply(job.peer, job.id, encode_radiance(sums));
        } else {
          rt.reply(job.peer, job.id, encode_radiance(job.radiance));
        }
      } catch (const std::exception& e) {
        rt.reply_error(job.peer, job.id, ErrorCode::shade_failed, e.what());
      }
      running_.erase(running_.begin() + static_cast<ptrdiff_t>(i));
    }
  }

  size_t queue_length() const override { return waiting_.size(); }
  bool has_local_work() const override {
    return std::any_of(waiting_.begin(), waiting_.end(), [this](const auto& j) { return can_start(*j); });
  }
  // The op's own figures (cache hits, photons, ...) under STATS "detail"; in a job of several frames, how many
  // frames, setups and extensions to a view there were (the op's figures are then the last setup's).
  Value extra_stats() const override {
    Value stats = op_ ? op_->stats() : Value();
    if (frames_ > 0) {
      if (!stats.is_map()) stats = Value::Map{};
      stats.as_map()["frames"] = static_cast<int64_t>(frames_ + 1);
      stats.as_map()["setups"] = static_cast<int64_t>(setups_);
      if (extensions_ > 0) stats.as_map()["extended"] = static_cast<int64_t>(extensions_);
    }
    if (tracing_) {
      if (!stats.is_map()) stats = Value::Map{};
      Value tracing = tracing_->stats(tracer_ != nullptr);  // held: a range-for over a temporary's map would dangle
      for (auto& [key, value] : tracing.as_map()) stats.as_map()[key] = std::move(value);
    }
    return stats;
  }

 private:
  // Starts op.setup() (or, `extend`: op.extend_to_view()) over this actor's context; on_progress answers READY
  // setup once it finishes.
  void start_setup(Runtime& rt, bool extend = false) {
    SceneContext ctx{&scene(), tracer_.get(), replica_index_, replica_count_, exchange_.get()};
    views_->enter_latest();
    ctx.camera = camera_.get();
    ctx.width = width_;
    ctx.height = height_;
    ctx.lit_samples = lit_samples_;
    ctx.sampler = sampler_;
    ctx.tracing = tracing_.get();
    ctx.progress = [&rt](const char* what, uint64_t done, uint64_t total) { rt.report_progress(what, done, total); };
    setup_ = extend ? op_->extend_to_view(std::move(ctx), *inputs_) : op_->setup(std::move(ctx), *inputs_);
    setup_running_ = true;
    ++(extend ? extensions_ : setups_);
  }

  // A resumed job: the carried setup the director kept for this actor, in place of extending it over the views.
  // `key` by value: a coroutine's reference parameter would dangle after its first co_await.
  Task restore_setup(std::string key) {
    std::string state;
    co_await exchange_->fetch(key, &state);
    op_->restore_carried(state);
  }

  // Sends the carried setup, as extended to `frame`'s view, to the director for the job's record (before READY
  // setup, on the same socket: the director has it before the frame renders). A refusal costs only the resume.
  void keep_setup(int frame, Runtime& rt) {
    std::string state = op_->carried_state();
    if (state.empty()) return;
    Value::Map body{{"frame", static_cast<int64_t>(frame)}, {"state", Bytes{std::move(state)}}};
    rt.ask_director(wire::Op::keep_setup, std::move(body), [](Result<wire::Message> r) {
      if (!r) log_warn("the director did not keep this op's setup (a resumed job will replay the views instead): " +
                       r.error().message);
    });
  }

  struct Job {
    std::string peer;
    uint64_t id = 0;
    ShadingPoints points;
    std::vector<RGB> radiance;
    std::optional<PixelFold> fold;  // the asker wants the radiance summed by pixel
    std::optional<int> view;        // the frame whose view it names (none: the latest)
    std::shared_ptr<LightOp> op;    // the op it runs on: the latest, or the last frame's
    Task task;
  };
  // A request for the last frame's view, still rendering (frames in flight), may start at once; one for the latest
  // once it is set up.
  bool can_start(const Job& job) const { return views_->is_earlier(job.view) ? earlier_op_ != nullptr : set_up_; }
  static constexpr size_t kMaxRunning = 16;

  const LightOpKind& kind_;
  Value::Map params_;  // the op's parameters, for a new op each frame whose setup depends on the view
  std::shared_ptr<LightOp> op_;
  std::shared_ptr<LightOp> earlier_op_;  // frames in flight: the op as it answers the last frame's requests
  FrameScene frame_scene_;  // the shipped scene and the frame's, if it changes materials
  const Scene& scene() const { return *frame_scene_.scene(); }  // the frame's: what the op sees
  std::shared_ptr<const RayTracer> tracer_;
  SamplerKind sampler_ = SamplerKind::independent;
  int lit_samples_ = 0;
  std::unique_ptr<Camera> camera_;  // what ctx.camera points at: the view of the code that runs (views_)
  std::unique_ptr<ViewsInFlight> views_;
  int width_ = 0, height_ = 0;
  std::unique_ptr<RemoteInputs> inputs_;
  std::unique_ptr<Exchange> exchange_;
  PeerExchange* peer_exchange_ = nullptr;  // exchange_, when the pool's replicas share their setup peer to peer
  std::unique_ptr<RemoteTracing> tracing_;  // a partitioned scene's geometry actors, or none
  int replica_index_ = 0, replica_count_ = 1;
  std::string carried_owner_;  // the actor whose kept carried setup this one's is (itself, or its pool's first)
  Task setup_;
  bool setup_running_ = false;
  bool set_up_ = false;  // setup finished: requests may start
  bool renew_ = false;   // PHASE frame: a new op is due for the new view, set up at the next PHASE setup
  bool extend_ = false;  // PHASE frame: the op carries its setup to the new view, at the next PHASE setup
  bool restore_ = false;  // PHASE frame: the op takes its carried setup from the director, at the next PHASE setup
  std::optional<int> keep_frame_;  // PHASE frame: the carried setup goes to the director once extended to this frame
  bool setup_asked_ = false;
  size_t frames_ = 0;    // PHASE frames taken (frames after the first)
  size_t setups_ = 0, extensions_ = 0;
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
