#include "render/tracing/partition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "render/shading/sampler.hpp"

namespace lf {

namespace {

// The estimate of a triangle's share of ray work without measurement: half its share of the surface area, half its
// share of the triangle count. Sums to 1.
std::vector<double> area_and_count_costs(const Scene& scene) {
  const size_t n = scene.triangle_count();
  double area = 0;
  for (size_t t = 0; t < n; ++t) area += scene.area(static_cast<uint32_t>(t));
  std::vector<double> cost(n);
  for (size_t t = 0; t < n; ++t)
    cost[t] = 0.5 * (area > 0 ? scene.area(static_cast<uint32_t>(t)) / area : 0) + 0.5 / static_cast<double>(n);
  return cost;
}

Vec3 centroid(const Scene& scene, uint32_t t) {
  return (scene.vertex(t, 0) + scene.vertex(t, 1) + scene.vertex(t, 2)) * (1.0f / 3.0f);
}

struct Splitter {
  const Scene& scene;
  std::vector<double> cost;
  std::vector<Vec3> centre;
  std::vector<ScenePart> out;

  void split(std::vector<uint32_t>::iterator begin, std::vector<uint32_t>::iterator end, int parts) {
    parts = static_cast<int>(std::min<ptrdiff_t>(parts, end - begin));
    if (parts <= 1) {
      ScenePart part;
      part.triangles.assign(begin, end);
      std::sort(part.triangles.begin(), part.triangles.end());
      std::vector<Vec3> corners;
      corners.reserve(3 * part.triangles.size());
      for (uint32_t t : part.triangles) {
        for (int c = 0; c < 3; ++c) corners.push_back(scene.vertex(t, c));
        part.cost += cost[t];
      }
      part.bounds = bounds_of(corners);
      out.push_back(std::move(part));
      return;
    }
    Vec3 lo = centre[*begin], hi = lo;
    for (auto it = begin; it != end; ++it) {
      const Vec3 c = centre[*it];
      lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
      hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
    }
    const Vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    std::sort(begin, end, [&](uint32_t a, uint32_t b) {
      const float ca = centre[a][axis], cb = centre[b][axis];
      return ca < cb || (ca == cb && a < b);
    });
    const int left_parts = parts / 2;
    double total = 0;
    for (auto it = begin; it != end; ++it) total += cost[*it];
    const double target = total * left_parts / parts;
    // Each side keeps at least as many triangles as it must make parts.
    auto cut = begin + left_parts;
    double running = 0;
    for (auto it = begin; it != end; ++it) {
      running += cost[*it];
      if (running >= target) {
        cut = it + 1;
        break;
      }
    }
    cut = std::clamp(cut, begin + left_parts, end - (parts - left_parts));
    split(begin, cut, left_parts);
    split(cut, end, parts - left_parts);
  }
};

}  // namespace

std::vector<ScenePart> partition_scene(const Scene& scene, int parts, std::span<const double> weights) {
  const size_t n = scene.triangle_count();
  Splitter s{scene, std::vector<double>(n), std::vector<Vec3>(n), {}};
  if (!weights.empty() && weights.size() == n) {
    const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
    for (size_t t = 0; t < n; ++t) s.cost[t] = sum > 0 ? weights[t] / sum : 1.0 / static_cast<double>(n);
  } else {
    s.cost = area_and_count_costs(scene);
  }
  for (size_t t = 0; t < n; ++t) s.centre[t] = centroid(scene, static_cast<uint32_t>(t));
  std::vector<uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  if (n > 0) s.split(ids.begin(), ids.end(), std::max(1, parts));
  return std::move(s.out);
}

namespace {

// The probe rays: the camera's through every pixel centre at width x height, and one cosine-distributed bounce from
// each point they hit, with the whole scene's hits.
struct Probes {
  std::vector<Ray> rays;
  std::vector<Hit> hits;
};

Probes probe_rays(const Scene& scene, const RayTracer& tracer, const Camera& camera, int width, int height) {
  Probes p;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) p.rays.push_back(camera.ray(x + 0.5f, y + 0.5f));
  p.hits.resize(p.rays.size());
  tracer.intersect(p.rays, p.hits);
  Sampler rng(SamplerKind::independent, 0x9e3779b97f4a7c15ull, 0, 0, 1);
  const size_t camera_rays = p.rays.size();
  for (size_t i = 0; i < camera_rays; ++i) {
    if (!p.hits[i].valid()) continue;
    Vec3 nrm = scene.normal(p.hits[i].triangle);
    if (dot(nrm, p.rays[i].direction) > 0) nrm = -nrm;
    const Vec3 a = std::fabs(nrm.x) > 0.5f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
    const Vec3 t = normalize(cross(a, nrm)), b = cross(nrm, t);
    const Uniform2 u = rng.uniform2();
    const float r = std::sqrt(u.u), phi = 6.2831853f * u.v;
    const Vec3 d = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + nrm * std::sqrt(std::max(0.0f, 1 - r * r));
    const Vec3 x = p.rays[i].origin + p.rays[i].direction * p.hits[i].t;
    p.rays.push_back(Ray{scene.ray_origin(p.hits[i].triangle, x, nrm), normalize(d)});
  }
  std::vector<Hit> bounce_hits(p.rays.size() - camera_rays);
  tracer.intersect(std::span<const Ray>(p.rays).subspan(camera_rays), bounce_hits);
  p.hits.insert(p.hits.end(), bounce_hits.begin(), bounce_hits.end());
  return p;
}

std::vector<double> hit_weights(const Scene& scene, const Probes& probes) {
  const size_t n = scene.triangle_count();
  std::vector<double> weight(n, 0.0);
  for (const Hit& h : probes.hits)
    if (h.valid()) weight[h.triangle] += 1;
  const double total = std::accumulate(weight.begin(), weight.end(), 0.0);
  // The floor: a tenth of the probes' total, spread by the area-and-count estimate.
  const std::vector<double> estimate = area_and_count_costs(scene);
  for (size_t t = 0; t < n; ++t) weight[t] += 0.1 * total * estimate[t];
  return weight;
}

}  // namespace

