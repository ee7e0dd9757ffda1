#include "radiosity/solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/tracing/tracer.hpp"

namespace lf::radiosity {

Shooter make_shooter(const Mesh& mesh, uint32_t patch, RGB unshot, int samples) {
  Shooter s;
  s.patch = patch;
  s.surface = mesh.patches[patch].surface;
  s.polygon = mesh.patches[patch].polygon;
  s.unshot = unshot;
  const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(samples)))));
  s.parts = tile(s.polygon, k);
  for (const auto& p : s.parts) s.targets.push_back(p.centroid());
  return s;
}

Segment visibility_segment(Vec3 point, Vec3 normal, const Shooter& shooter, int m, float epsilon) {
  return {point + normal * epsilon, shooter.targets[static_cast<size_t>(m)] + shooter.polygon.normal() * epsilon};
}

Part::Part(const Mesh& mesh, std::vector<uint32_t> patches, SolverSettings settings)
    : mesh_(mesh), patches_(std::move(patches)), settings_(settings) {
  std::sort(patches_.begin(), patches_.end());
  split_threshold_ = static_cast<float>(settings_.subdivide * mesh.mean_emission());
  local_of_patch_.assign(mesh.patches.size(), -1);
  for (size_t i = 0; i < patches_.size(); ++i) local_of_patch_[patches_[i]] = static_cast<int32_t>(i);
  reset();
}

void Part::reset() {
  elements_.clear();
  patch_elements_.assign(patches_.size(), {});
  for (size_t i = 0; i < patches_.size(); ++i) {
    const Patch& p = mesh_.patches[patches_[i]];
    for (const auto& piece : tile(p.polygon, p.element_tiles)) {
      patch_elements_[i].push_back(static_cast<uint32_t>(elements_.size()));
      elements_.push_back({piece, patches_[i], 0, true, p.emission, p.emission});
    }
  }
  shooter_ = nullptr;
  round_.clear();
  shot_ = {};
}

Status Part::restore(std::vector<Element> leaves) {
  std::vector<std::vector<uint32_t>> lists(patches_.size());
  for (uint32_t i = 0; i < leaves.size(); ++i) {
    const Element& e = leaves[i];
    if (e.patch >= local_of_patch_.size() || local_of_patch_[e.patch] < 0)
      return make_error("a checkpoint element of patch " + std::to_string(e.patch) + ", which this part does not hold");
    if (!e.leaf || e.depth < 0 || e.depth > settings_.max_depth) return make_error("a checkpoint element that cannot be");
    lists[static_cast<size_t>(local_of_patch_[e.patch])].push_back(i);
  }
  elements_ = std::move(leaves);
  patch_elements_ = std::move(lists);
  shooter_ = nullptr;
  round_.clear();
  shot_ = {};
  return Ok{};
}

size_t Part::leaf_count() const {
  size_t n = 0;
  for (const auto& e : elements_) n += e.leaf ? 1 : 0;
  return n;
}

Candidate Part::best() const {
  Candidate best;
  for (size_t i = 0; i < patches_.size(); ++i) {
    RGB sum;
    for (uint32_t e : patch_elements_[i])
      if (elements_[e].leaf) sum += elements_[e].unshot * elements_[e].polygon.area();
    const float area = mesh_.patches[patches_[i]].polygon.area();
    Candidate c{patches_[i], static_cast<double>(average(sum)), sum / area};
    if (c.beats(best)) best = c;
  }
  return best;
}

double Part::unshot_power() const {
  double total = 0;
  for (const auto& e : elements_)
    if (e.leaf) total += static_cast<double>(e.polygon.area()) * average(e.unshot);
  return total;
}

