#include "render/shading/microfacet.hpp"

#include <algorithm>
#include <cmath>

#include "render/shading/bsdf.hpp"  // fresnel_dielectric, refract

namespace lf {
namespace {

constexpr float kMinAlpha = 1e-4f;

Vec3 reflect_about(Vec3 w, Vec3 n) { return n * (2 * dot(w, n)) - w; }

Vec3 cosine_local(float u1, float u2) {
  const float r = std::sqrt(u1), phi = 2 * kPi * u2;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - u1))};
}

}  // namespace

TrowbridgeReitz::TrowbridgeReitz(float alpha_x, float alpha_y)
    : ax_(std::max(alpha_x, kMinAlpha)), ay_(std::max(alpha_y, kMinAlpha)) {}

float TrowbridgeReitz::d(Vec3 wm) const {
  if (wm.z <= 0) return 0;
  const float x = wm.x / ax_, y = wm.y / ay_;
  const float e = x * x + y * y + wm.z * wm.z;
  return 1 / (kPi * ax_ * ay_ * e * e);
}

float TrowbridgeReitz::lambda(Vec3 w) const {
  const float cos2 = w.z * w.z;
  if (cos2 <= 0) return INFINITY;
  // alpha^2 tan^2(theta) along w's azimuth.
  const float a2_tan2 = (w.x * w.x * ax_ * ax_ + w.y * w.y * ay_ * ay_) / cos2;
  return (std::sqrt(1 + a2_tan2) - 1) / 2;
}

float TrowbridgeReitz::d_visible(Vec3 w, Vec3 wm) const {
  if (w.z <= 0) return 0;
  return g1(w) * std::max(0.0f, dot(w, wm)) * d(wm) / w.z;
}

Vec3 TrowbridgeReitz::sample_visible_normal(Vec3 w, float u1, float u2) const {
  // Stretch to the hemisphere configuration, sample the projected half disk, unstretch (Heitz 2018, listing 1).
  const Vec3 wh = normalize(Vec3{ax_ * w.x, ay_ * w.y, w.z});
  const float len2 = wh.x * wh.x + wh.y * wh.y;
  const Vec3 t1 = len2 > 0 ? Vec3{-wh.y, wh.x, 0} / std::sqrt(len2) : Vec3{1, 0, 0};
  const Vec3 t2 = cross(wh, t1);
  const float r = std::sqrt(u1), phi = 2 * kPi * u2;
  const float p1 = r * std::cos(phi);
  const float s = 0.5f * (1 + wh.z);
  const float p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * r * std::sin(phi);
  const Vec3 nh = t1 * p1 + t2 * p2 + wh * std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2));
  return normalize(Vec3{ax_ * nh.x, ay_ * nh.y, std::max(1e-7f, nh.z)});
}

float TrowbridgeReitz::pdf(Vec3 wo, Vec3 wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  const Vec3 wm = normalize(wo + wi);
  return d_visible(wo, wm) / (4 * dot(wo, wm));
}

RGB fresnel_schlick(RGB f0, float cos_theta) {
  const float m = std::clamp(1 - cos_theta, 0.0f, 1.0f);
  const float m5 = (m * m) * (m * m) * m;
  return f0 + (RGB{1, 1, 1} - f0) * m5;
}

