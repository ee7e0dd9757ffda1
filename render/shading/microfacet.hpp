#pragma once
// Microfacet reflection with the Trowbridge-Reitz (GGX) distribution of normals, Smith's height-correlated masking
// and shadowing, and sampling of the normals visible from the outgoing direction (Heitz 2018, "Sampling the GGX
// Distribution of Visible Normals"), and glTF 2.0's metal-roughness material built on it: a conductor whose Fresnel
// term is Schlick's with the base colour as F0, mixed by `metallic` with a dielectric specular layer (F0 = 0.04,
// index 1.5) over a Lambertian base.
//
// Everything works in a local frame whose z axis is the shading normal; directions point away from the surface.
// GGX single scattering loses the light that scatters between microfacets more than once: at roughness 1 a white
// conductor's specular lobe returns 0.31 of the light at normal incidence and 0.59 at 75 degrees (microfacet.test
// measures it). MetalRoughness gives that light back as a lobe of its own.
#include <optional>

#include "render/math.hpp"
#include "render/shading/elevation_bands.hpp"

namespace lf {

class TrowbridgeReitz {
 public:
  // alpha: the slope roughness along x and y (glTF: alpha = roughness squared). Kept at least 1e-4: the model
  // cannot represent a perfect mirror, and a delta lobe belongs to the mirror material.
  TrowbridgeReitz(float alpha_x, float alpha_y);
  static float alpha_of_roughness(float roughness) { return roughness * roughness; }

  // D(wm): the density of microfacet normals per unit projected area (integrates to 1 against cos(wm)).
  float d(Vec3 wm) const;
  // Smith's Lambda, G1 and the height-correlated G of a pair of directions.
  float lambda(Vec3 w) const;
  float g1(Vec3 w) const { return 1 / (1 + lambda(w)); }
  float g(Vec3 wo, Vec3 wi) const { return 1 / (1 + lambda(wo) + lambda(wi)); }
  // The distribution of normals visible from w: G1(w) max(0, w.wm) D(wm) / cos(w); integrates to 1.
  float d_visible(Vec3 w, Vec3 wm) const;
  // A normal drawn from d_visible(w, .) for w above the surface.
  Vec3 sample_visible_normal(Vec3 w, float u1, float u2) const;
  // The density of wi, per unit solid angle, when wi is wo reflected about a normal drawn from d_visible(wo, .).
  float pdf(Vec3 wo, Vec3 wi) const;

 private:
  float ax_, ay_;
};

// Schlick's approximation of the Fresnel reflectance with reflectance f0 at normal incidence.
RGB fresnel_schlick(RGB f0, float cos_theta);

// The directional albedo of GGX reflection, E(mu, roughness) = the integral of f cos over wi for wo at cos(theta)
// = mu, and its cosine-weighted average over mu, for a Fresnel term of 1 (`conductor`) and for Schlick's with
// F0 = 0.04 (`dielectric`, the specular layer of glTF's dielectric). Tabulated on first use in a process (32
// roughnesses x 32 angles, 16 x 16 stratified visible normals each: a few tens of milliseconds) and interpolated.
struct MicrofacetAlbedo {
  float conductor(float mu, float roughness) const;
  float conductor_average(float roughness) const;
  float dielectric(float mu, float roughness) const;
  float dielectric_average(float roughness) const;
  // E averaged over elevation band j (render/shading/elevation_bands.hpp), weighted by the cosine: what a band's
  // irradiance loses to the layer above the lobe it reaches.
  float conductor_band(int j, float roughness) const;
  float dielectric_band(int j, float roughness) const;
  static const MicrofacetAlbedo& table();

  static constexpr int kSize = 32;
  float e[2][kSize][kSize];  // [conductor, dielectric][roughness][mu]
  float average[2][kSize];
  float band[2][kSize][kElevationBands];  // [conductor, dielectric][roughness][band]
};

// A rough dielectric interface (Walter, Marschner, Li and Torrance 2007, "Microfacet Models for Refraction through
// Rough Surfaces"): GGX reflection and refraction weighed by the dielectric's Fresnel term, in the frame where wo
// is above the surface (z > 0); wi below it is transmission. eta: the index of refraction beyond the surface over
// the index on wo's side. Transmission is not scaled by 1 / eta^2 (the radiance a denser medium compresses), as
// the perfect `glass` material is not: a path enters and leaves a closed object, and the two factors cancel.
// Single scattering loses light at high roughness, as reflection does (microfacet.test measures it).
class RoughDielectric {
 public:
  RoughDielectric(float alpha, float eta) : ggx_(alpha, alpha), eta_(eta) {}
  float eval(Vec3 wo, Vec3 wi) const;
  float pdf(Vec3 wo, Vec3 wi) const;
  // u0 chooses reflection or refraction (by the Fresnel term at the visible normal u1, u2 draws).
  std::optional<Vec3> sample(Vec3 wo, float u0, float u1, float u2) const;
  // The Fresnel reflectance at the macro surface for wo: the expected share of reflection, for lobe choices.
  float reflectance(Vec3 wo) const;

