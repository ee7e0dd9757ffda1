#pragma once
// The path-tracing kernel shared by `pathtrace` and `direct`. Paths for a whole batch advance together, one bounce
// at a time, so each bounce's shadow rays and continuation rays go to Embree as one stream.
//
// At every vertex: next-event estimation (a point on a light, a shadow ray) and a BSDF sample that continues the
// path; a BSDF-sampled ray that hits a light counts too. The two are combined by multiple importance sampling
// (power heuristic), so glossy surfaces get both estimators' strengths. Russian roulette ends long paths without
// bias. Emission at the first vertex is not counted: the renderer adds what the camera sees.
#include <span>

#include "render/caches/directional_cache.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/lights/near_lights.hpp"
#include "render/lightops/lightop.hpp"
#include "render/shading/sampler.hpp"

namespace lf {

struct PathOptions {
  int max_depth = 8;          // vertices that gather light; 1 is direct light only
  int rr_depth = 3;           // Russian roulette from this vertex on
  // How roulette weighs a path's throughput beta (its largest channel) over rr_threshold, b = beta / rr_threshold:
  // survival min(1, sqrt(b)) ("sqrt", Cycles' rule when rr_threshold is 1), which ends fewer paths that still carry
  // a fair share of the pixel's light, or min(0.95, b) ("throughput"). A path whose throughput is at least
  // rr_threshold always goes on. docs/decisions.md, "Roulette below a quarter".
  enum class Roulette : uint8_t { throughput, sqrt } roulette = Roulette::sqrt;
  float rr_threshold = 0.25f;
  int samples = 1;            // paths per point, averaged
  uint64_t stream = 0;        // random stream of the calling op (sampler.hpp); the sampler is the farm's (ctx)
  // With max_depth 1: on diffuse surfaces use light sampling alone (a BSDF ray adds cost, not quality there)...
  bool light_only_on_diffuse = false;
  // ... except at points these say are near a light (render/lights/near_lights.hpp), which get the BSDF sample too.
  const NearLights* mis_near = nullptr;
  // Points on mirrors and glass get nothing: in a network the `specular` op follows their chains, emitters met
  // included, so a BSDF ray from here would count those emitters twice.
  bool dark_on_specular = false;
  // Choose lights through the scene's light tree (by what each can give the point), or else by power alone.
  bool light_tree = true;
  // With the light tree: a point on the chosen triangle light uniform over its area, or over the solid angle it
  // subtends (render/lights/light_sampling.hpp).
  LightPoint light_point = LightPoint::area;
  // With the light tree: lights learned where the camera looks (render/lights/light_selection.hpp), mixed with the tree's
  // choice at points in a learned cell.
  const LightSelection* light_selection = nullptr;
  // The directional cache (render/caches/directional_cache.hpp), for diffuse continuation rays: one that meets a surface
  // inside its cell's neighbourhood goes on as usual; one that leaves it takes the cache's radiance for its direction
  // where the cache answers, and is traced on through the scene where it does not. While the cache is not frozen,
  // what such rays bring back is recorded in it: darkness at once for one that leaves the scene, the light its path
  // gathered beyond the hit once the batch is done (in path order). Light sampling and a ray the cache
  // answers split each direction's emitted light without overlap: a light sample towards a direction the cache
  // answers counts fully, and the cache holds only light reflected beyond the neighbourhood.
  DirectionalCache* cache = nullptr;
};

// Counted as paths go: each path, and each vertex at which one gathered light (the first included).
struct PathTally {
  uint64_t paths = 0;
  uint64_t vertices = 0;
  // With a directional cache: diffuse continuation rays, and how each ended (Jansen & Reinhard's Table 3): a hit inside
  // the neighbourhood (local), traced beyond it (global), answered by the cache (lookup).
  uint64_t diffuse_rays = 0, local_rays = 0, global_rays = 0, cache_lookups = 0;
};

// A coroutine: it waits where rays are traced through ctx.tracing (a partitioned scene); with the whole scene's BVH it
// finishes before it returns. `ctx`, `points`, `radiance`, `o` and `tally` must outlive it.
Task trace_paths(const SceneContext& ctx, const ShadingPoints& points, std::span<RGB> radiance, const PathOptions& o,
                 PathTally* tally = nullptr);

}  // namespace lf
