#pragma once
// The LightOp interface (Kipfer's lighting networks). A LightOp is a plain class: set up on the scene, then shade
// batches of shading points into outgoing radiance, asking its inputs (predecessors in the lighting network) where the
// algorithm needs light from elsewhere. It never sees ZeroMQ or msgpack: the actor runtime wraps it
// (actors/runtime/lightop_actor.cpp), and tests run it in-process (LocalInputs below).
//
// shade() and setup() are coroutines. Asking inputs is
//     std::vector<RGB> light;
//     co_await inputs.shade(0, points, light);
// In a farm the runtime turns that into an asynchronous batched request and serves other batches meanwhile;
// in-process the input is called directly. Asking several inputs in one gather() runs them concurrently.
#include <coroutine>
#include <functional>
#include <cstdint>
#include <exception>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/params.hpp"
#include "render/tracing/camera.hpp"
#include "render/shading/light_paths.hpp"
#include "render/math.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

// A batch of points to shade, as structure of arrays (it travels as one float blob per field).
struct ShadingPoints {
  std::vector<Vec3> position;
  std::vector<Vec3> normal;    // unit, on the side of wo: the shading normal (interpolated vertex normals)
  std::vector<Vec3> wo;        // unit, pointing away from the surface (towards the viewer)
  std::vector<uint32_t> material;
  std::vector<uint64_t> key;   // sample_key(pixel, sample): seeds every random decision for this point
  // Optional: the scene triangle each point lies on (its winding tells outside from inside). Empty when the
  // sender did not say; then every point counts as on the outside.
  std::vector<uint32_t> triangle;
  size_t size() const { return position.size(); }
  void reserve(size_t n);
  void clear();
  void push_back(Vec3 p, Vec3 n, Vec3 w, uint32_t m, uint64_t k);
  void push_back(Vec3 p, Vec3 n, Vec3 w, uint32_t m, uint64_t k, uint32_t tri);
  uint32_t triangle_of(size_t i) const { return triangle.empty() ? UINT32_MAX : triangle[i]; }
  // True when point i is on the side its triangle's winding faces (or nothing says otherwise).
  bool outside(size_t i, const Scene& scene) const {
    return triangle.empty() || dot(scene.normal(triangle[i]), wo[i]) >= 0;
  }
  // The geometric normal at point i, on the side of its shading normal (that normal itself without a triangle).
  Vec3 face_normal(size_t i, const Scene& scene) const {
    if (triangle.empty()) return normal[i];
    const Vec3 n = scene.normal(triangle[i]);
    return dot(n, wo[i]) >= 0 ? n : -n;
  }
  // The diffuse reflectance at point i: its triangle's texture there (filtered to `footprint`, the width of a
  // pixel there: pixel_footprint()), else its material's kd.
  RGB albedo(size_t i, const Scene& scene, float footprint = 0) const {
    const Material& m = scene.material(material[i]);
    if (triangle.empty() || m.kd_map < 0 || !scene.has_uvs()) return m.kd;
    return scene.albedo(triangle[i], scene.barycentrics(triangle[i], position[i]), footprint);
  }
  // A metal_rough material's metallic and roughness at point i (Scene::metal_rough_at; its factors without maps).
  void metal_rough(size_t i, const Scene& scene, float footprint, float& metallic, float& roughness) const {
    const Material& m = scene.material(material[i]);
    metallic = m.metallic;
    roughness = m.roughness;
    if (triangle.empty() || (m.metallic_map < 0 && m.roughness_map < 0) || !scene.has_uvs()) return;
    scene.metal_rough_at(triangle[i], scene.barycentrics(triangle[i], position[i]), footprint, metallic, roughness);
  }
  // Empty string when consistent; otherwise what is wrong (for validating what arrives from the wire).
  std::string check(size_t material_count, size_t triangle_count = SIZE_MAX) const;
};

// The coroutine type of setup() and shade(). Starts eagerly; whoever holds it checks done() and failure.
class Task {
 public:
  struct promise_type {
    std::exception_ptr error;
    std::coroutine_handle<> continuation;  // a coroutine awaiting this one, resumed when it finishes
    Task get_return_object() { return Task(std::coroutine_handle<promise_type>::from_promise(*this)); }
    std::suspend_never initial_suspend() noexcept { return {}; }
    auto final_suspend() noexcept {
      struct Resume {
        bool await_ready() noexcept { return false; }
        std::coroutine_handle<> await_suspend(std::coroutine_handle<promise_type> h) noexcept {
          auto c = h.promise().continuation;
          return c ? c : std::noop_coroutine();
        }
        void await_resume() noexcept {}
      };
      return Resume{};
    }
    void return_void() {}
    void unhandled_exception() { error = std::current_exception(); }
  };
  Task() = default;
  explicit Task(std::coroutine_handle<promise_type> h) : handle_(h) {}
  Task(Task&& o) noexcept : handle_(std::exchange(o.handle_, {})) {}
  Task& operator=(Task&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, {});
    }
    return *this;
  }
  ~Task() { reset(); }
  bool done() const { return !handle_ || handle_.done(); }
  // A LightOp may `co_await` a helper coroutine of its own: the caller resumes when the helper finishes.
  bool await_ready() const noexcept { return done(); }
  void await_suspend(std::coroutine_handle<> h) noexcept { handle_.promise().continuation = h; }
  void await_resume() const { rethrow_if_failed(); }
  // Rethrows what the coroutine threw, if it finished by throwing.
  void rethrow_if_failed() const {
    if (handle_ && handle_.done() && handle_.promise().error) std::rethrow_exception(handle_.promise().error);
  }

 private:
  void reset() {
    if (handle_) handle_.destroy();
    handle_ = {};
  }
  std::coroutine_handle<promise_type> handle_;
};

