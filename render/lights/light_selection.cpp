#include "render/lights/light_selection.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "render/byte_io.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/scene/surface.hpp"

namespace lf {
namespace {

inline constexpr uint64_t kSelectionStream = 8;  // next to sampler.hpp's streams
// The moment maps' key for the environment: after every light index.
inline constexpr uint32_t kEnvironmentEntry = UINT32_MAX;

struct Candidate {
  Vec3 origin;  // the shadow rays' start, above the face
  Vec3 x, ns, ng;
};

// Axis and sign of a normal's largest component: 0..5.
uint64_t facing_of(Vec3 n) {
  const float ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
  if (ax >= ay && ax >= az) return n.x >= 0 ? 0 : 1;
  if (ay >= az) return n.y >= 0 ? 2 : 3;
  return n.z >= 0 ? 4 : 5;
}

}  // namespace

LightSelectionOptions light_selection_options(const ParamTable& p, uint64_t seed) {
  LightSelectionOptions o;
  o.cell = static_cast<float>(p.get_float("learned_cell", o.cell, 1e-5, 1));
  o.samples = static_cast<int>(p.get_int("learned_samples", o.samples, 2, 1 << 20));
  o.stride = static_cast<int>(p.get_int("learned_stride", o.stride, 1, 64));
  o.share = static_cast<float>(p.get_float("learned_share", o.share, 0, 0.99));
  o.seed = seed;
  return o;
}

LightSampling read_light_sampling(const ParamTable& p) {
  const std::string s = p.get_string("light_sampling", "tree", {"tree", "power", "learned"});
  return s == "learned" ? LightSampling::learned : s == "power" ? LightSampling::power : LightSampling::tree;
}

bool learns_lights(const Value::Map& params) {
  try {
    return read_light_sampling(ParamTable(params, "")) == LightSampling::learned;
  } catch (const ParamError&) {
    return false;  // a bad value is the op's to refuse, with its name
  }
}

void LightSelection::add_stats(Value::Map& m) const {
  // The cells as they stand (one learned again counts once).
  size_t cells = 0, lights = 0;
  for (const auto& [key, known] : index_)
    if (known.cell >= 0) ++cells, lights += cells_[static_cast<size_t>(known.cell)].count;
  m["learned_cells"] = static_cast<int64_t>(cells);
  m["learned_lights_per_cell"] = cells == 0 ? 0.0 : static_cast<double>(lights) / static_cast<double>(cells);
  m["learned_blocked"] = shadow_rays_ ? static_cast<double>(blocked_rays_) / static_cast<double>(shadow_rays_) : 0.0;
}

uint64_t LightSelection::key_of(Vec3 x, Vec3 n) const {
  // 20 bits per axis around the origin: +-2^19 cells, far more than a scene holds at the sizes allowed.
  auto axis = [&](float v) {
    const double c = std::floor(static_cast<double>(v) * inverse_size_) + (1 << 19);
    return static_cast<uint64_t>(std::clamp(c, 0.0, static_cast<double>((1 << 20) - 1)));
  };
  return (axis(x.x) << 43) | (axis(x.y) << 23) | (axis(x.z) << 3) | facing_of(n);
}

int32_t LightSelection::cell_of(Vec3 x, Vec3 n) const {
  if (cells_.empty()) return -1;
  const auto it = index_.find(key_of(x, n));
  return it == index_.end() ? -1 : it->second.cell;
}

void LightSelection::pick(int32_t cell, float u, size_t& light, float& probability, float* remainder) const {
  const Cell& c = cells_[static_cast<size_t>(cell)];
  const float* begin = cdf_.data() + c.first;
  const float* end = begin + c.count;
  const float* at = std::min(std::upper_bound(begin, end, u), end - 1);
  const size_t i = static_cast<size_t>(at - cdf_.data());
  light = lights_[i];
  probability = probability_[i];
  if (remainder) {
    const float below = at == begin ? 0.0f : at[-1];
    *remainder = std::clamp((u - below) / probability, 0.0f, 0x1.fffffep-1f);
  }
}

float LightSelection::probability(int32_t cell, size_t light) const {
  const Cell& c = cells_[static_cast<size_t>(cell)];
  const uint32_t* begin = lights_.data() + c.first;
  const uint32_t* end = begin + c.count;
  const uint32_t* at = std::lower_bound(begin, end, static_cast<uint32_t>(light));
  return at != end && *at == light ? probability_[static_cast<size_t>(at - lights_.data())] : 0.0f;
}

namespace {

// Sends this replica's cells to the others and takes theirs: afterwards `moment` holds every cell's and the
// counts every replica's, exactly what one process learning alone would hold. A share, as bytes (byte_io): u64
// shadow rays, u64 blocked, then per cell learned: u32 cell, u32 light count, that many (u32 light, f64 moment).
Task exchange_moments(Exchange& exchange, const std::vector<uint32_t>& mine,
                      std::vector<std::map<uint32_t, double>>& moment, uint64_t& shadow_rays, uint64_t& blocked_rays) {
  std::string part;
  bytes::put(part, shadow_rays);
  bytes::put(part, blocked_rays);
  for (uint32_t c : mine) {
    bytes::put(part, c);
    bytes::put(part, static_cast<uint32_t>(moment[c].size()));
    for (const auto& [light, m] : moment[c]) {
      bytes::put(part, light);
      bytes::put(part, m);
    }
  }
  std::vector<std::string> parts;
  co_await exchange.all_gather(std::move(part), &parts);
  shadow_rays = blocked_rays = 0;
  const LightOpError malformed("learned lights: a replica's share is malformed");
  for (const std::string& p : parts) {
    bytes::Reader in(p);
    uint64_t shadow = 0, blocked = 0;
    if (!in.u64(shadow) || !in.u64(blocked)) throw malformed;
    shadow_rays += shadow;
    blocked_rays += blocked;
    while (!in.done()) {
      uint32_t c = 0, lights = 0;
      if (!in.u32(c) || !in.u32(lights) || c >= moment.size() || !in.room(lights, 12)) throw malformed;
      auto& cell = moment[c];
      cell.clear();
      for (uint32_t i = 0; i < lights; ++i) {
        uint32_t light = 0;
        double m = 0;
        if (!in.u32(light) || !in.f64(m)) throw malformed;
        cell[light] = m;
      }
    }
  }
}

}  // namespace

Task LightSelection::build(const SceneContext& ctx, const LightSelectionOptions& options, LightSelection& out,
                           const char* op) {
  out = LightSelection{};
  out.share_ = options.share;
  out.inverse_size_ = 1.0f / (options.cell * ctx.scene->bounds().diagonal());
  co_await out.extend(ctx, options, op);
}

Task LightSelection::extend(const SceneContext& ctx, const LightSelectionOptions& options, const char* op) {
  if (!ctx.camera) throw LightOpError(std::string(op) + ": light_sampling = \"learned\" needs the farm's camera");
  const Scene& scene = *ctx.scene;
  View view{static_cast<uint32_t>(cells_.size()), static_cast<uint32_t>(dark_.size())};
  if (scene.emitters().empty()) {
    views_.push_back(view);
    co_return;
  }

  // Where the camera looks: the first hit through every stride-th pixel centre, in pixel order.
  std::vector<Ray> rays;
  for (int y = 0; y < ctx.height; y += options.stride)
    for (int x = 0; x < ctx.width; x += options.stride)
      rays.push_back(ctx.camera->ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f));
  std::vector<Hit> hits(rays.size());
  if (!rays.empty()) co_await trace_intersect(ctx, rays, hits);
  std::vector<Candidate> candidates;
  std::vector<std::pair<uint64_t, uint32_t>> keyed;  // (cell key, candidate)
  for (size_t r = 0; r < rays.size(); ++r) {
    if (!hits[r].valid()) continue;
    const uint32_t tri = hits[r].triangle;
    const Material& m = scene.material(scene.material_of(tri));
    if (m.specular() || (is_black(m.kd) && is_black(m.ks))) continue;
    const Vec3 wo = -rays[r].direction;
    const Vec3 x = rays[r].origin + rays[r].direction * hits[r].t;
    const SurfacePoint sp = surface_at(scene, tri, x, wo);
    keyed.emplace_back(key_of(x, sp.ns), static_cast<uint32_t>(candidates.size()));
    candidates.push_back(Candidate{scene.ray_origin(tri, x, sp.ng), x, sp.ns, sp.ng});
  }
  std::sort(keyed.begin(), keyed.end());

