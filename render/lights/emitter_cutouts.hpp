#pragma once
// Light samples on emitters that an alpha map cuts out: drawn only where the emitter may be there.
//
// A cut-out emitter (a torch quad of Lost Empire is ~85 % cut away) used to get points uniform over its whole
// triangle, and a point on a cut part brought nothing: most of its light samples were spent for no light. Here each
// such triangle keeps the cells of its coverage map (the squares between four texel centres, which bilinear lookup
// blends) that reach coverage 1/2 at one of their corners, clipped to the triangle. A bilinear value is a blend of
// its cell's four corners, so a point can be there only inside such a cell: sampling those cells uniformly by area
// covers every point that emits, and the cut-out test at the sampled point still removes the rest. The density is
// uniform over the cells' area, so it is the same at every point that emits (what MIS needs when a BSDF ray hits
// the emitter). Emitters without an alpha map, or whose cells cover the whole triangle, are sampled as before.
// A pure function of the scene, built in every process like the light tree.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "render/math.hpp"
#include "render/shading/sampler.hpp"

namespace lf {

class Scene;

class EmitterCutouts {
 public:
  explicit EmitterCutouts(const Scene& scene);

  // Whether emitter e (Scene's numbering) has its samples restricted to part of its triangle.
  bool restricted(size_t e) const { return e < slot_.size() && slot_[e] >= 0; }
  // The world area emitter e's samples are spread over (restricted emitters only).
  float sampled_area(size_t e) const { return emitters_[static_cast<size_t>(slot_[e])].area; }
  // Barycentrics of a point uniform over that area, from uv uniform in [0, 1)^2 (restricted emitters only).
  Vec3 barycentrics(size_t e, Uniform2 uv) const;
  // Whether any emitter is restricted (when none, nothing changes for any sample).
  bool any() const { return !emitters_.empty(); }

 private:
  struct Emitter {
    double x[3], y[3];     // the triangle's corners in its coverage map's texel space
    double to_barycentric[4];  // from (x - x0, y - y0) to (b1, b2)
    uint32_t first = 0, count = 0;  // its cells in cells_
    float area = 0;        // the world area of its cells, clipped to the triangle
  };
  struct Cell {
    int32_t i, j;  // the square [i, i + 1] x [j, j + 1] of texel space
    float cdf;     // the emitter's cells up to this one, as a share of their area (the last is 1)
    bool whole;    // inside the triangle: sampled as a square, without clipping
  };
  std::vector<int32_t> slot_;  // per emitter: its index in emitters_, or -1
  std::vector<Emitter> emitters_;
  std::vector<Cell> cells_;
};

}  // namespace lf
