// specular against closed forms.
#include <gtest/gtest.h>

#include "render/shading/bsdf.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

struct Net {
  std::unique_ptr<LightOp> input, op;
  LocalInputs none, inputs;
};

std::vector<RGB> run_specular(const Scene& scene, const RayTracer& tracer, const char* input_kind,
                              Value::Map input_params, Value::Map params, const ShadingPoints& pts) {
  Net n;
  SceneContext ctx{&scene, &tracer};
  n.input = create_lightop(*find_lightop_kind(input_kind), ParamTable(std::move(input_params), input_kind));
  run_to_completion(n.input->setup(ctx, n.none));
  n.op = create_lightop(*find_lightop_kind("specular"), ParamTable(std::move(params), "specular"));
  n.inputs = LocalInputs({{n.input.get(), &n.none}});
  run_to_completion(n.op->setup(ctx, n.inputs));
  std::vector<RGB> out(pts.size());
  run_to_completion(n.op->shade(pts, out, n.inputs));
  return out;
}

// Light from below through a glass slab seen at normal incidence: each interface reflects R = ((n-1)/(n+1))^2 and
// the inter-reflections add up to a transmittance of (1 - R) / (1 + R).
TEST(Specular, GlassSlabTransmitsOneMinusROverOnePlusR) {
  Scene s;
  auto glass = s.add_material(material_from_mtl("glass", {}, {}, {}, 0, 1.5f, 7));
  auto glow = s.add_material({"glow", {}, {1, 1, 1}});
  s.add_quad({-50, 1, -50}, {-50, 1, 50}, {50, 1, 50}, {50, 1, -50}, glass);          // top, facing up
  s.add_quad({-50, 0.9f, -50}, {50, 0.9f, -50}, {50, 0.9f, 50}, {-50, 0.9f, 50}, glass);  // bottom, facing down
  s.add_quad({-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}, glow);           // floor, facing up
  ASSERT_TRUE(s.finalize("slab").ok());
  RayTracer tracer(s);
  ShadingPoints pts;
  for (int i = 0; i < 4; ++i) pts.push_back({0.1f * i, 1, 0}, {0, 1, 0}, {0, 1, 0}, glass, sample_key(i, 0), 0);
  // The floor reflects nothing, so its input (`direct`) adds nothing: what arrives is the floor's own emission,
  // which a chain counts itself (inputs return reflected light only, as everywhere in a network).
  auto out = run_specular(s, tracer, "direct", {}, Value::Map{{"samples", 20000}, {"max_depth", 64}}, pts);
  const float r = fresnel_dielectric(1.0f, 1.5f);
  for (const RGB& l : out) EXPECT_NEAR(l.y / ((1 - r) / (1 + r)), 1.0, 0.01);

  // One chain asks the input, 20000 look for the floor's emission: the emission is their mean.
  out = run_specular(s, tracer, "direct", {}, Value::Map{{"samples", 1}, {"emission_samples", 20000}, {"max_depth", 64}}, pts);
  for (const RGB& l : out) EXPECT_NEAR(l.y / ((1 - r) / (1 + r)), 1.0, 0.01);
}

// A mirror passes on Ks times what its input says about the point its reflection lands on.
TEST(Specular, MirrorReflectsItsInputsLight) {
  Scene s;
  auto mirror = s.add_material(material_from_mtl("mirror", {}, {0.9f, 0.9f, 0.9f}, {}, 0, 1, 3));
  auto white = s.add_material({"white", {0.8f, 0.8f, 0.8f}, {}});
  auto light = s.add_material({"light", {}, {4, 4, 4}});
  s.add_quad({-1, 0, 1}, {-1, 2, 1}, {1, 2, 1}, {1, 0, 1}, mirror);            // a wall at z = 1 facing -z
  s.add_quad({-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, white);           // floor
  s.add_quad({-1, 3, -2}, {1, 3, -2}, {1, 3, 0}, {-1, 3, 0}, light);          // light facing down
  ASSERT_TRUE(s.finalize("mirror").ok());
  RayTracer tracer(s);
  // Looking at the mirror at (0, 1, 1) from (0, 2, -1): the reflection goes to (0, 0, -1) on the floor.
  const Vec3 wo = normalize(Vec3{0, 1, -2});
  ShadingPoints on_mirror;
  on_mirror.push_back({0, 1, 1}, {0, 0, -1}, wo, mirror, sample_key(0, 0), 0);
  auto out = run_specular(s, tracer, "direct", Value::Map{{"light_samples", 200000}}, Value::Map{}, on_mirror);
  // The same landing point asked of `direct` directly.
  ShadingPoints landing;
  landing.push_back({0, 0, -1}, {0, 1, 0}, normalize(Vec3{0, 1, 2}), white, sample_key(1, 0));
  auto d = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 200000}}, "d"));
  LocalInputs none;
  run_to_completion(d->setup(SceneContext{&s, &tracer}, none));
  std::vector<RGB> expected(1);
  run_to_completion(d->shade(landing, expected, none));
  ASSERT_GT(expected[0].y, 0.0f);
  EXPECT_NEAR(out[0].y / (0.9f * expected[0].y), 1.0, 0.01);
  // Chains that only look for emitters do not dilute what the asking chain brings back.
  auto with_emission_chains = run_specular(s, tracer, "direct", Value::Map{{"light_samples", 200000}},
                                           Value::Map{{"emission_samples", 8}}, on_mirror);
  EXPECT_NEAR(with_emission_chains[0].y / (0.9f * expected[0].y), 1.0, 0.01);

  // A point on the (diffuse) floor is not specular's business.
  auto none_out = run_specular(s, tracer, "direct", {}, Value::Map{}, landing);
  EXPECT_EQ(none_out[0], RGB{});
}

}  // namespace
}  // namespace lf
