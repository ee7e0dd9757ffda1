#pragma once
// Scattering at a surface point: diffuse (Lambert), glossy (Lambert + a normalized Phong lobe), either with a
// perfect mirror term beside, perfect mirror, and dielectric glass with Fresnel. Directions point away from the
// surface; `n` is the unit normal on the side of wo. eval() returns f(wo, wi) without the cosine; sample() returns wi
// with weight f * |cos| / pdf.
#include <algorithm>
#include <optional>

#include "render/math.hpp"
#include "render/scene/scene.hpp"
#include "render/shading/microfacet.hpp"

namespace lf {

class Bsdf {
 public:
  explicit Bsdf(const Material& m) : m_(m), kd_(m.kd) { with_microfacet(m.metallic, m.roughness, true); }
  // With the diffuse reflectance (a metal_rough material's base colour) at the point (a texture's), kept to at most
  // 1 - ks per channel.
  Bsdf(const Material& m, RGB albedo) : Bsdf(m, albedo, m.metallic, m.roughness) {}
  // The same with a metal_rough material's metallic and roughness at the point (its maps', Scene::metal_rough_at).
  // `outside`: wo is on the side the face's normal points to (a transmitting material's index ratio depends on it).
  Bsdf(const Material& m, RGB albedo, float metallic, float roughness, bool outside = true)
      : m_(m),
        kd_{std::min(albedo.x, 1 - m.ks.x - m.kr.x), std::min(albedo.y, 1 - m.ks.y - m.kr.y),
            std::min(albedo.z, 1 - m.ks.z - m.kr.z)} {
    with_microfacet(metallic, roughness, outside);
  }

  // Mirror and glass scatter into single directions: light sampling cannot reach them, only sample() can.
  bool is_delta() const { return m_.type == Material::Type::mirror || m_.type == Material::Type::glass; }
  // Non-delta lobes also scatter through the surface (rough glass): directions below n count.
  bool transmits() const { return microfacet_ && microfacet_->transmits(); }
  RGB eval(Vec3 n, Vec3 wo, Vec3 wi) const;
  float pdf(Vec3 n, Vec3 wo, Vec3 wi) const;

  struct Sample {
    Vec3 wi;
    RGB weight;      // f * |cos(wi)| / pdf
    float pdf;       // of wi (meaningless for delta lobes)
    bool delta;
    bool diffuse_lobe = false;  // sample_by_lobe() chose the Lambert lobe
  };
  // `entering`: wo is on the outside of the surface (for glass: which way refraction bends).
  std::optional<Sample> sample(Vec3 n, Vec3 wo, bool entering, float u0, float u1, float u2) const;

  // A glossy material's Phong lobe alone: whether it has one, and a direction drawn in proportion to it, weighted
  // by that lobe's f * cos / pdf (the diffuse part left out: the `glossy` LightOp's share of the BSDF).
  // A metal_rough material's glossy lobes are its specular lobe and its rough glass; u0 chooses between them (a
  // Phong lobe needs none).
  bool has_glossy_lobe() const { return microfacet_ || (m_.type == Material::Type::glossy && !is_black(m_.ks)); }
  std::optional<Sample> sample_glossy(Vec3 n, Vec3 wo, float u1, float u2, float u0 = 0.5f) const;
  // The glossy lobes' share of what the surface reflects towards wo (its mirror term aside): ks against kd for a
  // Phong lobe, MetalRoughness::glossy_share for a metal_rough material.
  float glossy_share(Vec3 n, Vec3 wo) const;
  // The lobes a diffuse cache lights: a Lambert lobe (diffuse and glossy materials' kd), or a metal_rough
  // material's base under its coating and its conductor's multiply scattered light (their share of each direction
  // of arrival depends on the elevation alone). What they reflect towards wo of light whose irradiance arrives in
  // elevation bands around n: kd / pi times the irradiance, or MetalRoughness::reflect_bands.
  bool has_diffuse_lobe() const {
    return microfacet_ ? microfacet_->has_diffuse() : !is_delta() && !is_black(kd_);
  }
  RGB reflect_bands(Vec3 n, Vec3 wo, const ElevationBands& irradiance) const;
  // A glossy surface's lobes one at a time (the directional cache answers its diffuse lobe's rays): the mirror term,
  // the Lambert lobe or the Phong lobe, chosen as sample() chooses; the weight is that lobe's f * cos over the
  // chance of choosing it times its density, `pdf` that product (for MIS with light samples of the same lobe).
  std::optional<Sample> sample_by_lobe(Vec3 n, Vec3 wo, float u0, float u1, float u2) const;
  // The parts of eval() and the densities sample_by_lobe() draws them with, for light samples' MIS per lobe.
  RGB eval_diffuse(Vec3 n, Vec3 wo, Vec3 wi) const;
  RGB eval_glossy(Vec3 n, Vec3 wo, Vec3 wi) const;
  float pdf_diffuse(Vec3 n, Vec3 wo, Vec3 wi) const;
  float pdf_glossy(Vec3 n, Vec3 wo, Vec3 wi) const;
  // A diffuse or glossy surface's mirror term alone (Material::kr), weighted by kr: the `specular` op's share.
  std::optional<Sample> sample_mirror_term(Vec3 n, Vec3 wo) const;

 private:
  float diffuse_probability() const;
  // The chance sample() takes a surface's mirror term (0 without one), in proportion to its reflectance.
  float mirror_probability() const;
  void with_microfacet(float metallic, float roughness, bool outside) {
    if (m_.type == Material::Type::metal_rough)
      microfacet_.emplace(kd_, metallic, roughness, Transmission{m_.transmission, m_.ior, outside});
  }
  // The microfacet model in the frame around n (z = n), for a metal_rough material.
  RGB eval_microfacet(Vec3 n, Vec3 wo, Vec3 wi) const;
  float pdf_microfacet(Vec3 n, Vec3 wo, Vec3 wi) const;
  std::optional<Sample> sample_microfacet(Vec3 n, Vec3 wo, float u0, float u1, float u2) const;
  const Material& m_;
  RGB kd_;
  std::optional<MetalRoughness> microfacet_;
};

// Fresnel reflectance of a dielectric interface for unpolarized light; cos_i > 0, eta = n_transmitted / n_incident.
float fresnel_dielectric(float cos_i, float eta);
Vec3 reflect(Vec3 wo, Vec3 n);
// Refracted direction, or nullopt on total internal reflection.
std::optional<Vec3> refract(Vec3 wo, Vec3 n, float eta);
// Orthonormal basis around n (Duff et al.).
void basis(Vec3 n, Vec3& t, Vec3& s);
Vec3 cosine_hemisphere(Vec3 n, float u, float v);

}  // namespace lf
