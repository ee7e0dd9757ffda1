// BSDFs against closed forms and against each other: sample() weights must agree with eval()/pdf(), densities
// must integrate to what sample() produces, Fresnel and Snell must hold.
#include "render/shading/bsdf.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "render/shading/sampler.hpp"

namespace lf {

static Vec3 uniform_hemisphere(Vec3 n, float u, float v) {
  Vec3 t, s;
  basis(n, t, s);
  const float z = u, r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * v;
  return t * (r * std::cos(phi)) + s * (r * std::sin(phi)) + n * z;
}

static const Vec3 kN{0, 0, 1};

static Vec3 direction(float theta_deg) {
  const float t = theta_deg * kPi / 180;
  return {std::sin(t), 0, std::cos(t)};
}

TEST(Bsdf, DiffuseReflectsItsAlbedo) {
  Material m{"d", {0.6f, 0.3f, 0.1f}, {}};
  Bsdf b(m);
  Rng rng(1, 1);
  double integrated_x = 0, integrated_z = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    auto s = b.sample(kN, direction(30), true, rng.uniform(), rng.uniform(), rng.uniform());
    ASSERT_TRUE(s);
    EXPECT_NEAR(s->weight.x, 0.6f, 1e-5f);  // cosine sampling: every weight is kd
    Vec3 wi = uniform_hemisphere(kN, rng.uniform(), rng.uniform());
    RGB f = b.eval(kN, direction(30), wi) * (dot(kN, wi) * 2 * kPi);
    integrated_x += f.x;
    integrated_z += f.z;
  }
  EXPECT_NEAR(integrated_x / n, 0.6, 0.01);
  EXPECT_NEAR(integrated_z / n, 0.1, 0.002);
}

TEST(Bsdf, GlossyEvalPdfAndSampleAgree) {
  Material m = material_from_mtl("g", {0.3f, 0.3f, 0.3f}, {0.6f, 0.6f, 0.6f}, {}, 40, 1, 2);
  ASSERT_EQ(m.type, Material::Type::glossy);
  Bsdf b(m);
  for (float theta : {0.0f, 45.0f, 75.0f}) {
    const Vec3 wo = direction(theta);
    Rng rng(2, static_cast<uint64_t>(theta));
    const int n = 400000;
    double pdf_integral = 0, valid = 0, albedo_sampled = 0, albedo_integrated = 0;
    for (int i = 0; i < n; ++i) {
      Vec3 wi = uniform_hemisphere(kN, rng.uniform(), rng.uniform());
      pdf_integral += b.pdf(kN, wo, wi) * 2 * kPi;
      albedo_integrated += b.eval(kN, wo, wi).x * (dot(kN, wi) * 2 * kPi);
      if (auto s = b.sample(kN, wo, true, rng.uniform(), rng.uniform(), rng.uniform())) {
        valid += 1;
        albedo_sampled += s->weight.x;
        EXPECT_NEAR(s->pdf, b.pdf(kN, wo, s->wi), 1e-3f * s->pdf);
      }
    }
    // The density over the hemisphere is the share of samples that land in it (the lobe may dip below).
    EXPECT_NEAR(pdf_integral / n, valid / n, 0.02) << theta;
    // Two estimates of the directional albedo agree, and no energy is created.
    EXPECT_NEAR(albedo_sampled / n, albedo_integrated / n, 0.03) << theta;
    EXPECT_LE(albedo_sampled / n, 1.0) << theta;
  }
}

