#include "render/caches/irradiance_cache.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace lf {

Vec3 stratum_direction(int j, int k, int m, int n, float a, float b, Vec3 u, Vec3 v, Vec3 w) {
  const float sin2 = (static_cast<float>(j) + a) / static_cast<float>(m);
  const float sin_t = std::sqrt(sin2), cos_t = std::sqrt(std::max(0.0f, 1.0f - sin2));
  const float phi = 2.0f * kPi * (static_cast<float>(k) + b) / static_cast<float>(n);
  return normalize(u * (sin_t * std::cos(phi)) + v * (sin_t * std::sin(phi)) + w * cos_t);
}

IrradianceRecord make_record(Vec3 position, Vec3 u, Vec3 v, Vec3 w, const HemisphereSamples& s) {
  const int m = s.m, n = s.n;
  auto L = [&](int j, int k) { return s.radiance[static_cast<size_t>(j * n + ((k + n) % n))]; };
  auto r = [&](int j, int k) { return s.distance[static_cast<size_t>(j * n + ((k + n) % n))]; };
  IrradianceRecord rec{};
  rec.position = position;
  rec.normal = w;
  // E = pi / (M N) sum L (cosine-weighted strata); R = harmonic mean distance.
  RGB sum{};
  double inverse_distance = 0;
  for (int j = 0; j < m; ++j)
    for (int k = 0; k < n; ++k) {
      sum += L(j, k);
      inverse_distance += 1.0 / std::max(r(j, k), 1e-6f);
    }
  rec.irradiance = sum * (kPi / static_cast<float>(m * n));
  rec.harmonic_distance = static_cast<float>(static_cast<double>(m * n) / inverse_distance);

  for (int c = 0; c < 3; ++c) {
    Vec3 rot{}, trans{};
    for (int k = 0; k < n; ++k) {
      const float phi_mid = 2.0f * kPi * (static_cast<float>(k) + 0.5f) / static_cast<float>(n);
      const float phi_low = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(n);
      const Vec3 u_mid = u * std::cos(phi_mid) + v * std::sin(phi_mid);
      const Vec3 v_mid = u * -std::sin(phi_mid) + v * std::cos(phi_mid);
      const Vec3 v_low = u * -std::sin(phi_low) + v * std::cos(phi_low);
      // Rotational: sum over theta of tan(theta) L, along the direction perpendicular to the azimuth. (Ward &
      // Heckbert write -tan with the opposite handedness of the (u, v) frame; the sign here is the one that
      // matches finite differences of the closed form, irradiance.test.cpp.)
      float rot_sum = 0;
      for (int j = 0; j < m; ++j) {
        const float sin2 = (static_cast<float>(j) + 0.5f) / static_cast<float>(m);
        const float tan_t = std::sqrt(sin2 / std::max(1e-6f, 1.0f - sin2));
        rot_sum += tan_t * L(j, k)[c];
      }
      rot += v_mid * rot_sum;
      // Translational: changes across the theta boundaries of this azimuth cell, and across its low phi boundary.
      float across_theta = 0, across_phi = 0;
      for (int j = 1; j < m; ++j) {
        const float sin_lo = std::sqrt(static_cast<float>(j) / static_cast<float>(m));
        const float cos2_lo = 1.0f - sin_lo * sin_lo;
        across_theta += sin_lo * cos2_lo / std::min(r(j, k), r(j - 1, k)) * (L(j, k)[c] - L(j - 1, k)[c]);
      }
      for (int j = 0; j < m; ++j) {
        const float sin_lo = std::sqrt(static_cast<float>(j) / static_cast<float>(m));
        const float sin_hi = std::sqrt(static_cast<float>(j + 1) / static_cast<float>(m));
        across_phi += (sin_hi - sin_lo) / std::min(r(j, k), r(j, k - 1)) * (L(j, k)[c] - L(j, k - 1)[c]);
      }
      trans += u_mid * (across_theta * 2.0f * kPi / static_cast<float>(n)) + v_low * across_phi;
    }
    rec.rotational[c] = rot * (kPi / static_cast<float>(m * n));
    rec.translational[c] = trans;
  }
  return rec;
}

size_t IrradianceCache::KeyHash::operator()(const Key& k) const {
  uint64_t h = static_cast<uint64_t>(k.level) * 0x9e3779b97f4a7c15ull;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.x)) * 0xbf58476d1ce4e5b9ull;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.y)) * 0x94d049bb133111ebull;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.z)) * 0x2545f4914f6cdd1dull;
  return static_cast<size_t>(h ^ (h >> 29));
}