// Thrown by a LightOp (or by an input it asked) when a batch cannot be shaded; the runtime answers with ERROR.
class LightOpError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a co_await on inputs waits for: a count of outstanding answers, filled in by whoever serves the inputs.
struct GatherState {
  size_t remaining = 0;
  std::string error;                 // first failure, if any
  std::coroutine_handle<> waiter;    // resumed when remaining reaches 0
  // Called just before the waiter resumes: the runtime gives the coroutine back what it saw when it began waiting
  // (the view of a job's frame it shades, while another frame's requests ran meanwhile).
  std::function<void()> before_resume;
  void complete_one(std::string failure = {});
};

class Gather {
 public:
  explicit Gather(std::shared_ptr<GatherState> s) : state_(std::move(s)) {}
  bool await_ready() const noexcept { return state_->remaining == 0; }
  void await_suspend(std::coroutine_handle<> h) noexcept { state_->waiter = h; }
  void await_resume() const {
    if (!state_->error.empty()) throw LightOpError(state_->error);
  }

 private:
  std::shared_ptr<GatherState> state_;
};

struct InputQuery {
  size_t input;                  // which input, in the order the script wired them
  const ShadingPoints* points;   // must stay alive until the gather completes
  std::vector<RGB>* radiance;    // resized and filled by the answer
};

// A LightOp's view of its predecessors.
class Inputs {
 public:
  virtual ~Inputs() = default;
  virtual size_t count() const = 0;
  virtual Gather gather(std::vector<InputQuery> queries) = 0;
  Gather shade(size_t input, const ShadingPoints& points, std::vector<RGB>& radiance) {
    return gather({InputQuery{input, &points, &radiance}});
  }
};

// Replicas of one pool share work done in setup: each contributes its part and receives every replica's part, in
// replica order, so that all of them build the same state (e.g. a photon map from disjoint shares). An op that is
// not in a pool gets its own part back at once.
class Exchange {
 public:
  virtual ~Exchange() = default;
  virtual Gather all_gather(std::string part, std::vector<std::string>* parts) = 0;
  // Something the farm publishes by name, e.g. "radiosity" (a RadiosityField's bytes, once the ring converged).
  // Waits until it is ready; fails when nothing by that name exists.
  virtual Gather fetch(const std::string& key, std::string* blob);
};

// The exchange of an op with no peers: its part comes straight back.
class SoloExchange final : public Exchange {
 public:
  Gather all_gather(std::string part, std::vector<std::string>* parts) override {
    parts->assign(1, std::move(part));
    return Gather(std::make_shared<GatherState>());
  }
};

// Tracing the op may have to wait for: in a farm whose scene is split into parts (partition { parts = N }), rays
// travel to the geometry actors that hold the parts. `co_await tracing.intersect(rays, hits)` answers exactly what
// RayTracer::intersect would on the whole scene (render/tracing/partition.hpp); the op's coroutine waits meanwhile and the
// runtime serves other requests.
class Tracing {
 public:
  virtual ~Tracing() = default;
  virtual Task intersect(std::span<const Ray> rays, std::span<Hit> hits) = 0;
  virtual Task occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) = 0;
};

// What a LightOp gets at setup: the scene, its ray tracer, and where it stands among replicas.
struct SceneContext {
  const Scene* scene = nullptr;
  const RayTracer* tracer = nullptr;
  int replica_index = 0;
  int replica_count = 1;
  Exchange* exchange = nullptr;  // never null in setup(): SoloExchange when not in a pool
  // The farm's camera and image size, for ops that place work where the camera looks (null in some tests).
  const Camera* camera = nullptr;
  int width = 0, height = 0;
  // The image's lit (shaded) samples a pixel, the farm's quality knob: what settings left unset are derived from
  // (derived_settings.hpp). 0 where there is no image (some tests): taken as 16.
  int lit_samples = 0;
  // How camera samples and the ops that follow them draw their numbers (image { sampler }): a point's key is that
  // sampler's (sampler.hpp).
  SamplerKind sampler = SamplerKind::sobol;
  // How far a long setup is ("shooting photons", done, total); the runtime tells the director, which shows it.
  // Call it as often as convenient: the runtime passes on a few a second. May be empty (tests).
  std::function<void(const char* what, uint64_t done, uint64_t total)> progress;
  // Set in a partitioned farm: ops that trace through it (path_kernel: `direct`, `pathtrace`) do, and the others
  // use `tracer`, the whole scene's BVH, as before.
  Tracing* tracing = nullptr;
  void report(const char* what, uint64_t done, uint64_t total) const {
    if (progress) progress(what, done, total);
  }
  // How wide a pixel of the farm's camera is at p, in scene units (0 without a camera): the footprint textures are
  // filtered to. Measured from the eye, so for a point seen only by a secondary ray it is a guess, and a blurrier
  // texture there keeps its mean colour.
  float pixel_footprint(Vec3 p) const { return camera ? length(p - camera->eye()) * camera->pixel_angle() : 0.0f; }
};

