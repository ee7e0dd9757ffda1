#include "render/shading/bsdf.hpp"

#include <algorithm>
#include <cmath>

namespace lf {

void basis(Vec3 n, Vec3& t, Vec3& s) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z), b = n.x * n.y * a;
  t = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
  s = {b, sign + n.y * n.y * a, -n.y};
}

Vec3 cosine_hemisphere(Vec3 n, float u, float v) {
  Vec3 t, s;
  basis(n, t, s);
  const float r = std::sqrt(u), phi = 2.0f * kPi * v;
  return normalize(t * (r * std::cos(phi)) + s * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1.0f - u)));
}

Vec3 reflect(Vec3 wo, Vec3 n) { return n * (2.0f * dot(wo, n)) - wo; }

std::optional<Vec3> refract(Vec3 wo, Vec3 n, float eta) {
  const float cos_i = dot(wo, n);
  const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return std::nullopt;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  return normalize(-wo / eta + n * (cos_i / eta - cos_t));
}

float fresnel_dielectric(float cos_i, float eta) {
  const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  const float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5f * (rs * rs + rp * rp);
}

// Around the mirror direction r with density proportional to cos^ns.
static Vec3 phong_direction(Vec3 r, float ns, float u1, float u2) {
  Vec3 t, s;
  basis(r, t, s);
  const float cos_a = std::pow(u1, 1.0f / (ns + 1.0f));
  const float sin_a = std::sqrt(std::max(0.0f, 1.0f - cos_a * cos_a));
  const float phi = 2.0f * kPi * u2;
  return normalize(t * (sin_a * std::cos(phi)) + s * (sin_a * std::sin(phi)) + r * cos_a);
}

namespace {
struct Frame {
  Vec3 t, s, n;
  explicit Frame(Vec3 normal) : n(normal) { basis(normal, t, s); }
  Vec3 local(Vec3 v) const { return {dot(v, t), dot(v, s), dot(v, n)}; }
  Vec3 world(Vec3 v) const { return t * v.x + s * v.y + n * v.z; }
};
}  // namespace

RGB Bsdf::eval_microfacet(Vec3 n, Vec3 wo, Vec3 wi) const {
  if ((dot(n, wi) <= 0 && !microfacet_->transmits()) || dot(n, wo) <= 0) return {};
  const Frame f(n);
  return microfacet_->eval(f.local(wo), f.local(wi));
}

float Bsdf::pdf_microfacet(Vec3 n, Vec3 wo, Vec3 wi) const {
  if ((dot(n, wi) <= 0 && !microfacet_->transmits()) || dot(n, wo) <= 0) return 0;
  const Frame f(n);
  return microfacet_->pdf(f.local(wo), f.local(wi));
}

std::optional<Bsdf::Sample> Bsdf::sample_microfacet(Vec3 n, Vec3 wo, float u0, float u1, float u2) const {
  if (dot(n, wo) <= 0) return std::nullopt;
  const Frame f(n);
  const auto s = microfacet_->sample(f.local(wo), u0, u1, u2);
  if (!s || !(s->pdf > 0)) return std::nullopt;
  return Sample{normalize(f.world(s->wi)), s->weight, s->pdf, false};
}

std::optional<Bsdf::Sample> Bsdf::sample_glossy(Vec3 n, Vec3 wo, float u1, float u2, float u0) const {
  if (microfacet_) {
    if (dot(n, wo) <= 0) return std::nullopt;
    const Frame f(n);
    const auto s = microfacet_->sample_glossy(f.local(wo), u0, u1, u2);
    if (!s || !(s->pdf > 0)) return std::nullopt;
    return Sample{normalize(f.world(s->wi)), s->weight, s->pdf, false};
  }
  if (!has_glossy_lobe() || dot(n, wo) <= 0) return std::nullopt;
  const Vec3 wi = phong_direction(reflect(wo, n), m_.ns, u1, u2);
  const float cos_i = dot(n, wi);
  if (cos_i <= 0) return std::nullopt;
  // f = ks (ns + 2) / (2 pi) cos^ns(alpha), pdf = (ns + 1) / (2 pi) cos^ns(alpha): their ratio needs no power.
  const float ca = std::max(0.0f, dot(reflect(wo, n), wi));
  const float pdf = (m_.ns + 1.0f) / (2.0f * kPi) * std::pow(ca, m_.ns);
  return Sample{wi, m_.ks * ((m_.ns + 2.0f) / (m_.ns + 1.0f) * cos_i), pdf, false};
}