  // The cells to learn, in key order, their points' range in keyed and their centre: those never learned, and
  // those learned from far fewer points than this view has in them or from points around another centre.
  std::vector<std::pair<size_t, size_t>> cell_ranges;
  std::vector<Vec3> centres;
  for (size_t i = 0; i < keyed.size();) {
    size_t j = i;
    Vec3 sum{};
    for (; j < keyed.size() && keyed[j].first == keyed[i].first; ++j) sum = sum + candidates[keyed[j].second].x;
    const Vec3 centre = sum * (1.0f / static_cast<float>(j - i));
    const auto known = index_.find(keyed[i].first);
    if (known == index_.end() ||
        learns_again(j - i, centre, known->second.points, known->second.centre, inverse_size_)) {
      cell_ranges.emplace_back(i, j);
      centres.push_back(centre);
    }
    i = j;
  }

  // `samples` light samples from each cell's points (taken in turn) through the tree, shadow rays included. Light
  // l's chance in the cell is proportional to the root mean square of what its samples bring over their chance,
  // (E[f_l^2 / p_l])^(1/2): that is the choice with the least variance for a fixed split among lights (each light's
  // own point sampling given). It leans towards partly hidden lights more than their mean would: their samples are
  // all or nothing. Measured on Lost Empire, the mean instead gave 2 % more error, and a second round drawn through
  // the first round's mixture 27 % more (docs/decisions.md, "Lights learned where the camera looks").
  const size_t n = static_cast<size_t>(std::max(1, options.samples));
  const float base_share = scene.environment_share();
  const size_t n_environment = base_share > 0 && base_share < 1 ? std::max<size_t>(1, n / 4) : 0;
  std::vector<std::map<uint32_t, double>> moment(cell_ranges.size());  // per cell and light: sum of p (f / p)^2
  // A pool's replicas each learn every replicas-th cell; a cell's samples are seeded by the cell alone.
  const size_t replicas = ctx.exchange ? static_cast<size_t>(std::max(1, ctx.replica_count)) : 1;
  const size_t replica = replicas > 1 ? static_cast<size_t>(ctx.replica_index) : 0;
  std::vector<uint32_t> mine;
  for (size_t c = replica; c < cell_ranges.size(); c += replicas) mine.push_back(static_cast<uint32_t>(c));
  const size_t batch_cells = 64;
  for (size_t batch = 0; batch < mine.size(); batch += batch_cells) {
    ctx.report("learning lights", batch, mine.size());
    struct Pending {
      uint32_t cell, light;
      float value, chance;  // f / p, and p (the tree's chance of the light)
    };
    std::vector<Pending> pending;
    std::vector<Ray> shadow;
    for (size_t b = batch; b < std::min(mine.size(), batch + batch_cells); ++b) {
      const size_t c = mine[b];
      const auto [first, last] = cell_ranges[c];
      const uint64_t key = keyed[first].first;
      for (size_t s = 0; s < n; ++s) {
        const Candidate& p = candidates[keyed[first + s % (last - first)].second];
        Rng rng(splitmix64(key ^ (options.seed << 40)) ^ s, kSelectionStream);
        size_t e = 0;
        float p_light = 0;
        if (!scene.light_tree().pick(p.x, p.ns, rng.uniform(), e, p_light)) continue;
        const LightSample ls = light_sample_at(scene, e, p_light, rng.uniform2());
        if (is_black(ls.radiance)) continue;
        const Vec3 d = ls.point - p.x;
        const float dist2 = dot(d, d);
        if (!(dist2 > 0)) continue;
        const Vec3 wi = d / std::sqrt(dist2);
        const float cos_y = ls.is_point ? 1.0f : -dot(ls.normal, wi);
        if (!above_both(wi, p.ns, p.ng) || cos_y <= 0) continue;
        const float value = average(ls.radiance_towards(p.x)) * dot(p.ns, wi) * cos_y / (dist2 * ls.pdf_area);
        if (!(value > 0) || !std::isfinite(value)) continue;
        const Vec3 target = ls.is_point ? ls.point : scene.ray_origin(ls.triangle, ls.point, ls.normal);
        const Vec3 to_light = target - p.origin;
        const float span = length(to_light);
        if (!(span > 0)) continue;
        pending.push_back({static_cast<uint32_t>(c), static_cast<uint32_t>(e), value, p_light});
        shadow.push_back(Ray{p.origin, to_light / span, 0.0f, span});
      }
      // The environment's own samples, a quarter as many, weighed n / n_env so that its moment is on the tree
      // lights' footing: each cell then learns its share of the samples too (a room's sky through a window).
      for (size_t s = 0; s < n_environment; ++s) {
        const Candidate& p = candidates[keyed[first + s % (last - first)].second];
        Rng rng(splitmix64(key ^ (options.seed << 40)) ^ s, kSelectionStream ^ 0xe4b);
        const float u = rng.uniform(), v = rng.uniform();
        const Environment::Sample d = scene.environment()->sample(u, v);
        if (!(d.pdf > 0) || is_black(d.radiance) || !above_both(d.wi, p.ns, p.ng)) continue;
        const float value = average(d.radiance) * dot(p.ns, d.wi) / d.pdf;
        if (!(value > 0) || !std::isfinite(value)) continue;
        pending.push_back({static_cast<uint32_t>(c), kEnvironmentEntry, value,
                           static_cast<float>(n) / static_cast<float>(n_environment)});
        shadow.push_back(Ray{p.origin, d.wi});
      }
    }
    std::vector<uint8_t> blocked(shadow.size());
    if (!shadow.empty()) co_await trace_occluded(ctx, shadow, blocked);
    view.shadow_rays += shadow.size();
    for (size_t k = 0; k < pending.size(); ++k) {
      if (blocked[k]) {
        ++view.blocked_rays;
        continue;
      }
      // Samples of light l come with chance p_l: p_l (f / p)^2 averages to l's own second moment, whatever p_l.
      const double v = pending[k].value;
      moment[pending[k].cell][pending[k].light] += v * v * pending[k].chance;
    }
  }
  if (replicas > 1 && !cell_ranges.empty()) co_await exchange_moments(*ctx.exchange, mine, moment, view.shadow_rays, view.blocked_rays);
  for (size_t c = 0; c < cell_ranges.size(); ++c) {
    const auto [first, last] = cell_ranges[c];
    add_cell(keyed[first].first, static_cast<uint32_t>(std::min<size_t>(last - first, UINT32_MAX)), centres[c], moment[c]);
  }
  view.cells_end = static_cast<uint32_t>(cells_.size());
  view.dark_end = static_cast<uint32_t>(dark_.size());
  shadow_rays_ += view.shadow_rays;
  blocked_rays_ += view.blocked_rays;
  views_.push_back(view);
  ctx.report("learning lights", mine.size(), std::max<size_t>(mine.size(), 1));
}