class LightOp {
 public:
  virtual ~LightOp() = default;
  // Runs once before rendering (photon shooting, caches, ...). The pointers in ctx outlive the op. ctx comes by
  // value because setup is a coroutine: a reference parameter would dangle after its first co_await.
  virtual Task setup(SceneContext ctx, Inputs& inputs) = 0;
  // Whether setup() depends on the camera (it places work where the camera looks): the next frame of a job, seen
  // from elsewhere, then sets up a new op; one whose setup does not (a photon map) keeps it for every frame. Either
  // way ctx.camera points at the frame's camera while it renders. Unsure: true.
  virtual bool setup_sees_camera() const { return true; }
  // An op whose setup sees the camera may instead carry what it built over a job's frames: extend_to_view() then
  // adds what the new view (*ctx.camera) needs, never changing what is there, and the op is kept. Frame k's image
  // then depends on the job's frames up to k (the farm replays the views of frames it skips to keep it so).
  virtual bool carries_views() const { return false; }
  virtual Task extend_to_view(SceneContext ctx, Inputs& inputs) {
    (void)ctx, (void)inputs;
    co_return;
  }
  // A copy of this op as it stands, for a job's frames in flight: the copy is extended to the next view while this
  // one goes on answering the last view's requests, unchanged. nullptr: the op cannot be copied, and the job's frames
  // then go one at a time.
  virtual std::unique_ptr<LightOp> fork_view() const { return nullptr; }
  // A carried setup as bytes, kept in a job's record after each view, so that a run resuming the job restores it
  // (restore_carried) instead of replaying the views before its first frame. Empty: nothing to keep (the farm
  // then replays).
  virtual std::string carried_state() const { return {}; }
  // Makes this op hold what carried_state() gave, on an op set up (setup()) with the same parameters and scene:
  // its answers are then bit for bit those of the op that gave the bytes. Throws LightOpError on bytes it cannot
  // use.
  virtual void restore_carried(std::string_view state) {
    (void)state;
    throw LightOpError("this op keeps no carried setup");
  }
  // Writes the radiance leaving each point towards its wo into radiance[i] (radiance.size() == points.size()).
  // Emission of the point itself is not included: the renderer adds what the camera sees directly.
  virtual Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs& inputs) = 0;
  // What the op did, for STATS and the end-of-run table (a map of numbers; nil when there is nothing to tell):
  // how to tune it comes from here (docs/lua-api.md).
  virtual Value stats() const { return Value(); }
  // Which light paths shade() counts, given what each input's answer counts (render/shading/light_paths.hpp): e.g.
  // `irradiance` returns its input's paths each followed by a diffuse event. The farm composes these along the
  // network before it launches anything and checks that every path the scene's materials allow reaches the camera
  // exactly once (farm/light_path_check.hpp). nullopt: the op does not say (the check then passes over it).
  virtual std::optional<LightPaths> paths(std::span<const LightPaths> inputs) const {
    (void)inputs;
    return std::nullopt;
  }
};

// Inputs served in-process: each input is another LightOp in the same address space, called directly.
// Used by unit tests and single-process tools.
class LocalInputs : public Inputs {
 public:
  explicit LocalInputs(std::vector<std::pair<LightOp*, Inputs*>> ops) : ops_(std::move(ops)) {}
  LocalInputs() = default;
  size_t count() const override { return ops_.size(); }
  Gather gather(std::vector<InputQuery> queries) override;

 private:
  std::vector<std::pair<LightOp*, Inputs*>> ops_;
};

// Rays through ctx.tracing when the farm's scene is split into parts, else through ctx.tracer, the whole scene's BVH
// (then finished before it returns). `ctx`, `rays` and the answers must outlive it.
Task trace_intersect(const SceneContext& ctx, std::span<const Ray> rays, std::span<Hit> hits);
Task trace_occluded(const SceneContext& ctx, std::span<const Ray> rays, std::span<uint8_t> occluded);

// Runs a task that must complete synchronously (in-process use); throws what it threw.
void run_to_completion(Task task);

}  // namespace lf