float Bsdf::glossy_share(Vec3 n, Vec3 wo) const {
  if (microfacet_) return dot(n, wo) > 0 ? microfacet_->glossy_share(Frame(n).local(wo)) : 0.0f;
  return has_glossy_lobe() ? 1.0f - diffuse_probability() : 0.0f;
}

RGB Bsdf::reflect_bands(Vec3 n, Vec3 wo, const ElevationBands& irradiance) const {
  if (microfacet_) return dot(n, wo) > 0 ? microfacet_->reflect_bands(Frame(n).local(wo), irradiance) : RGB{};
  RGB e{};
  for (const RGB& band : irradiance) e += band;
  return has_diffuse_lobe() ? kd_ * e * (1.0f / kPi) : RGB{};
}

std::optional<Bsdf::Sample> Bsdf::sample_mirror_term(Vec3 n, Vec3 wo) const {
  if (!m_.has_mirror_term() || dot(n, wo) <= 0) return std::nullopt;
  return Sample{reflect(wo, n), m_.kr, 1.0f, true};
}

// Normalized Phong: (ns + 2) / (2 pi) cos^ns(alpha) integrates, times cos(theta), to at most 1.
static float phong(float ns, float cos_alpha) {
  return cos_alpha > 0 ? (ns + 2.0f) / (2.0f * kPi) * std::pow(cos_alpha, ns) : 0.0f;
}

RGB Bsdf::eval_diffuse(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (is_delta() || microfacet_ || dot(n, wi) <= 0 || dot(n, wo) <= 0) return {};
  return kd_ * (1.0f / kPi);
}

RGB Bsdf::eval_glossy(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (microfacet_) return eval_microfacet(n, wo, wi);
  if (!has_glossy_lobe() || dot(n, wi) <= 0 || dot(n, wo) <= 0) return {};
  return m_.ks * phong(m_.ns, dot(reflect(wo, n), wi));
}

float Bsdf::pdf_diffuse(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (is_delta() || microfacet_ || dot(n, wi) <= 0 || dot(n, wo) <= 0) return 0;
  const float pd = m_.type == Material::Type::glossy ? diffuse_probability() : 1.0f;
  return (1.0f - mirror_probability()) * pd * dot(n, wi) / kPi;
}

float Bsdf::pdf_glossy(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (microfacet_) return pdf_microfacet(n, wo, wi);
  if (m_.type != Material::Type::glossy || dot(n, wi) <= 0 || dot(n, wo) <= 0) return 0;
  const float ca = dot(reflect(wo, n), wi);
  const float lobe = ca > 0 ? (m_.ns + 1.0f) / (2.0f * kPi) * std::pow(ca, m_.ns) : 0.0f;
  return (1.0f - mirror_probability()) * (1.0f - diffuse_probability()) * lobe;
}

std::optional<Bsdf::Sample> Bsdf::sample_by_lobe(Vec3 n, Vec3 wo, float u0, float u1, float u2) const {
  if (m_.type != Material::Type::glossy || dot(n, wo) <= 0) return sample(n, wo, true, u0, u1, u2);
  if (const float pr = mirror_probability(); pr > 0) {
    if (u0 < pr) return Sample{reflect(wo, n), m_.kr * (1.0f / pr), pr, true};
    u0 = (u0 - pr) / (1.0f - pr);
  }
  const bool diffuse = u0 < diffuse_probability();
  const Vec3 wi = diffuse ? cosine_hemisphere(n, u1, u2) : phong_direction(reflect(wo, n), m_.ns, u1, u2);
  const float cos_i = dot(n, wi);
  if (cos_i <= 0) return std::nullopt;
  const float p = diffuse ? pdf_diffuse(n, wo, wi) : pdf_glossy(n, wo, wi);
  if (!(p > 0)) return std::nullopt;
  const RGB f = diffuse ? eval_diffuse(n, wo, wi) : eval_glossy(n, wo, wi);
  Sample s{wi, f * (cos_i / p), p, false};
  s.diffuse_lobe = diffuse;
  return s;
}

