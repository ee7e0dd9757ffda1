#include "render/scene/loaded_scene.hpp"

#include "render/scene/scene_image.hpp"

namespace lf {

namespace {

struct Preloaded {
  std::string hash;
  LoadedScene loaded;
};
// One per process: a host agent's, inherited by the actors it forks. Set before any actor thread exists.
Preloaded* g_preloaded = nullptr;
bool g_served_from_preload = false;

}  // namespace

Result<LoadedScene> load_scene_for_actor(const SceneSpec& spec, bool with_tracer) {
  if (g_preloaded && !spec.cache.empty() && spec.hash == g_preloaded->hash) {
    g_served_from_preload = true;
    return g_preloaded->loaded;
  }
  auto scene = Scene::load(spec);
  if (!scene) return scene.error();
  auto owned = std::make_shared<const Scene>(std::move(*scene));
  if (!with_tracer) return LoadedScene{std::move(owned), nullptr};
  auto tracer = std::make_shared<const RayTracer>(*owned);
  return LoadedScene{std::move(owned), std::move(tracer)};
}

Status preload_shipped_scene(const std::string& path, const std::string& hash) {
  auto scene = load_shared_scene(path, hash, "the shipped scene");
  if (!scene) return scene.error();
  auto owned = std::make_shared<const Scene>(std::move(*scene));
  auto tracer = std::make_shared<const RayTracer>(*owned);
  delete g_preloaded;
  g_preloaded = new Preloaded{hash, {std::move(owned), std::move(tracer)}};
  return Ok{};
}

bool scene_was_preloaded() { return g_served_from_preload; }

}  // namespace lf