void LightSelection::add_cell(uint64_t key, uint32_t points, Vec3 centre, std::map<uint32_t, double>& moment) {
  // The environment's entry (the map's last key) is its share of the cell, not a light of the distribution.
  double environment = 0;
  if (auto it = moment.find(kEnvironmentEntry); it != moment.end()) {
    environment = std::sqrt(it->second);
    moment.erase(it);
  }
  double sum = 0;
  for (auto& [light, m] : moment) sum += (m = std::sqrt(m));
  if (!(sum > 0)) return append_dark(key, points, centre);
  std::vector<uint32_t> lights;
  std::vector<float> cdf;
  double running = 0;
  for (const auto& [light, m] : moment) {
    running += m;
    lights.push_back(light);
    cdf.push_back(static_cast<float>(running / sum));
  }
  cdf.back() = 1.0f;
  append_cell(key, points, centre, static_cast<float>(environment / (environment + sum)), lights, cdf);
}

void LightSelection::append_cell(uint64_t key, uint32_t points, Vec3 centre, float environment,
                                 std::span<const uint32_t> lights, std::span<const float> cdf) {
  Cell cell{static_cast<uint32_t>(lights_.size()), static_cast<uint32_t>(lights.size()), environment, points, centre};
  lights_.insert(lights_.end(), lights.begin(), lights.end());
  cdf_.insert(cdf_.end(), cdf.begin(), cdf.end());
  // Each light's chance as the difference of the sums pick() compares u with, so that it is what pick() does.
  for (size_t i = cell.first; i < cdf_.size(); ++i)
    probability_.push_back(cdf_[i] - (i == cell.first ? 0.0f : cdf_[i - 1]));
  index_[key] = Known{static_cast<int32_t>(cells_.size()), points, centre};
  cells_.push_back(cell);
  keys_.push_back(key);
}

