#pragma once
// Sampling a point on the scene's area lights (or a direction of its environment), shared by every LightOp that
// does next-event estimation.
#include <optional>

#include "render/lights/light_selection.hpp"
#include "render/math.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/scene.hpp"
#include "render/lights/spherical_triangle.hpp"

namespace lf {

struct LightSample {
  Vec3 point;
  Vec3 normal;      // the emitter's front side (area lights)
  uint32_t triangle;
  RGB radiance;     // Le for an area light or the environment; intensity I for a point light
  float pdf_area;   // P(triangle) / area for an area light; P(light) for a point light; per solid angle for the
                    // environment
  bool is_point = false;
  bool at_infinity = false;  // from the environment (render/lights/environment.hpp): `direction`, not a point
  Vec3 direction{};          // towards the environment, unit length
  const PointLight* point_light = nullptr;  // a point light's own (a spot's intensity depends on the direction)
  // The intensity of a point light towards x (a spot's falloff), or `radiance` for any other light.
  RGB radiance_towards(Vec3 x) const {
    return point_light && point_light->spot() ? point_light->intensity_towards(normalize(x - point)) : radiance;
  }
};

// The environment's sample for uniform (u, v), the environment having been chosen with probability `share`.
inline LightSample environment_sample(const Scene& scene, float share, Uniform2 uv) {
  const Environment::Sample s = scene.environment()->sample(uv.u, uv.v);
  LightSample ls{{}, {}, UINT32_MAX, s.radiance, share * s.pdf};
  ls.at_infinity = true;
  ls.direction = s.wi;
  return ls;
}

// The environment's share of the light samples at point x facing n when lights are chosen through the tree (and a
// learned selection): Scene::environment_share(), or all of them where no other light can reach x's side (neither
// the tree nor a learned cell has one: a panel facing away), so that no sample is spent on nothing there.
inline float environment_share_at(const Scene& scene, Vec3 x, Vec3 n, const LightSelection* selection) {
  const float share = scene.environment_share();
  if (share <= 0 || share >= 1) return share;
  if (const int32_t cell = selection ? selection->cell_of(x, n) : -1; cell >= 0)
    return selection->environment_share(cell, share);
  return scene.light_tree().reaches(x, n) ? share : 1.0f;
}

// The density, per solid angle, with which light sampling draws direction wi from the environment, given the
// environment's share of the samples there (for MIS when a BSDF-sampled ray leaves the scene).
inline float environment_pdf(const Scene& scene, Vec3 wi, float share) {
  return share > 0 ? share * scene.environment()->pdf(wi) : 0.0f;
}

// A uniform number u that fell at or above `share`, rescaled to [0, 1) over the rest.
inline float past_share(float u, float share) {
  return share > 0 ? std::min((u - share) / (1 - share), 0x1.fffffep-1f) : u;
}
// One that fell below it, rescaled to [0, 1).
inline float within_share(float u, float share) { return std::min(u / share, 0x1.fffffep-1f); }

// The area over which emitter e (triangle tri) gets its light samples: the triangle's, or for an emitter an alpha
// map cuts out, that of the parts that may be there (render/lights/emitter_cutouts.hpp).
inline float emitter_sampled_area(const Scene& scene, uint32_t tri, size_t e) {
  const EmitterCutouts& cut = scene.emitter_cutouts();
  return cut.restricted(e) ? cut.sampled_area(e) : scene.area(tri);
}

// Light e (Scene's numbering: a triangle below emitters().size(), else a point light), chosen with probability
// p_light, as a sample: the point of the triangle that `uv` names (uniform over its sampled area for uniform uv).
inline LightSample light_sample_at(const Scene& scene, size_t e, float p_light, Uniform2 uv) {
  if (e >= scene.emitters().size()) {
    const PointLight& p = scene.point_lights()[e - scene.emitters().size()];
    LightSample ls{p.position, {}, UINT32_MAX, p.intensity, p_light, true};
    ls.point_light = &p;
    return ls;
  }
  const uint32_t tri = scene.emitters()[e];
  const EmitterCutouts& cut = scene.emitter_cutouts();
  Vec3 b;
  float area;
  if (cut.restricted(e)) {
    b = cut.barycentrics(e, uv);
    area = cut.sampled_area(e);
  } else {
    const float su = std::sqrt(uv.u);
    const float v = uv.v;
    b = Vec3{1 - su, su * (1 - v), su * v};
    area = scene.area(tri);
  }
  const Vec3 y = scene.vertex(tri, 0) * b.x + scene.vertex(tri, 1) * b.y + scene.vertex(tri, 2) * b.z;
  // A cut-out part of an emitter is not there: it sends nothing (the sample still counts, so no bias).
  const RGB le = scene.opaque(tri, b) ? scene.emission(tri, b) : RGB{};
  return LightSample{y, scene.normal(tri), tri, le, p_light / area};
}

// How a point on a chosen triangle light is drawn: uniform over its (sampled) area, or uniform over the solid angle
// it subtends at the shaded point (render/lights/spherical_triangle.hpp), which takes away the 1 / d^2 weight of points next
// to a light. Emitters with cut-out parts (render/lights/emitter_cutouts.hpp), lights too small to be worth it from there
// (kMinSampledSolidAngle) and point lights are drawn by area (or are points) either way.
enum class LightPoint : uint8_t { area, solid_angle };

// Whether emitter e may be drawn by solid angle at all (a triangle without cut-out parts, in that mode); from a
// point, it then is when its solid angle there reaches kMinSampledSolidAngle.
inline bool solid_angle_candidate(const Scene& scene, size_t e, LightPoint mode) {
  return mode == LightPoint::solid_angle && e < scene.emitters().size() && !scene.emitter_cutouts().restricted(e);
}

// Whether emitter e seen from x is drawn by solid angle, and that solid angle: the density at a BSDF hit. The
// sampler below decides with the same function of the same corners (sample_spherical_triangle), so both take the
// same branch with the same number.
inline bool solid_angle_sampled(const Scene& scene, size_t e, Vec3 x, LightPoint mode, double& omega) {
  omega = 0;
  if (!solid_angle_candidate(scene, e, mode)) return false;
  const uint32_t tri = scene.emitters()[e];
  omega = spherical_triangle_solid_angle(x, scene.vertex(tri, 0), scene.vertex(tri, 1), scene.vertex(tri, 2));
  return omega >= kMinSampledSolidAngle;
}

// As light_sample_at, with the point drawn as `mode` says for a shaded point at x.
inline LightSample light_sample_from(const Scene& scene, size_t e, float p_light, Uniform2 uv, Vec3 x, LightPoint mode) {
  if (solid_angle_candidate(scene, e, mode)) {
    const uint32_t tri = scene.emitters()[e];
    const Vec3 p0 = scene.vertex(tri, 0), p1 = scene.vertex(tri, 1), p2 = scene.vertex(tri, 2);
    double omega = 0;  // nullopt below kMinSampledSolidAngle: then an area sample, as solid_angle_sampled says
    const std::optional<Vec3> dir = sample_spherical_triangle(x, p0, p1, p2, uv.u, uv.v, omega);
    const Vec3 ng = scene.normal(tri);
    const float facing = dir ? dot(*dir, ng) : 0.0f;
    const float t = facing != 0 ? dot(p0 - x, ng) / facing : 0.0f;
    if (dir && t > 0 && std::isfinite(t)) {
      const Vec3 y = x + *dir * t;
      // The emitter's alpha there (a wholly cut-out emitter sends nothing).
      const Vec3 b = scene.barycentrics(tri, y);
      const RGB le = scene.opaque(tri, b) ? scene.emission(tri, b) : RGB{};
      // Density 1 / omega over directions, as an area density at y: cos_y / (omega t^2).
      const float pdf_area = p_light * static_cast<float>(std::fabs(facing) / (omega * static_cast<double>(t) * t));
      return LightSample{y, ng, tri, le, pdf_area};
    }
  }
  return light_sample_at(scene, e, p_light, uv);
}

// A low-discrepancy Sampler draws the light and the point on it from one 2D point (the pick's remainder and v), so
// that a pixel's samples stay stratified over the lights' area together; an Rng, or the independent sampler, draws
// three numbers in turn, as always.
template <class Draws>
constexpr bool draws_jointly(const Draws& rng) {
  if constexpr (requires { rng.low_discrepancy(); }) return rng.low_discrepancy();
  return false;
}

// Picks a light by power and a uniform point on it, or the environment (Scene::environment_share). `Draws` is an
// Rng or a Sampler.
template <class Draws>
inline LightSample sample_light(const Scene& scene, Draws& rng) {
  float p_light = 0;
  const float share = scene.environment_share();
  if (draws_jointly(rng)) {
    Uniform2 uv = rng.uniform2();
    if (uv.u < share) return environment_sample(scene, share, {within_share(uv.u, share), uv.v});
    const size_t e = scene.pick_emitter(past_share(uv.u, share), p_light, &uv.u);
    return light_sample_at(scene, e, p_light * (1 - share), uv);
  }
  const float u = rng.uniform();
  if (u < share) return environment_sample(scene, share, rng.uniform2());
  const size_t e = scene.pick_emitter(past_share(u, share), p_light);
  return light_sample_at(scene, e, p_light * (1 - share), rng.uniform2());
}

// The light for point x facing n from one number u in [0, 1): through the scene's light tree, or, in a learned
// cell of `selection`, from the cell's lights for u below its share and through the tree above it (each part
// rescaled to [0, 1)), `probability` then being the mixture's. `remainder` as LightTree::pick. False when the tree
// finds no light that can reach x's side (and u fell in its part).
inline bool pick_light(const Scene& scene, Vec3 x, Vec3 n, float u, const LightSelection* selection, size_t& light,
                       float& probability, float* remainder) {
  const int32_t cell = selection ? selection->cell_of(x, n) : -1;
  if (cell < 0) return scene.light_tree().pick(x, n, u, light, probability, remainder);
  const float share = selection->share();
  if (u < share) {
    float p_cell = 0;
    selection->pick(cell, std::min(u / share, 0x1.fffffep-1f), light, p_cell, remainder);
    probability = share * p_cell + (1 - share) * scene.light_tree().probability(x, n, light);
    return true;
  }
  float p_tree = 0;
  if (!scene.light_tree().pick(x, n, std::min((u - share) / (1 - share), 0x1.fffffep-1f), light, p_tree, remainder))
    return false;
  probability = selection->mixture(cell, light, p_tree);
  return true;
}

// Picks a light for point x facing n: the environment with chance environment_share_at(), else through the
// scene's light tree (by what each can give the point), or, with a learned LightSelection whose cell holds x, from
// that cell's lights with chance selection->share() and through the tree otherwise; then a point on it as `mode`
// says. nullopt when no light can reach x's side.
template <class Draws>
inline std::optional<LightSample> sample_light_at(const Scene& scene, Vec3 x, Vec3 n, Draws& rng,
                                                  LightPoint mode = LightPoint::area,
                                                  const LightSelection* selection = nullptr) {
  size_t e = 0;
  float p_light = 0;
  const float share = environment_share_at(scene, x, n, selection);
  auto pick = [&](float u, float* remainder) {
    if (!pick_light(scene, x, n, past_share(u, share), selection, e, p_light, remainder)) return false;
    p_light *= 1 - share;
    return true;
  };
  if (draws_jointly(rng)) {
    Uniform2 uv = rng.uniform2();
    if (uv.u < share) return environment_sample(scene, share, {within_share(uv.u, share), uv.v});
    if (!pick(uv.u, &uv.u)) return std::nullopt;
    // The default's path is exactly the area sample, with nothing to decide per sample.
    if (mode == LightPoint::area) return light_sample_at(scene, e, p_light, uv);
    return light_sample_from(scene, e, p_light, uv, x, mode);
  }
  const float u = rng.uniform();
  if (u < share) return environment_sample(scene, share, rng.uniform2());
  if (!pick(u, nullptr)) return std::nullopt;
  if (mode == LightPoint::area) return light_sample_at(scene, e, p_light, rng.uniform2());
  return light_sample_from(scene, e, p_light, rng.uniform2(), x, mode);
}

// The area density with which sample_light_at(x, n, mode, selection) draws point y on emitter triangle `tri` (y
// seen from x at distance dist with cosine cos_y at the light).
inline float light_pdf_area_at(const Scene& scene, uint32_t tri, Vec3 x, Vec3 n, LightPoint mode = LightPoint::area,
                               float dist = 0, float cos_y = 0, const LightSelection* selection = nullptr) {
  const size_t e = scene.emitter_index_of(tri);
  float p_light = scene.light_tree().probability(x, n, e);
  if (const int32_t cell = selection ? selection->cell_of(x, n) : -1; cell >= 0)
    p_light = selection->mixture(cell, e, p_light);
  p_light *= 1 - environment_share_at(scene, x, n, selection);
  double omega = 0;
  if (solid_angle_sampled(scene, e, x, mode, omega))
    return p_light * static_cast<float>(std::fabs(cos_y) / (omega * static_cast<double>(dist) * dist));
  return p_light / emitter_sampled_area(scene, tri, e);
}

// The area density with which sample_light draws a point on triangle `tri` (for MIS when a BSDF-sampled ray hits
// a light).
inline float light_pdf_area(const Scene& scene, uint32_t tri) {
  const float area = scene.emitter_cutouts().any() ? emitter_sampled_area(scene, tri, scene.emitter_index_of(tri)) : scene.area(tri);
  return scene.emitter_probability_of_triangle(tri) * (1 - scene.environment_share()) / area;
}

// Power heuristic (beta = 2) weight of a sample drawn with density `a` when `b` could also have drawn it.
inline float power_heuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0f;
}

}  // namespace lf
