#include "render/lightops/derived_settings.hpp"

#include <algorithm>
#include <cmath>

#include "render/tracing/camera.hpp"

namespace lf {

HemisphereStrata cache_hemisphere(int lit_samples) {
  constexpr double kRaysPerLitSample = 12;
  const double rays = kRaysPerLitSample * std::max(1, lit_samples);
  const int theta = std::clamp(static_cast<int>(std::lround(std::sqrt(rays / 3))), 6, 24);
  return {theta, 3 * theta};
}

float cache_accuracy(int lit_samples) {
  return static_cast<float>(std::clamp(0.2 * std::sqrt(16.0 / std::max(1, lit_samples)), 0.05, 0.3));
}

float record_radius_floor(const SceneContext& ctx, Vec3 x, Vec3 n, float reach_pixels, float a) {
  if (!ctx.camera || reach_pixels <= 0) return 0;
  const Vec3 to_eye = ctx.camera->eye() - x;
  const float distance = length(to_eye);
  if (distance <= 0) return 0;
  const float facing = std::max(0.25f, std::abs(dot(n, to_eye)) / distance);
  return reach_pixels * ctx.pixel_footprint(x) / (facing * a);
}

}  // namespace lf