void Part::begin_shot(const Shooter& shooter) {
  shooter_ = &shooter;
  shot_ = {};
  if (shooter.patch < local_of_patch_.size() && local_of_patch_[shooter.patch] >= 0)
    for (uint32_t e : patch_elements_[static_cast<size_t>(local_of_patch_[shooter.patch])]) elements_[e].unshot = RGB{};
  std::vector<uint32_t> all;
  for (const auto& list : patch_elements_)
    for (uint32_t e : list)
      // A black receiver (mirrors, glass) reflects nothing: what it receives changes no radiosity.
      if (elements_[e].leaf && mesh_.patches[elements_[e].patch].surface != shooter.surface &&
          !is_black(mesh_.patches[elements_[e].patch].reflectance))
        all.push_back(e);
  prepare_round(std::move(all));
}

void Part::prepare_round(std::vector<uint32_t> elements) {
  round_ = std::move(elements);
  round_first_sample_.clear();
  sample_point_.clear();
  sample_normal_.clear();
  sample_mask_.clear();
  sample_factor_.clear();
  const size_t m_count = shooter_->parts.size();
  for (uint32_t e : round_) {
    round_first_sample_.push_back(static_cast<uint32_t>(sample_point_.size()));
    const Polygon& poly = elements_[e].polygon;
    const Vec3 n = poly.normal();
    for (Vec3 x : sample_points(poly)) {
      uint64_t mask = 0;
      for (size_t m = 0; m < m_count; ++m) {
        const double f = point_to_polygon(x, n, shooter_->parts[m]);
        sample_factor_.push_back(f);
        if (f > 0) mask |= uint64_t{1} << m;
      }
      sample_point_.push_back(x);
      sample_normal_.push_back(n);
      sample_mask_.push_back(mask);
      if (mask) {
        ++shot_.samples;
        shot_.rays_requested += static_cast<uint64_t>(std::popcount(mask));
      }
    }
  }
  round_first_sample_.push_back(static_cast<uint32_t>(sample_point_.size()));
}

void Part::finish_round(std::span<const uint64_t> visible) {
  if (visible.size() != sample_point_.size()) throw std::logic_error("radiosity: visibility for the wrong samples");
  const size_t m_count = shooter_->parts.size();
  const RGB shot = shooter_->unshot;
  std::vector<uint32_t> next;
  for (size_t r = 0; r < round_.size(); ++r) {
    const uint32_t e = round_[r];
    const uint32_t first = round_first_sample_[r], last = round_first_sample_[r + 1];
    double lo = INFINITY, hi = -INFINITY, sum = 0;
    for (uint32_t s = first; s < last; ++s) {
      double f = 0;
      const uint64_t bits = visible[s] & sample_mask_[s];
      for (size_t m = 0; m < m_count; ++m)
        if (bits >> m & 1) f += sample_factor_[s * m_count + m];
      lo = std::min(lo, f);
      hi = std::max(hi, f);
      sum += f;
    }
    Element& el = elements_[e];
    const RGB rho = mesh_.patches[el.patch].reflectance;
    if (split_threshold_ > 0 && el.depth < settings_.max_depth &&
        (hi - lo) * average(rho * shot) > static_cast<double>(split_threshold_)) {
      // Too coarse for this shadow or highlight: the children sample the same shooter themselves.
      el.leaf = false;
      ++shot_.elements_split;
      const size_t local = static_cast<size_t>(local_of_patch_[el.patch]);
      const Element parent = el;
      for (const auto& piece : split4(parent.polygon)) {
        patch_elements_[local].push_back(static_cast<uint32_t>(elements_.size()));
        next.push_back(static_cast<uint32_t>(elements_.size()));
        elements_.push_back({piece, parent.patch, parent.depth + 1, true, parent.radiosity, parent.unshot});
      }
      continue;
    }
    const float factor = static_cast<float>(sum / static_cast<double>(last - first));
    const RGB irradiance = shot * factor;
    const RGB gain = rho * irradiance;
    el.radiosity += gain;
    el.unshot += gain;
    shot_.power_arrived += static_cast<double>(el.polygon.area()) * average(irradiance);
  }
  if (next.empty()) {
    round_.clear();
    return;
  }
  prepare_round(std::move(next));
}