// A metal_rough material is glTF's model on any shading normal: the same values as the model in its own frame, sample
// weights f cos / pdf, its directional albedo (all of it the glossy lobe's, none the Lambert lobe's) within 1, and
// a base colour from a texture used as given.
TEST(Bsdf, MetalRoughIsTheMicrofacetModelAroundTheNormal) {
  Material m{"ball", {0.9f, 0.6f, 0.3f}, {}};
  m.type = Material::Type::metal_rough;
  m.metallic = 0.5f;
  m.roughness = 0.4f;
  const Vec3 n = normalize(Vec3{0.3f, -0.5f, 0.8f});
  Vec3 t, s;
  basis(n, t, s);
  const MetalRoughness model({0.9f, 0.6f, 0.3f}, 0.5f, 0.4f);
  const Bsdf b(m);
  EXPECT_FALSE(b.is_delta());
  EXPECT_TRUE(b.has_glossy_lobe());
  Rng rng(5, 5);
  for (float theta : {10.0f, 60.0f, 80.0f}) {
    const Vec3 local_wo = direction(theta), wo = t * local_wo.x + s * local_wo.y + n * local_wo.z;
    double albedo = 0;
    const int count = 100000;
    for (int i = 0; i < count; ++i) {
      const Vec3 local_wi = uniform_hemisphere(kN, rng.uniform(), rng.uniform());
      const Vec3 wi = t * local_wi.x + s * local_wi.y + n * local_wi.z;
      const RGB f = b.eval(n, wo, wi), expected = model.eval(local_wo, local_wi);
      ASSERT_NEAR(f.y, expected.y, 1e-4f * std::max(1.0f, expected.y));
      EXPECT_EQ(b.eval_glossy(n, wo, wi), f);
      EXPECT_TRUE(is_black(b.eval_diffuse(n, wo, wi)));
      EXPECT_EQ(b.pdf_diffuse(n, wo, wi), 0.0f);
      EXPECT_NEAR(b.pdf(n, wo, wi), model.pdf(local_wo, local_wi), 1e-4f * std::max(1.0f, b.pdf(n, wo, wi)));
      if (auto smp = b.sample(n, wo, true, rng.uniform(), rng.uniform(), rng.uniform())) {
        const RGB expect = b.eval(n, wo, smp->wi) * (dot(n, smp->wi) / smp->pdf);
        ASSERT_NEAR(smp->weight.x, expect.x, 1e-3f * std::max(1.0f, expect.x));
        albedo += smp->weight.y;
      }
      // The glossy lobes alone: the model's, turned around the normal.
      const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
      const auto g = b.sample_glossy(n, wo, u1, u2, u0);
      const auto expected_g = model.sample_glossy(local_wo, u0, u1, u2);
      ASSERT_EQ(g.has_value(), expected_g.has_value());
      if (g) {
        EXPECT_NEAR(g->pdf, expected_g->pdf, 1e-3f * g->pdf);
        EXPECT_NEAR(g->weight.y, expected_g->weight.y, 1e-3f * std::max(1.0f, g->weight.y));
      }
    }
    EXPECT_LE(albedo / count, 1.0) << theta;
    EXPECT_GT(albedo / count, 0.4) << theta;
  }
  // A texture's colour is the base colour.
  const Bsdf white(m, RGB{1, 1, 1}), dark(m, RGB{0.1f, 0.1f, 0.1f});
  EXPECT_GT(white.eval(n, n, n).y, dark.eval(n, n, n).y);
}

TEST(Bsdf, MirrorReflectsAboutTheNormal) {
  Material m = material_from_mtl("m", {}, {0.9f, 0.9f, 0.9f}, {}, 1000, 1, 5);
  ASSERT_EQ(m.type, Material::Type::mirror);
  auto s = Bsdf(m).sample(kN, direction(30), true, 0.5f, 0.5f, 0.5f);
  ASSERT_TRUE(s && s->delta);
  EXPECT_NEAR(s->wi.x, -direction(30).x, 1e-6f);
  EXPECT_NEAR(s->wi.z, direction(30).z, 1e-6f);
  EXPECT_EQ(s->weight, (RGB{0.9f, 0.9f, 0.9f}));
  EXPECT_EQ(Bsdf(m).eval(kN, direction(30), s->wi), RGB{});  // a delta lobe has no density to evaluate
}