namespace {

// E(mu) of GGX reflection with the given Fresnel F0 (1: a perfect conductor) by stratified quadrature of visible
// normals: the mean of F G / G1 over reflections that stay above the surface.
float directional_albedo(float mu, float roughness, float f0) {
  const float alpha = TrowbridgeReitz::alpha_of_roughness(roughness);
  const TrowbridgeReitz ggx(alpha, alpha);
  const Vec3 wo{std::sqrt(std::max(0.0f, 1 - mu * mu)), 0, mu};
  constexpr int kStrata = 16;
  double sum = 0;
  for (int i = 0; i < kStrata; ++i)
    for (int j = 0; j < kStrata; ++j) {
      const Vec3 wm = ggx.sample_visible_normal(wo, (i + 0.5f) / kStrata, (j + 0.5f) / kStrata);
      const Vec3 wi = reflect_about(wo, wm);
      if (wi.z <= 0) continue;
      const float f = f0 >= 1 ? 1.0f : fresnel_schlick(RGB{f0, f0, f0}, dot(wo, wm)).x;
      sum += f * ggx.g(wo, wi) / ggx.g1(wo);
    }
  return static_cast<float>(sum / (kStrata * kStrata));
}

constexpr int kN = MicrofacetAlbedo::kSize;

float mu_at(int i) { return (i + 0.5f) / kN; }
float roughness_at(int r) { return static_cast<float>(r) / (kN - 1); }

// Linear interpolation in a table row of kN values at x scaled to [0, kN - 1].
float lerp_at(const float* row, float x) {
  x = std::clamp(x, 0.0f, static_cast<float>(kN - 1));
  const int i = std::min(static_cast<int>(x), kN - 2);
  const float t = x - static_cast<float>(i);
  return row[i] * (1 - t) + row[i + 1] * t;
}

float table_lookup(const float (&e)[kN][kN], float mu, float roughness) {
  const float r = std::clamp(roughness, 0.0f, 1.0f) * (kN - 1);
  const int k = std::min(static_cast<int>(r), kN - 2);
  const float t = r - static_cast<float>(k);
  const float x = std::clamp(mu, 0.0f, 1.0f) * kN - 0.5f;  // mu_at(i) = (i + 0.5) / kN
  return lerp_at(e[k], x) * (1 - t) + lerp_at(e[k + 1], x) * t;
}

}  // namespace

const MicrofacetAlbedo& MicrofacetAlbedo::table() {
  static const MicrofacetAlbedo tables = [] {
    MicrofacetAlbedo t{};
    for (int kind = 0; kind < 2; ++kind)
      for (int r = 0; r < kN; ++r) {
        double average = 0;
        for (int i = 0; i < kN; ++i) {
          t.e[kind][r][i] = directional_albedo(mu_at(i), roughness_at(r), kind == 0 ? 1.0f : 0.04f);
          average += 2.0 * t.e[kind][r][i] * mu_at(i) / kN;  // 2 times the integral of E(mu) mu over [0, 1]
        }
        t.average[kind][r] = static_cast<float>(average);
        // The band means of the interpolated table eval() reads, weighted by the cosine (midpoint rule in it).
        constexpr int kSteps = 32;
        const float (&rows)[kN][kN] = t.e[kind];
        for (int j = 0; j < kElevationBands; ++j) {
          double sum = 0, weight = 0;
          for (int q = 0; q < kSteps; ++q) {
            const float mu = 1 - (static_cast<float>(j) + (q + 0.5f) / kSteps) / kElevationBands;
            sum += mu * table_lookup(rows, mu, roughness_at(r));
            weight += mu;
          }
          t.band[kind][r][j] = static_cast<float>(sum / weight);
        }
      }
    return t;
  }();
  return tables;
}

float MicrofacetAlbedo::conductor(float mu, float roughness) const { return table_lookup(e[0], mu, roughness); }
float MicrofacetAlbedo::dielectric(float mu, float roughness) const { return table_lookup(e[1], mu, roughness); }
float MicrofacetAlbedo::conductor_average(float roughness) const {
  return lerp_at(average[0], std::clamp(roughness, 0.0f, 1.0f) * (kN - 1));
}
float MicrofacetAlbedo::dielectric_average(float roughness) const {
  return lerp_at(average[1], std::clamp(roughness, 0.0f, 1.0f) * (kN - 1));
}

namespace {
// A band's mean at the roughness, linear between the table's roughnesses (as table_lookup is).
float band_lookup(const float (&bands)[kN][kElevationBands], int j, float roughness) {
  const float r = std::clamp(roughness, 0.0f, 1.0f) * (kN - 1);
  const int k = std::min(static_cast<int>(r), kN - 2);
  const float t = r - static_cast<float>(k);
  return bands[k][j] * (1 - t) + bands[k + 1][j] * t;
}
}  // namespace

float MicrofacetAlbedo::conductor_band(int j, float roughness) const { return band_lookup(band[0], j, roughness); }
float MicrofacetAlbedo::dielectric_band(int j, float roughness) const { return band_lookup(band[1], j, roughness); }

