// The environment and the sun: their densities against their sampling, and the light they give against closed forms,
// through the ops that sample lights (pathtrace, direct), follow mirrors (specular) and see the sky (the camera).
#include "render/lights/environment.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "render/lightops/lightop_registry.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/scene/scene_file.hpp"
#include "render/shading/sampler.hpp"
#include "render/shading/tile_kernel.hpp"
#include "render/test_support.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {
namespace {

// A 32 x 16 sky: a gradient, darker below the horizon, and one texel 2000 times brighter than the rest (a sun
// painted into the map, as HDR skies have).
Environment painted_sky(float rotation = 0, float intensity = 1.5f) {
  const int w = 32, h = 16;
  std::vector<RGB> px(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float up = y < h / 2 ? 1.0f : 0.2f;
      px[static_cast<size_t>(y) * w + x] = RGB{0.3f, 0.5f, 0.9f} * (up * (1.0f + 0.5f * std::sin(0.4f * static_cast<float>(x))));
    }
  px[static_cast<size_t>(3) * w + 20] = {2000, 1800, 1500};
  return Environment(w, h, std::move(px), intensity, rotation);
}

// The integral of f over the sphere on an n x 2n grid in (theta, phi) (midpoints).
template <class F>
double integrate_sphere(F f, int n) {
  double sum = 0;
  const double dt = M_PI / n, dp = M_PI / n;
  for (int i = 0; i < n; ++i) {
    const double theta = (i + 0.5) * dt;
    for (int j = 0; j < 2 * n; ++j) {
      const double phi = (j + 0.5) * dp;
      const Vec3 d{static_cast<float>(std::sin(theta) * std::cos(phi)), static_cast<float>(std::cos(theta)),
                   static_cast<float>(std::sin(theta) * std::sin(phi))};
      sum += f(d) * std::sin(theta) * dt * dp;
    }
  }
  return sum;
}

TEST(Environment, ImageCoordinatesAndDirectionsAreInverses) {
  for (float u : {0.05f, 0.3f, 0.5f, 0.77f, 0.98f})
    for (float v : {0.02f, 0.25f, 0.5f, 0.9f}) {
      float u2, v2;
      Environment::image_coordinates(Environment::direction_of(u, v), u2, v2);
      EXPECT_NEAR(u2, u, 1e-5f);
      EXPECT_NEAR(v2, v, 1e-5f);
    }
  // Blender's layout seen through glTF's axes: the top row is up, the middle column looks along +x, and a quarter
  // further along the image along +z (Blender's -y: u = 0.5 - atan2(y, x) / 2 pi there).
  const Vec3 up = Environment::direction_of(0.5f, 0.0f), middle = Environment::direction_of(0.5f, 0.5f);
  EXPECT_NEAR(up.y, 1.0f, 1e-6f);
  EXPECT_NEAR(middle.x, 1.0f, 1e-6f);
  EXPECT_NEAR(Environment::direction_of(0.75f, 0.5f).z, 1.0f, 1e-6f);
}

TEST(Environment, DensityIntegratesToOneAndMatchesWhatSamplingDraws) {
  Environment sky = painted_sky(0.7f);
  sky.set_sun({normalize(Vec3{0.3f, 0.8f, -0.2f}), 2.0f * kPi / 180, {900, 850, 800}});
  // The density integrates to 1: the map's part on a grid (the sun's disc is too small for one, and its cone's
  // density integrates to 1 by construction; the sampling below checks it).
  EXPECT_NEAR(integrate_sphere([](Vec3 d) { static const Environment plain = painted_sky(0.7f); return plain.pdf(d); }, 512),
              1.0, 0.005);
  // Every sample's density is pdf() of its direction, its radiance radiance() there; and the estimator
  // L / pdf averages to the integral of L (the map's on a fine grid, the sun's E / (pi sin^2 a) times its cone).
  Rng rng(7, 1);
  double mean = 0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    const auto s = sky.sample(rng.uniform(), rng.uniform());
    ASSERT_GT(s.pdf, 0);
    EXPECT_FLOAT_EQ(s.pdf, sky.pdf(s.wi));
    mean += average(s.radiance) / s.pdf;
  }
  mean /= n;
  Environment no_sun = painted_sky(0.7f);
  const double sun_half = kPi / 180;
  const double sun_integral = average(RGB{900, 850, 800}) / (M_PI * std::sin(sun_half) * std::sin(sun_half)) * 2 * M_PI *
                              (1 - std::cos(sun_half));
  const double expected = integrate_sphere([&](Vec3 d) { return average(no_sun.radiance(d)); }, 1024) + sun_integral;
  EXPECT_NEAR(mean / expected, 1.0, 0.01);
  EXPECT_NEAR((no_sun.map_power() + sun_integral) / expected, 1.0, 0.01);
}

