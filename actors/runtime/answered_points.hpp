#pragma once
// The points of a request an input's answer can reach. An op asks its inputs about the points it shades (a combine
// asks every input about all of them), but an input whose light paths all end in lobes a point's material lacks
// answers exactly zero there: a glossy op at a Lambert point, a mirror op anywhere but on mirrors and glass. The
// runtime leaves such points out of the request and answers them zero itself, which saves encoding, sending and
// decoding them and the input's look at each. Where the answer can be other than zero comes from the farm's
// light-path accounting (CONFIG inputs[i].answers_at, render/shading/light_paths.hpp: AnswerEnds).
#include <cstdint>
#include <vector>

#include "render/lightops/lightop.hpp"
#include "render/shading/light_paths.hpp"

namespace lf {

struct AnsweredPoints {
  bool all = true;                // every point is asked about: `index` and `points` are empty
  std::vector<uint32_t> index;    // otherwise the asked points' places among the points
  ShadingPoints points;           // and those points, in order
};

// The points of `points` (on a scene with `materials`) whose answer `ends` can reach.
AnsweredPoints answered_points(const ShadingPoints& points, const std::vector<Material>& materials, const AnswerEnds& ends);

}  // namespace lf