TEST(Bsdf, GlassFollowsFresnelAndSnell) {
  EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);           // ((1.5 - 1) / (1.5 + 1))^2
  EXPECT_EQ(fresnel_dielectric(std::cos(0.8f), 1 / 1.5f), 1.0f);  // 45.8 deg, beyond the critical angle of 41.8
  Material m = material_from_mtl("glass", {}, {}, {}, 0, 1.5f, 7);
  ASSERT_EQ(m.type, Material::Type::glass);
  Bsdf b(m);
  const Vec3 wo = direction(40);
  // Entering: refract (u0 above F) obeys sin(t) = sin(i) / 1.5, on the far side.
  auto t = b.sample(kN, wo, true, 0.99f, 0, 0);
  ASSERT_TRUE(t);
  EXPECT_LT(t->wi.z, 0.0f);
  EXPECT_NEAR(std::sqrt(1 - t->wi.z * t->wi.z), std::sin(40 * kPi / 180) / 1.5f, 1e-5f);
  // The share of reflections is the Fresnel reflectance.
  Rng rng(3, 3);
  int reflected = 0;
  for (int i = 0; i < 100000; ++i) reflected += b.sample(kN, wo, true, rng.uniform(), 0, 0)->wi.z > 0;
  EXPECT_NEAR(reflected / 100000.0, fresnel_dielectric(wo.z, 1.5f), 0.005);
  // Leaving at 60 degrees from inside: total internal reflection, always.
  for (float u : {0.0f, 0.5f, 0.99f}) EXPECT_GT(b.sample(kN, direction(60), false, u, 0, 0)->wi.z, 0.0f);
}

TEST(Bsdf, MtlMappingKeepsEnergyBounded) {
  Material m = material_from_mtl("g", {0.8f, 0.8f, 0.8f}, {0.5f, 0.5f, 0.5f}, {}, 10, 1, 2);
  EXPECT_NEAR(m.kd.x + m.ks.x, 1.0f, 1e-6f);  // scaled from 1.3 down to 1
  EXPECT_EQ(material_from_mtl("d", {0.5f, 0.5f, 0.5f}, {}, {}, 10, 1.5f, 2).type, Material::Type::diffuse);
  EXPECT_FLOAT_EQ(material_from_mtl("s", {}, {0.3f, 0.3f, 0.3f}, {}, 200, 2.5f, 7).ior, 2.5f);
}

// MTL illum 3 with Kd ("reflection and ray trace on"): Kd stays, and Ks is a mirror term shared with the Phong lobe
// where Ns > 0 (half each), Kd + Ks capped at 1; without Kd it is the mirror it always was.
TEST(Bsdf, Illum3KeepsKdBesideTheMirror) {
  Material shiny = material_from_mtl("s", {0.6f, 0.5f, 0.4f}, {0.3f, 0.3f, 0.3f}, {}, 50, 1, 3);
  EXPECT_EQ(shiny.type, Material::Type::glossy);
  EXPECT_FLOAT_EQ(shiny.kd.x, 0.6f);
  EXPECT_FLOAT_EQ(shiny.ks.x, 0.15f);
  EXPECT_FLOAT_EQ(shiny.kr.x, 0.15f);
  EXPECT_TRUE(shiny.has_mirror_term());
  Material plain = material_from_mtl("p", {0.9f, 0.9f, 0.9f}, {0.3f, 0.3f, 0.3f}, {}, 0, 1, 3);
  EXPECT_EQ(plain.type, Material::Type::diffuse);
  EXPECT_NEAR(plain.kd.x + plain.kr.x, 1.0f, 1e-6f);  // 1.2 scaled to 1
  EXPECT_EQ(material_from_mtl("m", {}, {0.9f, 0.9f, 0.9f}, {}, 0, 1, 3).type, Material::Type::mirror);
}

// A diffuse or glossy surface with a mirror term: sample() takes the mirror (weight kr over its probability) or the
// other lobes, whose weights still equal eval * cos / pdf; in all it reflects kd + lobe + kr. A white furnace: Lambert
// 0.5 and a mirror 0.3 reflect 0.8 exactly; with a Phong lobe 0.2 (n = 20, at normal incidence, where it loses
// almost nothing below the horizon) about 1.
TEST(Bsdf, AMirrorTermAddsItsReflectance) {
  Material d{"d", {0.5f, 0.5f, 0.5f}, {}};
  d.kr = {0.3f, 0.3f, 0.3f};
  Material g = d;
  g.type = Material::Type::glossy;
  g.ks = {0.2f, 0.2f, 0.2f};
  g.ns = 20;
  for (const Material* m : {&d, &g}) {
    Bsdf b(*m);
    EXPECT_FALSE(b.is_delta()) << "light sampling still reaches its other lobes";
    Rng rng(5, 5);
    const int n = 400000;
    double reflected = 0, mirrored = 0;
    for (int i = 0; i < n; ++i) {
      auto s = b.sample(kN, kN, true, rng.uniform(), rng.uniform(), rng.uniform());
      if (!s) continue;
      reflected += s->weight.x;
      if (s->delta) {
        mirrored += s->weight.x;
        EXPECT_NEAR(s->wi.z, 1.0f, 1e-6f);
      } else {
        const RGB expected = b.eval(kN, kN, s->wi) * (dot(kN, s->wi) / b.pdf(kN, kN, s->wi));
        EXPECT_NEAR(s->weight.x, expected.x, 1e-4f * std::max(1.0f, expected.x));
      }
    }
    EXPECT_NEAR(mirrored / n, 0.3, 0.005) << m->name;
    EXPECT_NEAR(reflected / n, m == &d ? 0.8 : 0.9987, 0.005) << m->name;
    auto alone = b.sample_mirror_term(kN, direction(30));
    ASSERT_TRUE(alone);
    EXPECT_FLOAT_EQ(alone->weight.x, 0.3f);
    EXPECT_TRUE(alone->delta);
  }
}