std::vector<double> probe_weights(const Scene& scene, const RayTracer& tracer, const Camera& camera, int width,
                                  int height) {
  return hit_weights(scene, probe_rays(scene, tracer, camera, width, height));
}

std::vector<ScenePart> partition_by_probes(const Scene& scene, const RayTracer& tracer, const Camera& camera,
                                           int width, int height, int parts, int rounds) {
  constexpr double kEvenParts = 1.2;
  const Probes probes = probe_rays(scene, tracer, camera, width, height);
  std::vector<double> weights = hit_weights(scene, probes);
  std::vector<ScenePart> best;
  double best_busiest = 0, best_total = 0;
  bool best_even = false;
  std::vector<PartCrossing> crossings;
  for (int round = 0; round <= rounds; ++round) {
    std::vector<ScenePart> split = partition_scene(scene, parts, weights);
    const std::vector<Bounds> boxes = padded_boxes(split);
    // A ray visits exactly the parts whose boxes it enters before its hit (render/tracing/partition.hpp's routing).
    std::vector<double> visits(split.size(), 0.0);
    for (size_t i = 0; i < probes.rays.size(); ++i) {
      parts_along(probes.rays[i], boxes, crossings);
      for (const PartCrossing& c : crossings) {
        if (probes.hits[i].valid() && c.enter > probes.hits[i].t) break;
        visits[c.part] += 1;
      }
    }
    const double total = std::accumulate(visits.begin(), visits.end(), 0.0);
    const double mean = total / static_cast<double>(visits.size());
    const double busiest = *std::max_element(visits.begin(), visits.end());
    // The busiest part bounds a frame's time when each part has a host of its own; of two splits as busy, the one
    // with less work in all. A split whose parts are even (busiest at most kEvenParts times the mean) beats an uneven
    // one: on Lost Empire the least busy uneven split saves ~2 % on the busiest part, and leaves it 1.45x the mean.
    const bool even = mean > 0 && busiest <= kEvenParts * mean;
    if (best.empty() || (even && !best_even) ||
        (even == best_even && (busiest < best_busiest || (busiest == best_busiest && total < best_total)))) {
      best_busiest = busiest;
      best_total = total;
      best_even = even;
      best = split;
    }
    if (round == rounds || mean <= 0) break;
    // Parts that see more visits than the mean get heavier weights next round, so the cut gives them less room:
    // most visits are rays passing through a part's box, and a smaller box is passed by fewer (damped, since moving a
    // cut also moves which rays cross it).
    for (size_t p = 0; p < split.size(); ++p) {
      const double scale = std::pow(std::max(visits[p], 1.0) / mean, 0.7);
      for (uint32_t t : split[p].triangles) weights[t] *= scale;
    }
  }
  return best;
}

std::vector<Bounds> padded_boxes(std::vector<Bounds> boxes) {
  for (Bounds& b : boxes) {
    // A little of the box's own size and of its distance from the origin, well beyond float rounding.
    const float pad = 1e-5f * (b.diagonal() + std::fabs(b.lo.x) + std::fabs(b.lo.y) + std::fabs(b.lo.z) +
                               std::fabs(b.hi.x) + std::fabs(b.hi.y) + std::fabs(b.hi.z)) +
                      std::numeric_limits<float>::min();
    b = Bounds{b.lo - Vec3{pad, pad, pad}, b.hi + Vec3{pad, pad, pad}};
  }
  return boxes;
}

std::vector<Bounds> padded_boxes(std::span<const ScenePart> parts) {
  std::vector<Bounds> boxes;
  for (const ScenePart& part : parts) boxes.push_back(part.bounds);
  return padded_boxes(std::move(boxes));
}

