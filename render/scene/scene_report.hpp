#pragma once
// `lightfarm scene FILE.obj`: what a lighting TD wants to know before writing a farm script — triangles, bounds,
// materials with their kinds and face counts, emitters and their flux, textures found or missing, the OBJ's
// warnings, a camera that frames the whole scene, the lobes its materials have and a network for them.
#include <string>

#include "core/result.hpp"
#include "render/shading/light_paths.hpp"

namespace lf {

Result<std::string> describe_scene(const std::string& obj_path);

// Lua for a network that counts every light path on these lobes once (docs/lua-api.md, "Light paths"): direct light,
// caches and the ops the lobes need, or the path tracer alone where no lobe is diffuse or `worth_caching` is false
// (the only diffuse lobe is metals' multiply scattered light, a small share of what they reflect). With `cores` > 1
// the ops that do most of the work (the paths and the direct light, or the path tracer) are pools of that many
// replicas, one a core, as examples/lost_empire.lua has them.
std::string complete_network_for(const Lobes& lobes, bool worth_caching = true, int cores = 1);

}  // namespace lf
