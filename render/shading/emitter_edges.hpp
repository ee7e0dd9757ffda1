#pragma once
// Where the camera sees a light's outline: the pixels that take extra samples that only see (ImageSpec::edge_spp).
//
// A light the camera sees covers part of the pixels along its outline, and whether a camera sample lands on it is a
// coin toss worth the light's whole radiance: at a pixel's spp samples that is the image's largest noise wherever
// lights are small (on Lost Empire at 16 spp, the 0.2 % of pixels where a torch's flame shows held 45 % of the
// squared error). A sample that only looks costs one camera ray, a lit one the whole network's work, so those pixels
// take more samples that only see (their emission is averaged over all of them) and the rest of the image none.
// Which pixels is a function of the scene and the camera alone, never of what a sample found: each pixel's mean
// stays unbiased (a rule that refined the pixels whose first samples met a light would darken the rest), and the
// image is the same on any layout.
//
// Marked: the pixels an emitter triangle's outline crosses (an edge it shares with another emitter triangle of the
// same material lies inside one light, not on its outline), and every pixel of a triangle whose emission varies
// over it (an emission map, or an alpha map that cuts it to a shape: Lost Empire's flames are cut from quads), each
// widened by a pixel and, through a lens, by the blur at its depth. Front sides only (lights emit there). Occluders
// are ignored: a marked pixel behind something costs its rays, nothing else.
#include <cstdint>
#include <vector>

#include "core/specs.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/camera.hpp"

namespace lf {

struct EmitterEdges {
  int width = 0, height = 0;
  int samples = 0;               // seen samples a marked pixel takes in all, more than the image's spp (0: none)
  std::vector<uint8_t> marked;   // per pixel, row by row (empty when samples is 0)
  bool at(int x, int y) const { return samples > 0 && marked[static_cast<size_t>(y) * width + x] != 0; }
  size_t count() const;          // marked pixels
};

EmitterEdges emitter_edges(const Scene& scene, const Camera& camera, const ImageSpec& image);

}  // namespace lf