// Pearson's chi-square statistic of samples binned by texel against the texels' probabilities, with its p-value
// from the Wilson-Hilferty approximation: the map's sampling draws texels as its distribution says.
TEST(Environment, SamplesFallInTexelsAsTheDensitySays) {
  const int w = 8, h = 4;
  std::vector<RGB> px(static_cast<size_t>(w) * h);
  for (int i = 0; i < w * h; ++i) px[static_cast<size_t>(i)] = RGB{1, 1, 1} * (0.2f + static_cast<float>((i * 7) % 11));
  const Environment env(w, h, px, 1, 0);
  std::vector<double> seen(px.size());
  Rng rng(3, 9);
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    float u, v;
    Environment::image_coordinates(env.sample(rng.uniform(), rng.uniform()).wi, u, v);
    const int x = std::min(static_cast<int>(u * w), w - 1), y = std::min(static_cast<int>(v * h), h - 1);
    seen[static_cast<size_t>(y) * w + x] += 1;
  }
  // Against the distribution the sampler tabulates (what it tabulates is checked against the radiance by the
  // unbiasedness test above).
  double chi2 = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double e = n * env.texel_probability(x, y);
      const double o = seen[static_cast<size_t>(y) * w + x];
      chi2 += (o - e) * (o - e) / e;
    }
  const double k = static_cast<double>(px.size() - 1);
  const double z = (std::cbrt(chi2 / k) - (1 - 2 / (9 * k))) / std::sqrt(2 / (9 * k));
  const double p_value = 0.5 * std::erfc(z / std::sqrt(2.0));
  EXPECT_GE(p_value, 0.01) << "chi2 " << chi2 << " over " << k << " degrees of freedom";
}

TEST(Environment, TheSunGivesItsIrradianceToASurfaceFacingIt) {
  Environment env;  // black: the sun alone
  const Vec3 towards = normalize(Vec3{0.2f, 1, 0.1f});
  env.set_sun({towards, 0.526f * kPi / 180, {1000, 1000, 1000}});
  EXPECT_FLOAT_EQ(env.sun_share(), 1.0f);
  Rng rng(11, 2);
  double e = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const auto s = env.sample(rng.uniform(), rng.uniform());
    e += s.radiance.x * dot(s.wi, towards) / s.pdf;
  }
  EXPECT_NEAR(e / n, 1000.0, 0.5);
  EXPECT_GT(env.radiance(towards).x, 1e7f);  // a tiny bright disc
  EXPECT_EQ(env.radiance(normalize(Vec3{0.2f, 1, 0.2f})).x, 0.0f);
}

TEST(Environment, RotationTurnsTheMapAboutTheUpAxis) {
  const Environment still = painted_sky(0), turned = painted_sky(kPi / 2);
  for (float u : {0.1f, 0.4f, 0.63f})
    for (float v : {0.2f, 0.45f}) {
      const Vec3 d = Environment::direction_of(u, v);
      // Turned a quarter counter-clockwise seen from above: what was towards +x is now towards -z.
      const Vec3 d_turned{d.z, d.y, -d.x};
      const RGB a = still.radiance(d), b = turned.radiance(d_turned);
      EXPECT_NEAR(a.x, b.x, 1e-4f * a.x) << u << " " << v;
      EXPECT_NEAR(a.z, b.z, 1e-4f * a.z) << u << " " << v;
    }
}

