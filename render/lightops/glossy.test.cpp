// glossy against closed forms: the lobe's albedo in a furnace, and the path tracer's split of a purely glossy
// surface into direct light and the rest.
#include <gtest/gtest.h>

#include <cmath>

#include "render/shading/bsdf.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

std::vector<RGB> run(const char* kind, Value::Map params, const SceneContext& ctx, const ShadingPoints& pts,
                     const char* input_kind = nullptr, Value::Map input_params = {}) {
  LocalInputs none;
  std::unique_ptr<LightOp> input;
  if (input_kind) {
    input = create_lightop(*find_lightop_kind(input_kind), ParamTable(std::move(input_params), input_kind));
    run_to_completion(input->setup(ctx, none));
  }
  LocalInputs inputs = input ? LocalInputs({{input.get(), &none}}) : LocalInputs();
  auto op = create_lightop(*find_lightop_kind(kind), ParamTable(std::move(params), kind));
  run_to_completion(op->setup(ctx, inputs));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, inputs));
  return out;
}

// The Phong lobe's albedo seen from wo at angle theta_o: the integral of (ns + 2) / (2 pi) cos^ns(alpha) cos(theta)
// over the upper hemisphere, by the midpoint rule.
double phong_albedo(float ns, float theta_o) {
  const Vec3 n{0, 0, 1}, wo{std::sin(theta_o), 0, std::cos(theta_o)};
  const Vec3 r = reflect(wo, n);
  const int rows = 2000, cols = 2000;
  double sum = 0;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const double t = (i + 0.5) / rows * M_PI / 2, p = (j + 0.5) / cols * 2 * M_PI;
      const Vec3 wi{static_cast<float>(std::sin(t) * std::cos(p)), static_cast<float>(std::sin(t) * std::sin(p)),
                    static_cast<float>(std::cos(t))};
      const double ca = std::max(0.0f, dot(r, wi));
      sum += (ns + 2) / (2 * M_PI) * std::pow(ca, ns) * std::cos(t) * std::sin(t);
    }
  return sum * (M_PI / 2 / rows) * (2 * M_PI / cols);
}

// In a box whose walls all emit radiance 1 (inwards), what the lobe reflects is its albedo: ks at normal incidence
// (the lobe then lies wholly above the surface), less at grazing angles where the horizon clips it.
TEST(Glossy, FurnaceGivesTheLobesAlbedo) {
  for (const float ns : {5.0f, 40.0f, 1000.0f}) {
    Scene s;
    auto glow = s.add_material({"glow", {}, {1, 1, 1}});
    Material shiny = material_from_mtl("shiny", {0.2f, 0.2f, 0.2f}, {0.3f, 0.3f, 0.3f}, {}, ns, 1, 2);
    ASSERT_EQ(shiny.type, Material::Type::glossy);
    auto glossy = s.add_material(shiny);
    test::add_closed_box(s, glow);
    ASSERT_TRUE(s.finalize("furnace").ok());
    RayTracer tracer(s);
    SceneContext ctx{&s, &tracer};
    for (const float theta : {0.0f, 1.0f}) {
      ShadingPoints pts;
      const Vec3 wo{std::sin(theta), 0, std::cos(theta)};
      for (int i = 0; i < 8; ++i) pts.push_back({0.5f, 0.5f, 0.5f}, {0, 0, 1}, wo, glossy, sample_key(i, 0));
      const auto out = run("glossy", Value::Map{{"samples", 4096}}, ctx, pts, "emission");
      const double expected = shiny.ks.y * phong_albedo(ns, theta);
      double mean = 0;
      for (const RGB& l : out) mean += l.y / out.size();
      EXPECT_NEAR(mean / expected, 1.0, 0.01) << "ns " << ns << " theta " << theta;
      if (theta == 0.0f) {
        EXPECT_NEAR(expected, shiny.ks.y, 0.002);
      }
    }
  }
}