void LightSelection::append_dark(uint64_t key, uint32_t points, Vec3 centre) {
  index_[key] = Known{-1, points, centre};
  dark_.push_back(Dark{key, points, centre});
}

namespace {
constexpr std::string_view kStateTag = "LFLIGHTSEL2";

void put_centre(std::string& out, Vec3 c) {
  bytes::put(out, c.x);
  bytes::put(out, c.y);
  bytes::put(out, c.z);
}
bool read_centre(bytes::Reader& in, Vec3& c) {
  return in.f32(c.x) && in.f32(c.y) && in.f32(c.z) && std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
}
}

// Tag, f32 inverse cell size, f32 share, then a block a view: u64 shadow rays, u64 blocked, u32 cells, per cell
// (u64 key, u32 points, 3 f32 centre, f32 environment, u32 lights, that many (u32 light, f32 running sum)), u32
// dark keys, that many (u64 key, u32 points, 3 f32 centre).
std::string LightSelection::state() const {
  std::string out(kStateTag);
  bytes::put(out, inverse_size_);
  bytes::put(out, share_);
  uint32_t cell = 0, dark = 0;
  for (const View& v : views_) {
    bytes::put(out, v.shadow_rays);
    bytes::put(out, v.blocked_rays);
    bytes::put(out, v.cells_end - cell);
    for (; cell < v.cells_end; ++cell) {
      const Cell& c = cells_[cell];
      bytes::put(out, keys_[cell]);
      bytes::put(out, c.points);
      put_centre(out, c.centre);
      bytes::put(out, c.environment);
      bytes::put(out, c.count);
      for (uint32_t i = c.first; i < c.first + c.count; ++i) {
        bytes::put(out, lights_[i]);
        bytes::put(out, cdf_[i]);
      }
    }
    bytes::put(out, v.dark_end - dark);
    for (; dark < v.dark_end; ++dark) {
      bytes::put(out, dark_[dark].key);
      bytes::put(out, dark_[dark].points);
      put_centre(out, dark_[dark].centre);
    }
  }
  return out;
}

