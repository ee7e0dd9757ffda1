#pragma once
// Lights that light nothing: for each emitting material and each point light, the share of its emitted flux that
// leaves the scene without meeting a surface (a quad wound away from the room, a light placed above an open
// terrain). Estimated with a fixed set of rays (cosine-weighted from the emitters' surfaces, uniform from point
// lights), so the answer is the same on every run.
#include <string>
#include <vector>

#include "render/scene/scene.hpp"

namespace lf {

struct LightEscape {
  std::string light;     // "material 'Torch'", or a script light's "farm.lua:12: light"
  double escaping = 0;   // share of its flux that meets nothing, 0..1
};

// Every light of the finalized `scene`, in material order then point-light order. `point_light_labels` names the
// last point lights (the script's, in order, e.g. "farm.lua:9: light"); earlier ones are numbered.
std::vector<LightEscape> light_escapes(const Scene& scene, const std::vector<std::string>& point_light_labels = {});

// "LIGHT: 97% of its flux leaves the scene without lighting anything (...)" for each light above `threshold`.
std::vector<std::string> escaping_light_warnings(const std::vector<LightEscape>& escapes, double threshold = 0.5);

}  // namespace lf
