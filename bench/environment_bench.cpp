// Environment importance sampling against uniform sphere sampling and cosine sampling, at equal samples. The
// quantity: the irradiance an unoccluded surface gets from an HDR environment (E = integral of L cos over its
// hemisphere), estimated from --samples directions; the figure: the estimator's variance over --trials independent
// estimates, uniform's over the environment's (and cosine's over the environment's), for each of Debian Blender's
// four CC0 HDRIs (../shared/scenes/gltf/hdri) and five surface orientations (up, and four tilted 60 degrees towards
// the compass points). A fourth estimator, "mis", takes half its samples from the environment and half by cosine,
// weighed by the power heuristic, as the renderer combines light and BSDF samples. Sunset and forest have a small sun region thousands of times brighter than their sky; the
// goal is a variance >= 10 x lower than uniform sampling's on such a map. The means of the three estimators are
// printed too (they must agree: all three are unbiased). No timing: equal samples, not equal time.
//
//   build/bench/environment_bench [--samples 16] [--trials 40000] [--json FILE]
#include <cmath>
#include <cstdio>
#include <fstream>

#include "bench/bench_util.hpp"
#include "render/images/image.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/lights/environment.hpp"
#include "render/shading/bsdf.hpp"
#include "render/shading/sampler.hpp"

namespace {

struct Moments {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return sum / n; }
  double variance() const { return std::max(0.0, sum2 / n - mean() * mean()); }
};

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/environment_bench [--samples 16] [--trials 40000] [--json FILE]",
                            {"--samples", "--trials", "--json"});
  int samples = 16, trials = 40000;
  std::string json = "bench-environment.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--samples") samples = std::max(1, std::atoi(argv[i + 1]));
    if (a == "--trials") trials = std::max(2, std::atoi(argv[i + 1]));
    if (a == "--json") json = argv[i + 1];
  }
  const std::string dir = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/gltf/hdri/";
  const float tilt = 60 * lf::kPi / 180;
  const std::vector<std::pair<std::string, lf::Vec3>> normals{
      {"up", {0, 1, 0}},
      {"north", {0, std::cos(tilt), -std::sin(tilt)}},
      {"south", {0, std::cos(tilt), std::sin(tilt)}},
      {"east", {std::sin(tilt), std::cos(tilt), 0}},
      {"west", {-std::sin(tilt), std::cos(tilt), 0}}};
  lf::Value::Array rows;
  std::printf("irradiance from %d samples, variance over %d estimates (%d-sample estimates)\n", samples, trials, samples);
  std::printf("%-10s %-6s %9s %9s %9s %9s %12s %11s %11s\n", "map", "normal", "E env", "E uniform", "E cosine",
              "E mis", "uniform/env", "cosine/env", "uniform/mis");
  for (const char* name : {"courtyard", "interior", "sunset", "forest"}) {
    auto image = lf::read_image(dir + name + ".exr");
    if (!image) {
      std::fprintf(stderr, "%s\n", image.error().message.c_str());
      return 1;
    }
    const lf::Environment env(image->width, image->height, std::move(image->pixels), 1, 0);
    std::vector<double> uniform_ratios, cosine_ratios, mis_ratios;
    for (const auto& [label, n] : normals) {
      Moments by_env, by_uniform, by_cosine, by_mis;
      for (int t = 0; t < trials; ++t) {
        lf::Rng rng(static_cast<uint64_t>(t) * 7919 + 17, 0xe4b);
        double e_env = 0, e_uni = 0, e_cos = 0, e_mis = 0;
        for (int s = 0; s < samples; ++s) {
          const auto d = env.sample(rng.uniform(), rng.uniform());
          // A direction that rounds into a black texel has density 0 and radiance 0 there: it adds nothing.
          if (d.pdf > 0) e_env += lf::average(d.radiance) * std::max(0.0f, lf::dot(d.wi, n)) / d.pdf;
          const float z = 1 - 2 * rng.uniform(), r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * lf::kPi * rng.uniform();
          const lf::Vec3 w{r * std::cos(phi), z, r * std::sin(phi)};
          e_uni += lf::average(env.radiance(w)) * std::max(0.0f, lf::dot(w, n)) * 4 * lf::kPi;
          const lf::Vec3 c = lf::cosine_hemisphere(n, rng.uniform(), rng.uniform());
          e_cos += lf::average(env.radiance(c)) * lf::kPi;  // L cos / (cos / pi)
          // Half the samples from each, weighed by the power heuristic (what the renderer does with a light
          // sample and a BSDF sample): the environment's draw d, and the cosine draw c.
          if (s % 2 == 0) {
            const float cos_d = std::max(0.0f, lf::dot(d.wi, n));
            if (d.pdf > 0 && cos_d > 0)
              e_mis += 2 * lf::average(d.radiance) * cos_d / d.pdf * lf::power_heuristic(d.pdf, cos_d / lf::kPi);
            const float cos_c = std::max(0.0f, lf::dot(c, n));
            if (cos_c > 0)
              e_mis += 2 * lf::average(env.radiance(c)) * cos_c / (cos_c / lf::kPi) *
                       lf::power_heuristic(cos_c / lf::kPi, env.pdf(c));
          }
        }
        by_env.add(e_env / samples);
        by_uniform.add(e_uni / samples);
        by_cosine.add(e_cos / samples);
        by_mis.add(e_mis / samples);
      }
      const double ru = by_uniform.variance() / by_env.variance(), rc = by_cosine.variance() / by_env.variance();
      const double rm = by_uniform.variance() / by_mis.variance();
      uniform_ratios.push_back(ru);
      cosine_ratios.push_back(rc);
      mis_ratios.push_back(rm);
      std::printf("%-10s %-6s %9.4f %9.4f %9.4f %9.4f %12.1f %11.1f %11.1f\n", name, label.c_str(), by_env.mean(),
                  by_uniform.mean(), by_cosine.mean(), by_mis.mean(), ru, rc, rm);
      rows.push_back(lf::Value::Map{{"map", std::string(name)}, {"normal", label}, {"mean_env", by_env.mean()},
                                    {"mean_uniform", by_uniform.mean()}, {"mean_cosine", by_cosine.mean()},
                                    {"mean_mis", by_mis.mean()}, {"variance_ratio_uniform", ru},
                                    {"variance_ratio_cosine", rc}, {"variance_ratio_uniform_over_mis", rm}});
    }
    auto range = [](const std::vector<double>& v) {
      char b[64];
      std::snprintf(b, sizeof b, "%.1f (%.1f-%.1f)", bench::median(v), *std::min_element(v.begin(), v.end()),
                    *std::max_element(v.begin(), v.end()));
      return std::string(b);
    };
    std::printf("%-10s median variance ratio: uniform/env %s, cosine/env %s, uniform/mis %s\n", name,
                range(uniform_ratios).c_str(), range(cosine_ratios).c_str(), range(mis_ratios).c_str());
  }
  const lf::Value doc = lf::Value::Map{{"samples", samples}, {"trials", trials}, {"rows", rows}};
  std::ofstream(json) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json.c_str());
  return 0;
}