std::vector<uint64_t> trace_round(const Part& part, const Shooter& shooter, float epsilon, const SegmentTracer& trace) {
  std::vector<uint64_t> visible(part.sample_count());
  std::vector<Segment> segments;
  std::vector<std::pair<uint32_t, uint32_t>> which;  // sample, sub-area
  for (size_t i = 0; i < part.sample_count(); ++i) {
    const uint64_t mask = part.sample_mask(i);
    visible[i] = mask;
    for (int m = 0; m < 64; ++m)
      if (mask >> m & 1) {
        segments.push_back(visibility_segment(part.sample_point(i), part.sample_normal(i), shooter, m, epsilon));
        which.emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(m));
      }
  }
  std::vector<uint8_t> occluded(segments.size(), 0);
  if (!segments.empty()) trace(segments, occluded);
  for (size_t k = 0; k < segments.size(); ++k)
    if (occluded[k]) visible[which[k].first] &= ~(uint64_t{1} << which[k].second);
  return visible;
}

SerialResult solve_serial(const Mesh& mesh, const SolverSettings& settings, const SegmentTracer& trace) {
  std::vector<uint32_t> all(mesh.patches.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  Part part(mesh, all, settings);
  SerialResult result;
  const double emitted = mesh.emitted_power();
  result.unshot_fraction = emitted > 0 ? part.unshot_power() / emitted : 0;
  for (int it = 0; it < settings.max_iterations && result.unshot_fraction >= settings.converge; ++it) {
    const Candidate c = part.best();
    if (c.patch == UINT32_MAX || !(c.power > 0)) break;
    const Shooter shooter = make_shooter(mesh, c.patch, c.unshot, settings.shooter_samples);
    part.begin_shot(shooter);
    while (part.round_ready()) part.finish_round(trace_round(part, shooter, mesh.epsilon, trace));
    result.unshot_fraction = part.unshot_power() / emitted;
    result.iterations.push_back({c.patch, c.power, part.shot().power_arrived, result.unshot_fraction,
                                 part.shot().elements_split});
  }
  result.elements = part.elements();
  return result;
}

struct SceneVisibility::Impl {
  Scene scene;
  std::unique_ptr<RayTracer> tracer;
};

static std::vector<uint32_t> every_surface(const Mesh& mesh) {
  std::vector<uint32_t> all(mesh.surfaces.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  return all;
}

SceneVisibility::SceneVisibility(const Mesh& mesh) : SceneVisibility(mesh, every_surface(mesh)) {}

SceneVisibility::SceneVisibility(const Mesh& mesh, std::span<const uint32_t> surfaces) : impl_(std::make_unique<Impl>()) {
  const uint32_t any = impl_->scene.add_material({"blocker", {}, {}});
  for (uint32_t s : surfaces) {
    const Polygon& p = mesh.surfaces[s].polygon;
    if (p.count == 4)
      impl_->scene.add_quad(p.v[0], p.v[1], p.v[2], p.v[3], any);
    else
      impl_->scene.add_triangle(p.v[0], p.v[1], p.v[2], any);
  }
  if (impl_->scene.triangle_count() > 0) impl_->tracer = std::make_unique<RayTracer>(impl_->scene);
}

SceneVisibility::~SceneVisibility() = default;

void SceneVisibility::operator()(std::span<const Segment> segments, std::span<uint8_t> occluded) const {
  if (!impl_->tracer) {
    std::fill(occluded.begin(), occluded.end(), 0);
    return;
  }
  std::vector<Ray> rays(segments.size());
  for (size_t i = 0; i < segments.size(); ++i) rays[i] = {segments[i].from, segments[i].to - segments[i].from, 0.0f, 1.0f};
  impl_->tracer->occluded(rays, occluded);
}

}  // namespace lf::radiosity