// A job frame turns the map or changes its intensity (frames { environment }) without building its distribution
// again: the environment is then the one a script declaring those values makes, bit for bit, sun included.
TEST(Environment, AFramesIntensityAndRotationEqualAnEnvironmentMadeWithThem) {
  const Sun sun{normalize(Vec3{1, 2, 3}), 0.01f, {5, 6, 7}};
  Environment changed = painted_sky(0.3f);
  changed.set_sun(sun);
  const float intensity = 2.75f, rotation = 1.9f;
  changed.set_map_look(intensity, rotation);
  Environment fresh = painted_sky(rotation, intensity);
  fresh.set_sun(sun);
  EXPECT_EQ(changed.map_power(), fresh.map_power());
  EXPECT_EQ(changed.sun_share(), fresh.sun_share());
  for (float u = 0.013f; u < 1; u += 0.071f)
    for (float v = 0.007f; v < 1; v += 0.093f) {
      const Environment::Sample a = changed.sample(u, v), b = fresh.sample(u, v);
      ASSERT_EQ(a.wi.x, b.wi.x);
      ASSERT_EQ(a.wi.z, b.wi.z);
      ASSERT_EQ(a.pdf, b.pdf);
      ASSERT_EQ(a.radiance.y, b.radiance.y);
      const Vec3 d = Environment::direction_of(u, v);
      ASSERT_EQ(changed.pdf(d), fresh.pdf(d));
      ASSERT_EQ(changed.radiance(d).x, fresh.radiance(d).x);
    }
  // The change did something: the radiance towards a direction follows the intensity.
  const Vec3 d = Environment::direction_of(0.4f, 0.3f);
  const Environment before = painted_sky(rotation);
  EXPECT_NEAR(changed.radiance(d).y, before.radiance(d).y * intensity / 1.5f, 1e-5f * changed.radiance(d).y);

  // One radiance in every direction: a frame gives it anew.
  Environment overcast(RGB{1, 1, 1});
  overcast.set_sun(sun);
  overcast.set_constant({0.2f, 0.4f, 0.8f});
  Environment grey(RGB{0.2f, 0.4f, 0.8f});
  grey.set_sun(sun);
  EXPECT_EQ(overcast.map_power(), grey.map_power());
  EXPECT_EQ(overcast.sun_share(), grey.sun_share());
  EXPECT_EQ(overcast.radiance(d).z, grey.radiance(d).z);
  EXPECT_EQ(overcast.pdf(d), grey.pdf(d));
}