std::optional<Vec3> RoughDielectric::half_vector(Vec3 wo, Vec3 wi) const {
  if (wo.z <= 0 || wi.z == 0) return std::nullopt;
  const float etap = wi.z > 0 ? 1.0f : eta_;
  Vec3 wm = wi * etap + wo;
  if (!(dot(wm, wm) > 0)) return std::nullopt;
  wm = normalize(wm);
  if (wm.z < 0) wm = -wm;
  if (dot(wm, wi) * wi.z <= 0 || dot(wm, wo) <= 0) return std::nullopt;
  return wm;
}

float RoughDielectric::eval(Vec3 wo, Vec3 wi) const {
  const auto wm = half_vector(wo, wi);
  if (!wm) return 0;
  const float f = fresnel_dielectric(dot(wo, *wm), eta_);
  if (wi.z > 0) return f * ggx_.d(*wm) * ggx_.g(wo, wi) / (4 * wo.z * wi.z);
  const float denom = dot(wi, *wm) + dot(wo, *wm) / eta_;
  return (1 - f) * ggx_.d(*wm) * ggx_.g(wo, wi) *
         std::fabs(dot(wi, *wm) * dot(wo, *wm) / (denom * denom * wi.z * wo.z));
}

float RoughDielectric::pdf(Vec3 wo, Vec3 wi) const {
  const auto wm = half_vector(wo, wi);
  if (!wm) return 0;
  const float f = fresnel_dielectric(dot(wo, *wm), eta_);
  if (wi.z > 0) return f * ggx_.d_visible(wo, *wm) / (4 * dot(wo, *wm));
  const float denom = dot(wi, *wm) + dot(wo, *wm) / eta_;
  return (1 - f) * ggx_.d_visible(wo, *wm) * std::fabs(dot(wi, *wm)) / (denom * denom);
}

std::optional<Vec3> RoughDielectric::sample(Vec3 wo, float u0, float u1, float u2) const {
  if (wo.z <= 0) return std::nullopt;
  const Vec3 wm = ggx_.sample_visible_normal(wo, u1, u2);
  if (u0 < fresnel_dielectric(dot(wo, wm), eta_)) {
    const Vec3 wi = reflect_about(wo, wm);
    return wi.z > 0 ? std::optional<Vec3>(wi) : std::nullopt;
  }
  const auto wi = refract(wo, wm, eta_);
  return wi && wi->z < 0 ? wi : std::nullopt;
}

float RoughDielectric::reflectance(Vec3 wo) const { return fresnel_dielectric(std::max(0.0f, wo.z), eta_); }

MetalRoughness::MetalRoughness(RGB base_color, float metallic, float roughness, Transmission transmission)
    : base_(base_color),
      metallic_(std::clamp(metallic, 0.0f, 1.0f)),
      roughness_(std::clamp(roughness, 0.0f, 1.0f)),
      conductor_weight_(metallic_),
      dielectric_weight_((1 - metallic_) * (1 - std::clamp(transmission.amount, 0.0f, 1.0f))),
      glass_weight_((1 - metallic_) * std::clamp(transmission.amount, 0.0f, 1.0f)),
      ggx_(TrowbridgeReitz::alpha_of_roughness(roughness_), TrowbridgeReitz::alpha_of_roughness(roughness_)),
      glass_(TrowbridgeReitz::alpha_of_roughness(roughness_),
             transmission.from_outside ? transmission.ior : 1 / transmission.ior) {
  if (glass_weight_ > 0 && !transmission.from_outside) {
    conductor_weight_ = dielectric_weight_ = 0;
    glass_weight_ = 1;
  }
  const MicrofacetAlbedo& table = MicrofacetAlbedo::table();
  conductor_average_ = table.conductor_average(roughness_);
  dielectric_average_ = table.dielectric_average(roughness_);
  // Kulla and Conty's F_ms: the Fresnel term of light that scatters more than once (Schlick's hemispherical
  // average F0 + (1 - F0) / 21 compounded over the bounces).
  auto f_ms = [&](float f0) {
    const float f_avg = f0 + (1 - f0) / 21;
    return f_avg * f_avg * conductor_average_ / (1 - f_avg * (1 - conductor_average_));
  };
  multiple_scattering_fresnel_ = {f_ms(base_.x), f_ms(base_.y), f_ms(base_.z)};
}

RGB MetalRoughness::eval(Vec3 wo, Vec3 wi) const {
  if (!transmits()) return eval_specular(wo, wi) + eval_diffuse(wo, wi);
  if (wi.z < 0) return eval_transmitting(wo, wi);
  return eval_specular(wo, wi) + eval_diffuse(wo, wi) + eval_transmitting(wo, wi);
}

