#pragma once
// What the quality benchmarks share: a farm rendered to an image, and its relative RMSE against a reference.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_util.hpp"
#include "render/images/image.hpp"

namespace bench {

// Relative RMSE per pixel, over the reference's mean, leaving out the light's pixels (the same emission in both).
// `ring`: also leave out the pixels next to the light.
inline double relative_rmse(const lf::Image& a, const lf::Image& ref, bool ring = false) {
  double se = 0, mean = 0;
  size_t n = 0;
  const int w = ref.width, h = ref.height;
  auto light = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < w && y < h && ref.pixels[static_cast<size_t>(y * w + x)].x > 1.0f;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (light(x, y)) continue;  // the light: the same emission in both
      bool near = false;
      for (int dy = -1; dy <= 1 && ring; ++dy)
        for (int dx = -1; dx <= 1; ++dx) near = near || light(x + dx, y + dy);
      if (near) continue;
      const size_t i = static_cast<size_t>(y * w + x);
      const double d = lf::average(a.pixels[i]) - lf::average(ref.pixels[i]);
      se += d * d;
      mean += lf::average(ref.pixels[i]);
      ++n;
    }
  return std::sqrt(se / static_cast<double>(n)) / (mean / static_cast<double>(n));
}

// Flicker: the relative RMSE of the change from frame a0 to a1 against the references' change from r0 to r1, over
// r0's mean (the light's pixels in either reference left out): a change the true image does not make.
inline double relative_temporal_rmse(const lf::Image& a0, const lf::Image& a1, const lf::Image& r0, const lf::Image& r1) {
  double se = 0, mean = 0;
  size_t n = 0;
  for (size_t i = 0; i < r0.pixels.size(); ++i) {
    if (r0.pixels[i].x > 1.0f || r1.pixels[i].x > 1.0f) continue;
    const double d = (lf::average(a1.pixels[i]) - lf::average(a0.pixels[i])) -
                     (lf::average(r1.pixels[i]) - lf::average(r0.pixels[i]));
    se += d * d;
    mean += lf::average(r0.pixels[i]);
    ++n;
  }
  return std::sqrt(se / static_cast<double>(n)) / (mean / static_cast<double>(n));
}

// Renders `script` with `sets` to `out` and reads it back; `seconds` gets the farm's wall time.
inline lf::Image render_image(const std::string& script, const std::vector<std::string>& sets, const std::string& out,
                              double& seconds) {
  seconds = run_farm(script, sets, out).wall_seconds;
  auto img = lf::read_image(out);
  if (!img) {
    std::fprintf(stderr, "%s\n", img.error().message.c_str());
    std::exit(1);
  }
  return *img;
}

}  // namespace bench
