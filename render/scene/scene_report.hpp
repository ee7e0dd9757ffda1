#pragma once
// `lightfarm scene FILE.obj`: what a lighting TD wants to know before writing a farm script — triangles, bounds,
// materials with their kinds and face counts, emitters and their flux, textures found or missing, the OBJ's
// warnings, a camera that frames the whole scene, the lobes its materials have and a network for them.
#include <string>

#include "core/result.hpp"
#include "render/shading/light_paths.hpp"

namespace lf {

Result<std::string> describe_scene(const std::string& obj_path);

// What the suggested network depends on besides the lobes.
struct NetworkChoices {
  // False where no lobe is diffuse enough for a cache (the only diffuse lobe is metals' multiply scattered light,
  // a small share of what they reflect) or most of what the surfaces gather comes from outside the scene.
  bool worth_caching = true;
  // Above 1, the ops that do most of the work (the paths and the direct light, or the path tracer) are pools of
  // that many replicas, one a core, as examples/lost_empire.lua has them.
  int cores = 1;
  // More lights than one quad: `direct` learns which of them light what the camera sees, and takes 2 samples a
  // point, as examples/lost_empire.lua's does (docs/decisions.md, "The suggested network").
  bool many_lights = false;
};

// Lua for a network that counts every light path on these lobes once (docs/lua-api.md, "Light paths"): direct light,
// caches and the ops the lobes need, or the path tracer alone where no lobe is diffuse or caching is not worth it.
std::string complete_network_for(const Lobes& lobes, const NetworkChoices& choices = {});

}  // namespace lf