RGB MetalRoughness::eval_transmitting(Vec3 wo, Vec3 wi) const {
  if (!transmits()) return {};
  const float f = glass_weight_ * glass_.eval(wo, wi);
  return wi.z < 0 ? base_ * f : RGB{f, f, f};
}

RGB MetalRoughness::eval_specular(Vec3 wo, Vec3 wi) const {
  if (wo.z <= 0 || wi.z <= 0) return {};
  const Vec3 wm = normalize(wo + wi);
  const float cos_h = dot(wo, wm);
  const RGB f = fresnel_schlick(RGB{0.04f, 0.04f, 0.04f}, cos_h) * dielectric_weight_ +
                fresnel_schlick(base_, cos_h) * conductor_weight_;
  return f * (ggx_.d(wm) * ggx_.g(wo, wi) / (4 * wo.z * wi.z));
}

RGB MetalRoughness::eval_diffuse(Vec3 wo, Vec3 wi) const {
  if (wo.z <= 0 || wi.z <= 0) return {};
  const MicrofacetAlbedo& table = MicrofacetAlbedo::table();
  RGB f{};
  if (conductor_weight_ > 0 && conductor_average_ < 1) {
    const float lost = (1 - table.conductor(wo.z, roughness_)) * (1 - table.conductor(wi.z, roughness_));
    f += multiple_scattering_fresnel_ * (conductor_weight_ * lost / (kPi * (1 - conductor_average_)));
  }
  if (dielectric_weight_ > 0) {
    const float passed = (1 - table.dielectric(wo.z, roughness_)) * (1 - table.dielectric(wi.z, roughness_));
    f += base_ * (dielectric_weight_ * passed / (kPi * (1 - dielectric_average_)));
  }
  return f;
}

RGB MetalRoughness::reflect_bands(Vec3 wo, const ElevationBands& irradiance) const {
  if (wo.z <= 0) return {};
  const MicrofacetAlbedo& table = MicrofacetAlbedo::table();
  // The irradiance the layer above a lobe lets through to it, band by band.
  auto passed = [&](float (MicrofacetAlbedo::*band)(int, float) const) {
    RGB sum{};
    for (int j = 0; j < kElevationBands; ++j)
      sum += irradiance[static_cast<size_t>(j)] * (1 - (table.*band)(j, roughness_));
    return sum;
  };
  RGB out{};
  if (conductor_weight_ > 0 && conductor_average_ < 1)
    out += multiple_scattering_fresnel_ * passed(&MicrofacetAlbedo::conductor_band) *
           (conductor_weight_ * (1 - table.conductor(wo.z, roughness_)) / (kPi * (1 - conductor_average_)));
  if (dielectric_weight_ > 0)
    out += base_ * passed(&MicrofacetAlbedo::dielectric_band) *
           (dielectric_weight_ * (1 - table.dielectric(wo.z, roughness_)) / (kPi * (1 - dielectric_average_)));
  return out;
}

std::optional<MetalRoughness::Sample> MetalRoughness::sample_glossy(Vec3 wo, float u0, float u1, float u2) const {
  if (wo.z <= 0) return std::nullopt;
  // The rough dielectric with its share against the reflecting parts (as sample() takes it), else the specular
  // lobe's visible normals.
  const float pg = glass_probability(wo);
  std::optional<Vec3> wi;
  if (u0 < pg) {
    wi = glass_.sample(wo, std::min(u0 / pg, 0x1.fffffep-1f), u1, u2);
  } else {
    wi = reflect_about(wo, ggx_.sample_visible_normal(wo, u1, u2));
    if (wi->z <= 0) return std::nullopt;
  }
  if (!wi) return std::nullopt;
  float p = pg > 0 ? pg * glass_.pdf(wo, *wi) : 0.0f;
  if (pg < 1 && wi->z > 0) p += (1 - pg) * ggx_.pdf(wo, *wi);
  if (!(p > 0)) return std::nullopt;
  const RGB f = eval_specular(wo, *wi) + eval_transmitting(wo, *wi);
  return Sample{*wi, f * (std::fabs(wi->z) / p), p};
}