TEST(Environment, BinaryFormRebuildsTheSameLightAndRefusesDamage) {
  Environment sky = painted_sky(0.3f);
  sky.set_sun({normalize(Vec3{1, 2, 3}), 0.01f, {5, 6, 7}});
  sky.set_camera_visible(false);
  std::string bytes;
  sky.write(bytes);
  auto back = Environment::read(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_FALSE(back->camera_visible());
  Rng rng(5, 5);
  for (int i = 0; i < 1000; ++i) {
    const float a = rng.uniform(), b = rng.uniform();
    const auto s1 = sky.sample(a, b), s2 = back->sample(a, b);
    EXPECT_EQ(s1.wi, s2.wi);
    EXPECT_EQ(s1.pdf, s2.pdf);
    EXPECT_EQ(s1.radiance, s2.radiance);
  }
  for (size_t cut : {size_t{3}, size_t{9}, bytes.size() / 2, bytes.size() - 1})
    EXPECT_FALSE(Environment::read(bytes.substr(0, cut)).ok()) << cut;
  EXPECT_FALSE(Environment::read(bytes + "x").ok());
  std::string huge = bytes;
  huge[7] = '\xff', huge[8] = '\xff', huge[9] = '\xff';  // a width no data backs
  EXPECT_FALSE(Environment::read(huge).ok());
}

// A faceted ball (convex: each facet sees the whole sky above its plane) of albedo rho under a uniform sky L: every
// point reflects rho L. Light sampling and BSDF rays leaving the scene, weighed by MIS, must add up to exactly that.
struct Ball {
  Scene scene;
  uint32_t material = 0;
  ShadingPoints points;
  explicit Ball(Environment env, Material m = {"ball", {0.5f, 0.5f, 0.5f}, {}}, bool panel_facing_away = false) {
    material = scene.add_material(m);
    scene.add_sphere({0, 0, 0}, 1, 2, material);
    // A small bright panel high above, emitting upwards: it lights nothing here (and hides 0.05 % of the sky),
    // but it is a light of the tree.
    if (panel_facing_away)
      scene.add_quad({-0.1f, 5, -0.1f}, {-0.1f, 5, 0.1f}, {0.1f, 5, 0.1f}, {0.1f, 5, -0.1f},
                     scene.add_material({"panel", {}, {5000, 5000, 5000}}));
    scene.set_environment(std::move(env));
    EXPECT_TRUE(scene.finalize("ball").ok());
    for (uint32_t t = 0; t < scene.triangle_count(); t += 17) {
      const Vec3 c = (scene.vertex(t, 0) + scene.vertex(t, 1) + scene.vertex(t, 2)) / 3.0f;
      points.push_back(c, scene.normal(t), normalize(scene.normal(t) + Vec3{0.1f, 0.2f, 0}), material, sample_key(t, 0), t);
    }
  }
  std::vector<RGB> shade(const char* kind, Value::Map params, LightOp* input = nullptr) {
    RayTracer tracer(scene);
    auto op = create_lightop(*find_lightop_kind(kind), ParamTable(std::move(params), kind));
    LocalInputs none;
    LocalInputs inputs = input ? LocalInputs({{input, &none}}) : LocalInputs();
    if (input) run_to_completion(input->setup(SceneContext{&scene, &tracer}, none));
    run_to_completion(op->setup(SceneContext{&scene, &tracer}, inputs));
    std::vector<RGB> out(points.size());
    run_to_completion(op->shade(points, out, inputs));
    return out;
  }
};

double mean_of(const std::vector<RGB>& v) {
  double s = 0;
  for (const RGB& c : v) s += c.y;
  return s / static_cast<double>(v.size());
}

TEST(Environment, AWhiteFurnaceBallReflectsItsAlbedoOfTheSky) {
  Ball ball(Environment(RGB{2, 2, 2}));
  EXPECT_FLOAT_EQ(ball.scene.environment_share(), 1.0f);
  for (const char* kind : {"pathtrace", "direct"}) {
    const auto out = ball.shade(kind, {{std::string(kind) == "direct" ? "light_samples" : "samples", 256}});
    for (const RGB& c : out) EXPECT_NEAR(c.y, 1.0, 0.06) << kind;
    EXPECT_NEAR(mean_of(out), 1.0, 0.01) << kind;
  }
}

// With a light elsewhere, half the light samples go to the environment; where that light cannot reach (a panel
// facing away), all of them: the furnace stays exact either way, and no sample is spent on the panel.
TEST(Environment, WhereNoOtherLightReachesEverySampleGoesToTheEnvironment) {
  Ball ball(Environment(RGB{2, 2, 2}), {"ball", {0.5f, 0.5f, 0.5f}, {}}, true);
  EXPECT_FLOAT_EQ(ball.scene.environment_share(), 0.5f);
  for (size_t i = 0; i < ball.points.size(); ++i)
    EXPECT_FLOAT_EQ(environment_share_at(ball.scene, ball.points.position[i], ball.points.normal[i], nullptr), 1.0f);
  // Below the panel, facing up at its back: still nothing of it; beside it, above its plane, it counts.
  EXPECT_FLOAT_EQ(environment_share_at(ball.scene, {0, 6, 0}, {0, -1, 0}, nullptr), 0.5f);
  for (const char* kind : {"pathtrace", "direct"}) {
    const auto out = ball.shade(kind, {{std::string(kind) == "direct" ? "light_samples" : "samples", 256}});
    EXPECT_NEAR(mean_of(out), 1.0, 0.01) << kind;
  }
}

// A painted sky with a sun over a ball: direct light at each facet is rho / pi times the sky's cosine-weighted
// integral over the facet's side (the sun's part in closed form: E cos). Direct (light samples and BSDF rays by
// MIS) and the path tracer (for which a convex ball adds no bounce) both find it.
TEST(Environment, DirectLightFromAPaintedSkyAndASunMatchesItsIntegral) {
  Environment sky = painted_sky(0.4f);
  const Vec3 sun_dir = normalize(Vec3{0.4f, 0.9f, -0.3f});
  Environment with_sun = sky;
  with_sun.set_sun({sun_dir, 0.526f * kPi / 180, {40, 38, 35}});
  Ball ball(with_sun);
  std::vector<double> expected;
  for (size_t i = 0; i < ball.points.size(); ++i) {
    const Vec3 n = ball.points.normal[i];
    const double sky_part = integrate_sphere([&](Vec3 d) { return std::max(0.0f, dot(d, n)) * sky.radiance(d).y; }, 512);
    expected.push_back(0.5 / M_PI * (sky_part + 38.0 * std::max(0.0f, dot(sun_dir, n))));
  }
  for (const char* kind : {"direct", "pathtrace"}) {
    const auto out = ball.shade(kind, {{std::string(kind) == "direct" ? "light_samples" : "samples", 1024}});
    double sum = 0, want = 0;
    for (size_t i = 0; i < out.size(); ++i) {
      sum += out[i].y;
      want += expected[i];
      // Facets turned from the sun and the painted spot get few of the light samples (direct samples lights only
      // on diffuse surfaces by default): a looser bound where the light is dim.
      EXPECT_NEAR(out[i].y, expected[i], 0.06 * expected[i] + 0.02) << kind << " point " << i;
    }
    EXPECT_NEAR(sum / want, 1.0, 0.015) << kind;
  }
}

// A mirror ball shows the sky: the specular op's chains leave the scene and bring the environment back.
TEST(Environment, MirrorChainsThatLeaveTheSceneSeeTheSky) {
  Material mirror{"mirror", {}, {}};
  mirror.type = Material::Type::mirror;
  mirror.ks = {0.8f, 0.8f, 0.8f};
  Ball ball(Environment(RGB{1, 2, 3}), mirror);
  auto emission = create_lightop(*find_lightop_kind("emission"), ParamTable(Value::Map{}, "emission"));
  const auto out = ball.shade("specular", {}, emission.get());
  for (const RGB& c : out) {
    EXPECT_NEAR(c.x, 0.8, 1e-4);
    EXPECT_NEAR(c.z, 2.4, 1e-4);
  }
}

// Camera rays that miss see the environment unless it is hidden; the scene's own emitters are unaffected.
TEST(Environment, TheCameraSeesTheSkyUnlessItIsHidden) {
  for (bool visible : {true, false}) {
    Environment env(RGB{0.25f, 0.5f, 1});
    env.set_camera_visible(visible);
    Ball ball(env);
    RayTracer tracer(ball.scene);
    CameraSpec view;
    view.eye = {0, 0, 6};
    view.at = {0, 0, 0};
    view.fov = 30;
    const Camera camera(view, 16, 16);
    ImageSpec image;
    image.width = image.height = 16;
    image.spp = 1;
    TileWork work;
    trace_tile(ball.scene, tracer, camera, image, {0, 0, 16, 16}, work);
    EXPECT_GT(work.points.size(), 0u);
    size_t sky = 0;
    for (const RGB& e : work.emitted) sky += e.z == 1.0f;
    // Every camera ray that misses the ball sees the sky, or none does.
    EXPECT_GT(256u - work.points.size(), 0u);
    EXPECT_EQ(sky, visible ? 256u - work.points.size() : 0u);
  }
}

// The shipped scene carries its environment: the same light after the round trip.
TEST(Environment, TheShippedSceneCarriesIt) {
  Environment sky = painted_sky(0.2f);
  sky.set_sun({normalize(Vec3{0, 1, 1}), 0.02f, {3, 3, 3}});
  Ball ball(sky);
  auto back = scene_from_bytes(scene_to_bytes(ball.scene), "shipped");
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_NE(back->environment(), nullptr);
  EXPECT_EQ(back->environment_share(), 1.0f);
  const Vec3 d = normalize(Vec3{0.3f, 0.2f, 0.1f});
  EXPECT_EQ(back->environment()->radiance(d), ball.scene.environment()->radiance(d));
  EXPECT_EQ(back->environment()->pdf(d), ball.scene.environment()->pdf(d));
}

}  // namespace
}  // namespace lf
