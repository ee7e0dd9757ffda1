#pragma once
// Path-space accounting: does the lighting network count every light path that reaches the camera in this scene
// exactly once? Each LightOp says which paths its answer counts given its inputs' (LightOp::paths, in Heckbert's
// notation: render/shading/light_paths.hpp); this composes them along the farm's graph, from the ops without inputs to the
// one the renderers ask, and compares the result with the paths the scene's materials allow: a letter for each lobe
// some material has (D: diffuse reflectance, G: a glossy Phong lobe, S: mirror or glass).
//
//   counted twice  an error, at the line of the op where two parts first both add the same light
//   left out       a warning at the lighting's line naming the paths, the materials they end on and the op kind
//                  that computes them; an error with farm { light_paths = "complete" }, nothing with "partial"
//                  (a network meant to compute part of the light, e.g. direct light alone)
//
// Exec actors (plug-ins) do not say what they compute: a network with one is not checked, which a warning says.
#include <optional>
#include <string>
#include <vector>

#include "farm/farm_spec.hpp"
#include "render/shading/light_paths.hpp"

namespace lf {

struct LightPathReport {
  std::vector<std::string> errors;    // "farm.lua:12: ..." each
  std::vector<std::string> warnings;
  std::string error_text() const;  // the errors, a line each
};

LightPathReport check_light_paths(const FarmSpec& spec, const SceneLobes& scene);

// What each actor's answer counts, over every lobe (no scene needed): a short summary per actor index, empty for
// actors that are not LightOps or do not say. For the arrows of `lightfarm graph`.
std::vector<std::string> light_path_summaries(const FarmSpec& spec);

// Where each actor's answer can be other than zero (LightPaths::ends), by actor index: a pool's as its replicas';
// nullopt for actors that are not LightOps or do not say (plug-ins, and whatever asks one of them). What the
// director tells each asker of an input (CONFIG inputs[i].answers_at), so that it asks only about those points.
std::vector<std::optional<AnswerEnds>> answer_ends(const FarmSpec& spec);

}  // namespace lf
