#pragma once
// NearLights: whether a shading point lies close to an emitter triangle, within `reach` times the radius of the
// sphere around the triangle. A point on a light drawn by its area carries the weight cos cos / d²; where the light
// is as near as it is large that weight changes over the light by orders of magnitude, and where the light touches
// the surface (a torch on a wall, a panel set in a ceiling) its variance has no bound. A BSDF sample, weighed
// against it by MIS, tames those points; everywhere else it costs a ray that almost never meets a light. So
// `direct` takes BSDF samples on diffuse surfaces only inside these zones (docs/decisions.md, "MIS near the
// lights").
//
// Which zone holds a point is a pure function of the point and the scene: every process and every layout decides
// alike, and the estimator stays unbiased (the choice of strategies depends on the point alone, never on a sample).
// Point lights have no zone: no BSDF ray can meet one.
//
// A hash grid over the zones: cells twice the median zone's radius, each listing the zones that overlap it; a zone
// too large for that grid (a large panel among small lamps) is tested at every point.
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "render/math.hpp"

namespace lf {

class Scene;

class NearLights {
 public:
  NearLights(const Scene& scene, float reach);

  bool near(Vec3 x) const;

  size_t zone_count() const { return zones_.size(); }
  size_t everywhere_count() const { return everywhere_.size(); }

 private:
  struct Zone {
    Vec3 centre;
    float radius2;
  };
  // A zone that would overlap more cells than this is tested at every point instead.
  static constexpr int64_t kMostCells = 512;

  uint64_t key(int64_t ix, int64_t iy, int64_t iz) const;
  int64_t cell_index(float v, float lo) const;
  bool inside(uint32_t zone, Vec3 x) const {
    const Vec3 d = x - zones_[zone].centre;
    return dot(d, d) < zones_[zone].radius2;
  }

  std::vector<Zone> zones_;
  std::vector<uint32_t> everywhere_;
  Vec3 origin_{};
  float inverse_cell_ = 1;
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> cells_;  // key -> range in members_
  std::vector<uint32_t> members_;
};

}  // namespace lf