float IrradianceCache::cell_size(int level) const { return root_ / static_cast<float>(1 << level); }

IrradianceCache::Key IrradianceCache::key_of(int level, Vec3 p) const {
  const float s = cell_size(level);
  return Key{level, static_cast<int>(std::floor(p.x / s)), static_cast<int>(std::floor(p.y / s)),
             static_cast<int>(std::floor(p.z / s))};
}

void IrradianceCache::insert(const IrradianceRecord& r) {
  grid_cell_ = 0;  // a frozen grid no longer lists everything
  grid_.clear();
  grid_levels_.clear();
  // Valid where |x - x_i| / R_i < a (up to max_relax * a for relaxed lookups): the deepest level whose cells are
  // at least that wide.
  const float valid = max_relax_ * a_ * r.harmonic_distance;
  int level = 0;
  while (level < 20 && cell_size(level + 1) >= valid) ++level;
  if (std::find(levels_.begin(), levels_.end(), level) == levels_.end()) {
    levels_.push_back(level);
    std::sort(levels_.begin(), levels_.end());
  }
  cells_[key_of(level, r.position)].push_back(static_cast<uint32_t>(records_.size()));
  records_.push_back(r);
}

bool IrradianceCache::lookup(Vec3 x, Vec3 n, RGB& irradiance, float relax) const {
  const float one[1] = {relax};
  return lookup_first(x, n, one, irradiance) == 0;
}

void IrradianceCache::freeze() {
  grid_.clear();
  grid_levels_.clear();
  if (records_.empty()) return;
  // Cells half as wide as the median record's valid radius (measured: narrower is no faster); a record touching
  // more than kMaxCells cells goes to the next coarser grid. (Before, such records were checked by every lookup:
  // on Lost Empire 1726 of 5635 records, 1700 candidates a lookup, ~10 us.)
  constexpr double kMaxCells = 512;
  std::vector<float> radius;
  for (const auto& r : records_) radius.push_back(max_relax_ * a_ * r.harmonic_distance);
  std::vector<float> sorted = radius;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  grid_cell_ = std::max(0.5f * sorted[sorted.size() / 2], 1e-6f * root_);
  for (uint32_t id = 0; id < records_.size(); ++id) {
    const Vec3 p = records_[id].position;
    const float r = radius[id];
    for (int level = 0;; ++level) {
      const float cell = grid_cell_ * static_cast<float>(1 << (2 * level));
      const int lo[3] = {static_cast<int>(std::floor((p.x - r) / cell)), static_cast<int>(std::floor((p.y - r) / cell)),
                         static_cast<int>(std::floor((p.z - r) / cell))};
      const int hi[3] = {static_cast<int>(std::floor((p.x + r) / cell)), static_cast<int>(std::floor((p.y + r) / cell)),
                         static_cast<int>(std::floor((p.z + r) / cell))};
      const double cells = static_cast<double>(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
      if (cells > kMaxCells && level < kMaxGridLevel) continue;
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) grid_[Key{level, x, y, z}].push_back(id);
      if (std::find(grid_levels_.begin(), grid_levels_.end(), level) == grid_levels_.end()) grid_levels_.push_back(level);
      break;
    }
  }
  std::sort(grid_levels_.begin(), grid_levels_.end());
}

template <class Visit>
void IrradianceCache::for_candidates(Vec3 x, Visit&& visit) const {
  if (grid_cell_ > 0) {
    // Frozen: the cell holding x in each grid lists every record of that grid whose sphere might reach it, in
    // record order; the grids' lists are merged by index so that the order stays the record order.
    constexpr size_t kLists = kMaxGridLevel + 1;
    const uint32_t* at[kLists];
    const uint32_t* end[kLists];
    size_t lists = 0;
    for (int level : grid_levels_) {
      const float cell = grid_cell_ * static_cast<float>(1 << (2 * level));
      auto it = grid_.find(Key{level, static_cast<int>(std::floor(x.x / cell)), static_cast<int>(std::floor(x.y / cell)),
                               static_cast<int>(std::floor(x.z / cell))});
      if (it == grid_.end() || it->second.empty()) continue;
      at[lists] = it->second.data();
      end[lists++] = it->second.data() + it->second.size();
    }
    while (lists > 0) {
      size_t first = 0;
      for (size_t l = 1; l < lists; ++l)
        if (*at[l] < *at[first]) first = l;
      visit(records_[*at[first]++]);
      if (at[first] == end[first]) {
        at[first] = at[lists - 1];
        end[first] = end[lists - 1];
        --lists;
      }
    }
    return;
  }
  for (int level : levels_) {
    const Key c = key_of(level, x);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = cells_.find(Key{level, c.x + dx, c.y + dy, c.z + dz});
          if (it == cells_.end()) continue;
          for (uint32_t id : it->second) visit(records_[id]);
        }
  }
}