// The specular lobe's share of what wo reflects, from each lobe's albedo at wo. A lobe that reflects anything
// keeps at least 2 % of the samples, so its weights stay bounded.
float MetalRoughness::specular_probability(Vec3 wo) const {
  const MicrofacetAlbedo& table = MicrofacetAlbedo::table();
  const float e_d = table.dielectric(wo.z, roughness_), e_c = table.conductor(wo.z, roughness_);
  const float spec = dielectric_weight_ * e_d + conductor_weight_ * e_c * average(fresnel_schlick(base_, wo.z));
  const float diffuse = dielectric_weight_ * average(base_) * (1 - e_d) +
                        conductor_weight_ * average(multiple_scattering_fresnel_) * (1 - e_c);
  if (diffuse <= 0) return 1;
  if (spec <= 0) return 0;
  return std::clamp(spec / (spec + diffuse), 0.02f, 0.98f);
}

// The rough dielectric's share, by its albedo (reflectance plus tinted transmittance) against the reflecting parts'
// (dielectric layer, base, conductor), at least 2 % of the samples for each side that has any.
float MetalRoughness::glass_probability(Vec3 wo) const {
  if (!transmits()) return 0;
  if (conductor_weight_ <= 0 && dielectric_weight_ <= 0) return 1;
  const float r = glass_.reflectance(wo);
  const float glass = glass_weight_ * (r + (1 - r) * average(base_));
  const float rest = conductor_weight_ * average(fresnel_schlick(base_, wo.z)) +
                     dielectric_weight_ * std::max(0.04f, average(base_));
  if (rest <= 0) return 1;
  return std::clamp(glass / (glass + rest), 0.02f, 0.98f);
}

float MetalRoughness::pdf(Vec3 wo, Vec3 wi) const {
  if (!transmits()) {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    return mixture_pdf(wo, wi, specular_probability(wo));
  }
  if (wo.z <= 0) return 0;
  return transmitting_pdf(wo, wi, glass_probability(wo), specular_probability(wo));
}

float MetalRoughness::transmitting_pdf(Vec3 wo, Vec3 wi, float glass_share, float specular_share) const {
  float p = glass_share * glass_.pdf(wo, wi);
  if (wi.z > 0 && glass_share < 1) p += (1 - glass_share) * mixture_pdf(wo, wi, specular_share);
  return p;
}

float MetalRoughness::mixture_pdf(Vec3 wo, Vec3 wi, float specular_share) const {
  return specular_share * ggx_.pdf(wo, wi) + (1 - specular_share) * wi.z / kPi;
}

std::optional<MetalRoughness::Sample> MetalRoughness::sample(Vec3 wo, float u0, float u1, float u2) const {
  if (!transmits()) return sample_reflecting(wo, u0, u1, u2);
  if (wo.z <= 0) return std::nullopt;
  const float pg = glass_probability(wo), ps = specular_probability(wo);  // once, for the choice and the density
  std::optional<Vec3> wi;
  if (u0 < pg) {
    wi = glass_.sample(wo, std::min(u0 / pg, 0x1.fffffep-1f), u1, u2);
  } else {
    const float u = std::min((u0 - pg) / (1 - pg), 0x1.fffffep-1f);
    wi = u < ps ? reflect_about(wo, ggx_.sample_visible_normal(wo, u1, u2)) : cosine_local(u1, u2);
    if (wi->z <= 0) return std::nullopt;
  }
  if (!wi) return std::nullopt;
  const float p = transmitting_pdf(wo, *wi, pg, ps);
  if (!(p > 0)) return std::nullopt;
  return Sample{*wi, eval(wo, *wi) * (std::fabs(wi->z) / p), p};
}

std::optional<MetalRoughness::Sample> MetalRoughness::sample_reflecting(Vec3 wo, float u0, float u1, float u2) const {
  if (wo.z <= 0) return std::nullopt;
  const float ps = specular_probability(wo);  // once: two table lookups and a Fresnel term
  const Vec3 wi = u0 < ps ? reflect_about(wo, ggx_.sample_visible_normal(wo, u1, u2)) : cosine_local(u1, u2);
  if (wi.z <= 0) return std::nullopt;
  const float p = mixture_pdf(wo, wi, ps);
  if (!(p > 0)) return std::nullopt;
  return Sample{wi, eval(wo, wi) * (wi.z / p), p};
}

}  // namespace lf