void LightSelection::restore(std::string_view state, const Scene& scene, const char* op) {
  const size_t light_count = scene.emitters().size() + scene.point_lights().size();
  const std::string what = std::string(op) + ": the kept learned lights ";
  bytes::Reader in(state);
  std::string tag;
  float inverse_size = 0, share = 0;
  if (!in.str(tag, static_cast<uint32_t>(kStateTag.size())) || tag != kStateTag || !in.f32(inverse_size) || !in.f32(share))
    throw LightOpError(what + "are not ones this build reads (remove the job folder's setups/ to replay the views)");
  if (inverse_size != inverse_size_ || share != share_)
    throw LightOpError(what + "were learned with other settings");
  LightSelection out;
  out.inverse_size_ = inverse_size_;
  out.share_ = share_;
  const LightOpError malformed(what + "are cut short or hold what no learning makes");
  std::vector<uint32_t> lights;
  std::vector<float> cdf;
  while (!in.done()) {
    View v;
    uint32_t cells = 0, dark = 0;
    if (!in.u64(v.shadow_rays) || !in.u64(v.blocked_rays) || v.blocked_rays > v.shadow_rays || !in.u32(cells) ||
        !in.room(cells, 32))
      throw malformed;
    // A key learned before comes again only learned from enough more points, or from points around another centre.
    auto relearned = [&](uint64_t key, uint32_t points, Vec3 centre) {
      const auto known = out.index_.find(key);
      return known == out.index_.end() ||
             learns_again(points, centre, known->second.points, known->second.centre, out.inverse_size_);
    };
    for (uint32_t c = 0; c < cells; ++c) {
      uint64_t key = 0;
      float environment = 0;
      uint32_t count = 0, points = 0;
      Vec3 centre;
      if (!in.u64(key) || !in.u32(points) || !read_centre(in, centre) || !in.f32(environment) || !in.u32(count) ||
          count == 0 || !in.room(count, 8))
        throw malformed;
      if (!(environment == -1.0f || (environment >= 0 && environment <= 1)) || points == 0 ||
          !relearned(key, points, centre))
        throw malformed;
      lights.resize(count);
      cdf.resize(count);
      for (uint32_t i = 0; i < count; ++i) {
        if (!in.u32(lights[i]) || !in.f32(cdf[i])) throw malformed;
        // Lights ascending and known; sums never falling, ending at 1 (a faint light's may round to no step).
        if (lights[i] >= light_count || (i > 0 && lights[i] <= lights[i - 1])) throw malformed;
        if (!(cdf[i] >= (i > 0 ? cdf[i - 1] : 0.0f)) || !(cdf[i] <= 1)) throw malformed;
      }
      if (cdf.back() != 1.0f) throw malformed;
      out.append_cell(key, points, centre, environment, lights, cdf);
    }
    if (!in.u32(dark) || !in.room(dark, 24)) throw malformed;
    for (uint32_t d = 0; d < dark; ++d) {
      uint64_t key = 0;
      uint32_t points = 0;
      Vec3 centre;
      if (!in.u64(key) || !in.u32(points) || !read_centre(in, centre) || points == 0 || !relearned(key, points, centre))
        throw malformed;
      out.append_dark(key, points, centre);
    }
    v.cells_end = static_cast<uint32_t>(out.cells_.size());
    v.dark_end = static_cast<uint32_t>(out.dark_.size());
    out.shadow_rays_ += v.shadow_rays;
    out.blocked_rays_ += v.blocked_rays;
    out.views_.push_back(v);
  }
  *this = std::move(out);
}

}  // namespace lf