int IrradianceCache::lookup_first(Vec3 x, Vec3 n, std::span<const float> relax, RGB& irradiance,
                                  uint32_t* records, ElevationBands* bands) const {
  constexpr size_t kMaxBounds = 4;
  const size_t bounds = std::min(relax.size(), kMaxBounds);
  double weight_sum[kMaxBounds] = {};
  uint32_t count[kMaxBounds] = {};
  RGB sum[kMaxBounds] = {};
  ElevationBands band_sum[kMaxBounds] = {};
  if (relax[bounds - 1] > max_relax_ * 1.0001f)
    throw std::invalid_argument("irradiance cache: a lookup wider than the cache was built for");
  const float widest = a_ * relax[bounds - 1];
  for_candidates(x, [&](const IrradianceRecord& r) {
    const Vec3 d = x - r.position;
    // Not from behind: a record does not serve a point that lies behind its tangent plane by more than a surface
    // curving between their normals would put it (about half the distance times the angle between them), plus a
    // little. A parallel surface just behind the record's (the ceiling above a light panel hung under it, the
    // panel's records below) is then another surface, however far the record reaches; a fixed share of R let a
    // panel's records, which see the open room, light the ceiling in the gap above it.
    const float cos_n = std::min(1.0f, dot(n, r.normal));
    const float behind = -dot(d, (n + r.normal) * 0.5f);
    if (behind > 0 && behind > 0.5f * length(d) * std::sqrt(2.0f * std::max(0.0f, 1.0f - cos_n)) + kBehindSlack * r.harmonic_distance)
      return;
    const float error = length(d) / r.harmonic_distance + std::sqrt(std::max(0.0f, 1.0f - cos_n));
    if (error >= widest) return;  // weight 1/error at most 1/a: not valid here
    const float w = 1.0f / std::max(error, 1e-4f);
    const Vec3 nxn = cross(r.normal, n);
    RGB e;
    for (int ch = 0; ch < 3; ++ch) {
      const float base = ch == 0 ? r.irradiance.x : ch == 1 ? r.irradiance.y : r.irradiance.z;
      const float value = base + dot(nxn, r.rotational[ch]) + dot(d, r.translational[ch]);
      (ch == 0 ? e.x : ch == 1 ? e.y : e.z) = std::max(0.0f, value);
    }
    // The record's bands scaled per channel to its extrapolated irradiance (spread evenly where the record had
    // none in that channel and the gradients give some).
    ElevationBands scaled{};
    if (bands) {
      auto scale = [](float band, float base, float to) { return base > 0 ? band * (to / base) : to / kElevationBands; };
      for (size_t j = 0; j < scaled.size(); ++j)
        scaled[j] = RGB{scale(r.bands[j].x, r.irradiance.x, e.x), scale(r.bands[j].y, r.irradiance.y, e.y),
                        scale(r.bands[j].z, r.irradiance.z, e.z)};
    }
    for (size_t b = 0; b < bounds; ++b) {
      if (error >= a_ * relax[b]) continue;
      sum[b] += e * w;
      weight_sum[b] += w;
      ++count[b];
      if (bands)
        for (size_t j = 0; j < band_sum[b].size(); ++j) band_sum[b][j] += scaled[j] * w;
    }
  });
  for (size_t b = 0; b < bounds; ++b)
    if (weight_sum[b] > 0) {
      const float inverse = static_cast<float>(1.0 / weight_sum[b]);
      irradiance = sum[b] * inverse;
      if (records) *records = count[b];
      if (bands)
        for (size_t j = 0; j < bands->size(); ++j) (*bands)[j] = band_sum[b][j] * inverse;
      return static_cast<int>(b);
    }
  return -1;
}

std::string IrradianceCache::serialize(std::span<const IrradianceRecord> records) {
  std::string bytes(records.size_bytes(), '\0');
  if (!records.empty()) std::memcpy(bytes.data(), records.data(), bytes.size());
  return bytes;
}

bool IrradianceCache::deserialize(const std::string& bytes, std::vector<IrradianceRecord>& out) {
  if (bytes.size() % sizeof(IrradianceRecord) != 0) return false;
  const size_t n = bytes.size() / sizeof(IrradianceRecord);
  const size_t at = out.size();
  out.resize(at + n);
  if (n) std::memcpy(out.data() + at, bytes.data(), bytes.size());
  return true;
}

}  // namespace lf