float Bsdf::mirror_probability() const {
  if (!m_.has_mirror_term()) return 0.0f;
  const float r = average(m_.kr), rest = average(kd_) + (m_.type == Material::Type::glossy ? average(m_.ks) : 0.0f);
  return r / (r + rest);
}

float Bsdf::diffuse_probability() const {
  const float d = average(kd_), g = average(m_.ks);
  return d + g > 0 ? d / (d + g) : 1.0f;
}


RGB Bsdf::eval(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (microfacet_) return eval_microfacet(n, wo, wi);
  if (is_delta() || dot(n, wi) <= 0 || dot(n, wo) <= 0) return {};
  RGB f = kd_ * (1.0f / kPi);
  if (m_.type == Material::Type::glossy) f += m_.ks * phong(m_.ns, dot(reflect(wo, n), wi));
  return f;
}

float Bsdf::pdf(Vec3 n, Vec3 wo, Vec3 wi) const {
  if (microfacet_) return pdf_microfacet(n, wo, wi);
  if (is_delta() || dot(n, wi) <= 0 || dot(n, wo) <= 0) return 0;
  const float diffuse = dot(n, wi) / kPi;
  // sample() reaches the other lobes only when it does not take the mirror term.
  const float other = 1.0f - mirror_probability();
  if (m_.type != Material::Type::glossy) return other * diffuse;
  const float pd = diffuse_probability();
  const float ca = dot(reflect(wo, n), wi);
  const float lobe = ca > 0 ? (m_.ns + 1.0f) / (2.0f * kPi) * std::pow(ca, m_.ns) : 0.0f;
  return other * (pd * diffuse + (1 - pd) * lobe);
}

std::optional<Bsdf::Sample> Bsdf::sample(Vec3 n, Vec3 wo, bool entering, float u0, float u1, float u2) const {
  switch (m_.type) {
    case Material::Type::mirror:
      return Sample{reflect(wo, n), m_.ks, 1.0f, true};
    case Material::Type::glass: {
      // n faces wo; the ratio of indices depends on which side wo is.
      const float eta = entering ? m_.ior : 1.0f / m_.ior;
      const float f = fresnel_dielectric(std::max(0.0f, dot(wo, n)), eta);
      if (u0 < f) return Sample{reflect(wo, n), RGB{1, 1, 1}, f, true};
      auto t = refract(wo, n, eta);
      if (!t) return Sample{reflect(wo, n), RGB{1, 1, 1}, 1.0f, true};
      // Light is filtered once, where it enters (a closed object tints what passes through it once).
      return Sample{*t, entering ? m_.tf : RGB{1, 1, 1}, 1.0f - f, true};
    }
    case Material::Type::metal_rough:
      return sample_microfacet(n, wo, u0, u1, u2);
    default: break;
  }
  if (dot(n, wo) <= 0) return std::nullopt;
  if (const float pr = mirror_probability(); pr > 0) {
    if (u0 < pr) return Sample{reflect(wo, n), m_.kr * (1.0f / pr), pr, true};
    u0 = (u0 - pr) / (1.0f - pr);  // pdf() counts the other lobes' share
  } else if (m_.type == Material::Type::diffuse) {
    // Lambert alone, the commonest case: pdf() and eval() below, with the checks they would repeat left out and the
    // same arithmetic in the same order, so the same bits.
    const Vec3 wi = cosine_hemisphere(n, u1, u2);
    const float cos_i = dot(n, wi);
    if (cos_i <= 0) return std::nullopt;
    const float p = cos_i / kPi;
    if (!(p > 0)) return std::nullopt;
    return Sample{wi, (kd_ * (1.0f / kPi)) * (cos_i / p), p, false};
  }
  Vec3 wi;
  const float pd = m_.type == Material::Type::glossy ? diffuse_probability() : 1.0f;
  if (u0 < pd) {
    wi = cosine_hemisphere(n, u1, u2);
  } else {
    wi = phong_direction(reflect(wo, n), m_.ns, u1, u2);
  }
  const float cos_i = dot(n, wi);
  if (cos_i <= 0) return std::nullopt;
  const float p = pdf(n, wo, wi);
  if (!(p > 0)) return std::nullopt;
  return Sample{wi, eval(n, wo, wi) * (cos_i / p), p, false};
}

}  // namespace lf