// A glossy surface sampled one lobe at a time reflects what sample() does (the same lobe choice, each lobe's weight
// over its own density), and the lobes' densities add up to pdf().
TEST(Bsdf, SamplingByLobeReflectsTheSame) {
  Material g = material_from_mtl("g", {0.4f, 0.4f, 0.4f}, {0.4f, 0.4f, 0.4f}, {}, 30, 1, 3);  // Kd, lobe, mirror
  ASSERT_TRUE(g.has_mirror_term());
  Bsdf b(g);
  const Vec3 wo = direction(35);
  Rng rng(9, 9);
  const int n = 400000;
  double whole = 0, by_lobe = 0, diffuse_share = 0;
  for (int i = 0; i < n; ++i) {
    const float u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    if (auto s = b.sample(kN, wo, true, u0, u1, u2)) whole += s->weight.x;
    if (auto s = b.sample_by_lobe(kN, wo, u0, u1, u2)) {
      by_lobe += s->weight.x;
      if (s->diffuse_lobe) {
        diffuse_share += s->weight.x;
        EXPECT_NEAR(s->pdf, b.pdf_diffuse(kN, wo, s->wi), 1e-5f);
      }
      if (!s->delta) {
        EXPECT_NEAR(b.pdf_diffuse(kN, wo, s->wi) + b.pdf_glossy(kN, wo, s->wi), b.pdf(kN, wo, s->wi), 1e-4f);
      }
    }
  }
  EXPECT_NEAR(by_lobe / n, whole / n, 0.005);
  EXPECT_NEAR(diffuse_share / n, 0.4, 0.005) << "the Lambert lobe's own albedo";
}

// MTL Tf tints glass: light keeps tf where it enters (once per passage through a closed object), nothing where it
// leaves, and the Fresnel reflection stays white. A missing Tf (read as 0 0 0) leaves the glass clear.
TEST(Bsdf, TfFiltersWhatEntersGlass) {
  Material tinted = material_from_mtl("t", {}, {}, {}, 0, 1.5f, 7, {0.2f, 0.5f, 1.0f});
  EXPECT_FLOAT_EQ(tinted.tf.y, 0.5f);
  EXPECT_FLOAT_EQ(material_from_mtl("c", {}, {}, {}, 0, 1.5f, 7, {}).tf.x, 1.0f);
  Bsdf b(tinted);
  const Vec3 wo = direction(20);
  const float f = fresnel_dielectric(wo.z, 1.5f);
  auto in = b.sample(kN, wo, true, 0.999f, 0, 0);
  ASSERT_TRUE(in && in->wi.z < 0);
  EXPECT_FLOAT_EQ(in->weight.x, 0.2f);
  EXPECT_FLOAT_EQ(in->weight.z, 1.0f);
  auto out = b.sample(kN, wo, false, 0.999f, 0, 0);
  ASSERT_TRUE(out && out->wi.z < 0);
  EXPECT_FLOAT_EQ(out->weight.x, 1.0f);
  auto reflected = b.sample(kN, wo, true, 0.5f * f, 0, 0);
  ASSERT_TRUE(reflected && reflected->wi.z > 0);
  EXPECT_FLOAT_EQ(reflected->weight.x, 1.0f);
}

}  // namespace lf