void parts_along(const Ray& ray, std::span<const Bounds> boxes, std::vector<PartCrossing>& out) {
  out.clear();
  for (size_t p = 0; p < boxes.size(); ++p) {
    const Bounds& b = boxes[p];
    float enter = ray.tnear, exit = ray.tfar;
    bool missed = false;
    for (int a = 0; a < 3 && !missed; ++a) {
      const float o = ray.origin[a], d = ray.direction[a];
      const float lo = b.lo[a], hi = b.hi[a];
      if (d == 0) {
        missed = o < lo || o > hi;
        continue;
      }
      float t0 = (lo - o) / d, t1 = (hi - o) / d;
      if (t0 > t1) std::swap(t0, t1);
      enter = std::max(enter, t0);
      exit = std::min(exit, t1);
      missed = enter > exit;
    }
    if (!missed) out.push_back({static_cast<uint32_t>(p), enter, exit});
  }
  std::sort(out.begin(), out.end(), [](const PartCrossing& a, const PartCrossing& b) {
    return a.enter < b.enter || (a.enter == b.enter && a.part < b.part);
  });
}

PartitionedTracer::PartitionedTracer(const Scene& scene, std::vector<ScenePart> parts)
    : parts_(std::move(parts)), boxes_(padded_boxes(parts_)), ties_(scene), rays_per_part_(parts_.size(), 0) {
  for (const ScenePart& p : parts_) tracers_.push_back(std::make_unique<RayTracer>(scene, p.triangles));
}

RayRoutes::RayRoutes(std::span<const Ray> rays, std::span<const Bounds> boxes)
    : crossings_(rays.size()), next_(rays.size(), 0), by_part_(boxes.size()) {
  for (size_t i = 0; i < rays.size(); ++i) {
    parts_along(rays[i], boxes, crossings_[i]);
    if (!crossings_[i].empty()) active_.push_back(static_cast<uint32_t>(i));
  }
}

const std::vector<std::vector<uint32_t>>& RayRoutes::round() {
  for (auto& group : by_part_) group.clear();
  for (uint32_t i : active_) by_part_[crossings_[i][next_[i]].part].push_back(i);
  return by_part_;
}

template <class Ends>
void RayRoutes::advance_unless(Ends&& ends) {
  std::vector<uint32_t> still;
  for (uint32_t i : active_)
    if (++next_[i] < crossings_[i].size() && !ends(i, crossings_[i][next_[i]])) still.push_back(i);
  active_.swap(still);
}

void RayRoutes::advance(std::span<const Hit> hits) {
  advance_unless([&](uint32_t i, const PartCrossing& next) { return hits[i].valid() && next.enter > hits[i].t; });
}

void RayRoutes::advance(std::span<const uint8_t> blocked) {
  advance_unless([&](uint32_t i, const PartCrossing&) { return blocked[i] != 0; });
}

// Each part traces its rays of a round as one stream; `found` (the hits or the occlusion flags) says where each ray's
// search stands.
template <class Trace>
void PartitionedTracer::route(std::span<const Ray> rays, Trace&& trace, auto found) const {
  RayRoutes routes(rays, boxes_);
  while (!routes.done()) {
    const auto& by_part = routes.round();
    for (size_t p = 0; p < by_part.size(); ++p) {
      if (by_part[p].empty()) continue;
      rays_per_part_[p] += by_part[p].size();
      trace(p, by_part[p]);
    }
    routes.advance(found);
  }
}

namespace {

struct NearestHit {
  std::span<const Ray> rays;
  std::span<Hit> hits;
  const std::vector<std::unique_ptr<RayTracer>>& tracers;
  std::vector<Ray> batch;
  std::vector<Hit> found;
  void operator()(size_t part, const std::vector<uint32_t>& indices) {
    batch.clear();
    for (uint32_t i : indices) {
      Ray r = rays[i];
      if (hits[i].valid()) r.tfar = hits[i].t;  // only as near or nearer can replace it
      batch.push_back(r);
    }
    found.resize(batch.size());
    tracers[part]->intersect_unsettled(batch, found);
    for (size_t k = 0; k < indices.size(); ++k)
      if (found[k].valid()) hits[indices[k]] = found[k];
  }
};

struct AnyHit {
  std::span<const Ray> rays;
  std::span<uint8_t> occluded;
  const std::vector<std::unique_ptr<RayTracer>>& tracers;
  std::vector<Ray> batch;
  std::vector<uint8_t> found;
  void operator()(size_t part, const std::vector<uint32_t>& indices) {
    batch.clear();
    for (uint32_t i : indices) batch.push_back(rays[i]);
    found.resize(batch.size());
    tracers[part]->occluded(batch, found);
    for (size_t k = 0; k < indices.size(); ++k) occluded[indices[k]] |= found[k];
  }
};

}  // namespace

void PartitionedTracer::intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
  std::fill(hits.begin(), hits.end(), Hit{});
  NearestHit trace{rays, hits, tracers_, {}, {}};
  route(rays, trace, std::span<const Hit>(hits));
  for (size_t i = 0; i < rays.size(); ++i) hits[i] = ties_.settle(rays[i], hits[i]);
}

void PartitionedTracer::occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
  std::fill(occluded.begin(), occluded.end(), uint8_t{0});
  AnyHit trace{rays, occluded, tracers_, {}, {}};
  route(rays, trace, std::span<const uint8_t>(occluded));
}

}  // namespace lf
