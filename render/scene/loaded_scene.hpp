#pragma once
// A scene with its BVH, as an actor holds them. An actor loads its own, unless the process was forked from a host
// agent that preloaded the same scene (actors/runtime/host_agent.hpp): then every actor on the host shares the
// agent's BVH pages instead of building its own (Embree 3 keeps a BVH in its own heap, with pointers, so only fork
// can share one between processes).
#include <memory>
#include <string>

#include "core/result.hpp"
#include "core/specs.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

struct LoadedScene {
  std::shared_ptr<const Scene> scene;
  std::shared_ptr<const RayTracer> tracer;  // built over *scene
};

// The scene `spec` names, with its BVH: the preloaded one when `spec` is a shipped scene of the preloaded hash,
// else loaded and built here (without `with_tracer`, no BVH is built: a geometry actor builds its part's own).
Result<LoadedScene> load_scene_for_actor(const SceneSpec& spec, bool with_tracer = true);

// Loads the shipped scene at `path` (content hash `hash`) and builds its BVH, for load_scene_for_actor to return
// to this process and to every process forked from it.
Status preload_shipped_scene(const std::string& path, const std::string& hash);

// Whether load_scene_for_actor served the last scene from the preload (for tests and STATS).
bool scene_was_preloaded();

}  // namespace lf
