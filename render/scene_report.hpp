#pragma once
// `lightfarm scene FILE.obj`: what a lighting TD wants to know before writing a farm script — triangles, bounds,
// materials with their kinds and face counts, emitters and their flux, textures found or missing, the OBJ's
// warnings, and a camera that frames the whole scene.
#include <string>

#include "core/result.hpp"

namespace lf {

Result<std::string> describe_scene(const std::string& obj_path);

}  // namespace lf