// Points without a glossy lobe get nothing; nor does light straight from an emitter (that is `direct`'s L G): over
// an input that returns reflected light only, a lobe that sees only emitters reflects nothing.
TEST(Glossy, LeavesDiffusePointsAndEmittersAlone) {
  Scene s;
  auto glow = s.add_material({"glow", {}, {1, 1, 1}});
  auto glossy = s.add_material(material_from_mtl("shiny", {0.2f, 0.2f, 0.2f}, {0.3f, 0.3f, 0.3f}, {}, 20, 1, 2));
  auto matte = s.add_material({"matte", {0.5f, 0.5f, 0.5f}, {}});
  test::add_closed_box(s, glow);
  ASSERT_TRUE(s.finalize("furnace").ok());
  RayTracer tracer(s);
  SceneContext ctx{&s, &tracer};
  ShadingPoints pts;
  pts.push_back({0.5f, 0.5f, 0.5f}, {0, 0, 1}, {0, 0, 1}, matte, sample_key(0, 0));
  pts.push_back({0.5f, 0.5f, 0.5f}, {0, 0, 1}, {0, 0, 1}, glossy, sample_key(1, 0));
  const auto out = run("glossy", Value::Map{{"samples", 64}}, ctx, pts, "direct");
  EXPECT_EQ(out[0], RGB{});
  EXPECT_EQ(out[1], RGB{});  // the walls emit but reflect nothing
}

// On a purely glossy floor (Kd 0) in a lit room, the path tracer's light is direct light (L G) plus what the lobe
// sees reflected (the rest): direct + glossy over a path tracer = the path tracer, within their noise.
TEST(Glossy, WithDirectAddsUpToThePathTracer) {
  Scene s;
  auto white = s.add_material({"white", {0.7f, 0.7f, 0.7f}, {}});
  auto light = s.add_material({"light", {}, {5, 5, 5}});
  auto floor = s.add_material(material_from_mtl("floor", {}, {0.8f, 0.8f, 0.8f}, {}, 8, 1, 2));
  s.add_quad({0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, floor);  // floor, facing up
  s.add_quad({0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}, white);  // ceiling, facing down
  s.add_quad({0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}, white);  // walls, facing in
  s.add_quad({1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}, white);
  s.add_quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}, white);
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, white);
  s.add_quad({0.4f, 0.99f, 0.4f}, {0.6f, 0.99f, 0.4f}, {0.6f, 0.99f, 0.6f}, {0.4f, 0.99f, 0.6f}, light);  // facing down
  ASSERT_TRUE(s.finalize("glossy room").ok());
  RayTracer tracer(s);
  SceneContext ctx{&s, &tracer};
  ShadingPoints pts;
  const Vec3 wo = normalize(Vec3{0.3f, 0.6f, 0.2f});
  // Each of 4 places 4 times over (other keys), averaged.
  const int places = 4, copies = 4;
  for (int i = 0; i < places; ++i)
    for (int c = 0; c < copies; ++c)
      pts.push_back({0.2f + 0.2f * i, 0, 0.3f}, {0, 1, 0}, wo, floor, sample_key(static_cast<uint32_t>(i * copies + c), 0), 0);
  const auto reference = run("pathtrace", Value::Map{{"samples", 65536}, {"max_depth", 64}}, ctx, pts);
  const auto direct = run("direct", Value::Map{{"light_samples", 16384}}, ctx, pts);
  const auto rest = run("glossy", Value::Map{{"samples", 65536}}, ctx, pts, "pathtrace", Value::Map{{"max_depth", 63}});
  for (int i = 0; i < places; ++i) {
    double d = 0, r = 0, ref = 0;
    for (int c = 0; c < copies; ++c) {
      const size_t k = static_cast<size_t>(i * copies + c);
      d += direct[k].y, r += rest[k].y, ref += reference[k].y;
    }
    EXPECT_GT(r, 0.1 * d) << i;  // the room's walls are a visible part of the floor's light
    EXPECT_NEAR((d + r) / ref, 1.0, 0.015) << i << ": direct " << d / copies << " rest " << r / copies << " path tracer " << ref / copies;
  }
}

}  // namespace
}  // namespace lf