 private:
  // The generalized half vector of wo and wi (facing up), or nullopt where none exists or a microfacet would be
  // seen from behind by either direction.
  std::optional<Vec3> half_vector(Vec3 wo, Vec3 wi) const;
  TrowbridgeReitz ggx_;
  float eta_;
};

// How much of a metal_rough material's dielectric part transmits, through what, and from which side wo is
// (glTF's KHR_materials_transmission and KHR_materials_ior).
struct Transmission {
  float amount = 0;    // 0: opaque; 1: every dielectric part is rough glass
  float ior = 1.5f;
  bool from_outside = true;  // wo on the side the surface's normal faces
};

// glTF's metal-roughness material in the local frame, energy-conserving:
//   f = F(wo.wm) D G / (4 cos_o cos_i)                                   the specular lobe (single scattering),
//       F = mix(F_schlick(0.04), F_schlick(base), metallic)
//     + metallic F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg))       a conductor's multiple scattering
//     + (1 - metallic) base (1 - E_d(mu_o)) (1 - E_d(mu_i)) / (pi (1 - E_d avg))   the base under the layer
// The last two are Kulla and Conty's albedo scaling ("Revisiting physically based shading at Imageworks", 2017):
// what single scattering loses returns as a cosine-shaped lobe, so a white conductor and a white dielectric
// reflect all the light at every roughness and angle (the glTF specification's own mix, (1 - F(wo.wm)) base / pi,
// reflects up to 1.57 times the light at grazing angles: roughness 0.1, 85 degrees), and the whole stays reciprocal. The first term is the
// glossy lobe (G), the other two the diffuse-like one (D) of the light-path classes.
//
// With transmission t (KHR_materials_transmission), the dielectric part is (1 - t) of the above and t of a rough
// dielectric (RoughDielectric with the material's index) whose transmission the base colour tints, as glTF
// specifies: at every crossing, as glTF's BTDF and Cycles' Principled BSDF tint (a closed object's light crosses
// twice, so a solid ball's colour is the base colour squared). Seen from inside (wo on the far side of a transmitting
// surface), the material is that interface alone: the base and the conductor are on the outside. It refracts as
// Blender's importer and Cycles do, where glTF without KHR_materials_volume means a thin wall (docs/looks.md).
class MetalRoughness {
 public:
  MetalRoughness(RGB base_color, float metallic, float roughness, Transmission transmission = {});
  RGB eval(Vec3 wo, Vec3 wi) const;
  float pdf(Vec3 wo, Vec3 wi) const;
  struct Sample {
    Vec3 wi;
    RGB weight;  // f cos(wi) / pdf
    float pdf;
  };
  // u0 chooses the lobe (visible normals for the specular one, the cosine for the other), u1 and u2 the
  // direction; nothing for wo at or below the horizon or wi below it.
  std::optional<Sample> sample(Vec3 wo, float u0, float u1, float u2) const;
  RGB eval_specular(Vec3 wo, Vec3 wi) const;
  RGB eval_diffuse(Vec3 wo, Vec3 wi) const;  // the conductor's multiple scattering and the base
  RGB eval_transmitting(Vec3 wo, Vec3 wi) const;  // the rough dielectric's reflection and transmission
  // Whether eval_diffuse() is ever more than 0 (a perfectly smooth conductor's, or rough glass's, is not).
  bool has_diffuse() const { return dielectric_weight_ > 0 || (conductor_weight_ > 0 && conductor_average_ < 1); }
  // What eval_diffuse() reflects towards wo of light whose irradiance arrives split into elevation bands: its
  // factor of wi, 1 - E(cos theta_i), averaged over each band (the lobe is the same in every azimuth). This is
  // how a diffuse cache's records light these lobes.
  RGB reflect_bands(Vec3 wo, const ElevationBands& irradiance) const;
  // The glossy lobes alone: the specular lobe and the rough dielectric (what `glossy` follows; the others are the
  // diffuse caches'). A direction drawn in proportion to them, weighted by their f cos / pdf.
  std::optional<Sample> sample_glossy(Vec3 wo, float u0, float u1, float u2) const;
  // The glossy lobes' share of what wo reflects and transmits, by the lobes' albedos (as sample() chooses them).
  float glossy_share(Vec3 wo) const {
    if (wo.z <= 0) return 0;
    const float pg = glass_probability(wo);
    return pg + (1 - pg) * specular_probability(wo);
  }
  // Whether wi below the surface gets anything (the rough dielectric's share is not 0).
  bool transmits() const { return glass_weight_ > 0; }

 private:
  float specular_probability(Vec3 wo) const;
  // The chance sample() takes the rough dielectric (1 from inside).
  float glass_probability(Vec3 wo) const;
  float mixture_pdf(Vec3 wo, Vec3 wi, float specular_share) const;
  // pdf() of a transmitting material, given its lobe shares at wo.
  float transmitting_pdf(Vec3 wo, Vec3 wi, float glass_share, float specular_share) const;
  std::optional<Sample> sample_reflecting(Vec3 wo, float u0, float u1, float u2) const;
  RGB base_;
  float metallic_, roughness_;
  // The parts' weights: metallic, (1 - metallic)(1 - t) and (1 - metallic) t; from inside 0, 0 and 1.
  float conductor_weight_, dielectric_weight_, glass_weight_;
  TrowbridgeReitz ggx_;
  RoughDielectric glass_;
  RGB multiple_scattering_fresnel_;  // F_ms, per channel
  float conductor_average_, dielectric_average_;
};

}  // namespace lf
