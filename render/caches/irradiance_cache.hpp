#pragma once
// Ward's irradiance cache with Ward & Heckbert's irradiance gradients: the data structure and its arithmetic, apart
// from the LightOp that fills it (lightops/irradiance.cpp).
#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "render/math.hpp"
#include "render/shading/elevation_bands.hpp"

namespace lf {

struct IrradianceRecord {
  Vec3 position;
  Vec3 normal;
  RGB irradiance;
  float harmonic_distance;     // R_i: harmonic mean distance to what the hemisphere sees
  Vec3 rotational[3];          // d E / d(normal rotation), per channel
  Vec3 translational[3];       // d E / d position, per channel
  // E split by the elevation its light arrives from (they sum to E): what lobes that weigh light by its elevation
  // reflect (render/shading/elevation_bands.hpp). Filled by the op that traced the hemisphere.
  ElevationBands bands{};
};

// Hemisphere samples of one record, stratified for cosine weighting: cell (j, k) has sin^2(theta) in
// [j/M, (j+1)/M) and phi in [2 pi k / N, 2 pi (k+1) / N).
struct HemisphereSamples {
  int m = 0, n = 0;            // theta and phi strata
  std::vector<RGB> radiance;   // index j * n + k
  std::vector<float> distance; // to the hit (a large number for none)
};

// E, R and both gradients from a stratified hemisphere (Ward & Heckbert 1992). `u`, `v`, `w` are the local frame
// (w = the normal); the strata's directions were built from the same frame.
IrradianceRecord make_record(Vec3 position, Vec3 u, Vec3 v, Vec3 w, const HemisphereSamples& s);

// Direction of sample (j, k) with jitter (a, b) in [0,1)^2, in the frame (u, v, w).
Vec3 stratum_direction(int j, int k, int m, int n, float a, float b, Vec3 u, Vec3 v, Vec3 w);

class IrradianceCache {
 public:
  // `a`: Ward's error bound; `extent`: the scene's size (sets the octree's root cell); `max_relax`: the widest
  // bound any lookup will use, as a multiple of a (at most kMaxRelax). Records are listed only where that bound
  // reaches, so a cache whose lookups never relax lists each record in far fewer cells.
  IrradianceCache(float a, float extent, float max_relax = kMaxRelax)
      : a_(a), root_(extent), max_relax_(std::clamp(max_relax, 1.0f, kMaxRelax)) {}

  void insert(const IrradianceRecord& r);
  // Weighted, gradient-extrapolated irradiance at (x, n) from the records whose error there is below relax * a;
  // false when there is none. relax may be at most max_relax.
  bool lookup(Vec3 x, Vec3 n, RGB& irradiance, float relax = 1.0f) const;
  // The lookups under bounds relax[0] * a, relax[1] * a, ... (ascending, at most 4 of them, each at most
  // max_relax) in one pass over the records: the index of the first that found records, its irradiance in
  // `irradiance`, or -1. Gives exactly what the separate lookups would. `records`, if given: how many records that
  // answer averaged. `bands`, if given: that irradiance by elevation, each record's bands scaled to its
  // extrapolated irradiance (so they sum to `irradiance`) and averaged with the same weights.
  int lookup_first(Vec3 x, Vec3 n, std::span<const float> relax, RGB& irradiance, uint32_t* records = nullptr,
                   ElevationBands* bands = nullptr) const;
  static constexpr float kMaxRelax = 4.0f;
  // How far behind a record's tangent plane, as a share of its R, a point may lie beyond what the surface's
  // curvature explains (rounding, meshes' facets).
  static constexpr float kBehindSlack = 0.002f;
  static constexpr int kMaxGridLevel = 12;  // the coarsest frozen grid: cells 4^12 times the finest
  // No more inserts: builds grids in which every record is listed in each cell its widest valid sphere touches,
  // so that a lookup reads one cell per grid instead of 27 per octree level. The finest grid's cells are half the
  // median record's valid radius; a record that would touch more than 512 of them goes to a grid 4 times coarser,
  // and so on (a cache in open space holds records valid tens of cells wide). Lookups then give the same records,
  // visited in record order.
  void freeze();
  size_t size() const { return records_.size(); }
  const std::vector<IrradianceRecord>& records() const { return records_; }

  static std::string serialize(std::span<const IrradianceRecord> records);
  static bool deserialize(const std::string& bytes, std::vector<IrradianceRecord>& out);

 private:
  // A hashed octree: level L has cells of size root / 2^L; a record lives in the deepest level whose cells are at
  // least its valid diameter, so a lookup checks the 27 cells around x on each level.
  struct Key {
    int level, x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const;
  };
  float cell_size(int level) const;
  Key key_of(int level, Vec3 p) const;

  float a_;
  float root_;
  float max_relax_;
  std::vector<IrradianceRecord> records_;
  std::unordered_map<Key, std::vector<uint32_t>, KeyHash> cells_;
  std::vector<int> levels_;  // levels that hold records, ascending: lookups visit only these
  // The frozen grids (empty until freeze()): the finest one's cell size, cell (level k: cells grid_cell_ * 4^k)
  // -> records in index order, and the levels that hold records.
  float grid_cell_ = 0;
  std::unordered_map<Key, std::vector<uint32_t>, KeyHash> grid_;
  std::vector<int> grid_levels_;
  template <class Visit>
  void for_candidates(Vec3 x, Visit&& visit) const;
};

}  // namespace lf
