#pragma once
// Light arriving at a surface, split by elevation into kElevationBands bands of equal width in cos(theta): band j
// holds the directions with cos(theta) in (1 - (j + 1) / K, 1 - j / K]. Narrow near the horizon, where the
// lobes below change fastest with the elevation (a rough metal's multiply scattered light).
//
// Why: a BSDF lobe of the form A(wo) B(cos theta_i), the same in every azimuth, reflects
//   the integral of A B L cos = A times the sum over bands of B (cosine-weighted mean over band j) times band j's
//   irradiance,
// exact up to how L varies inside a band. A Lambert lobe has B = 1 and needs only the irradiance; the base of
// glTF's metal-roughness material under its coating, and a rough conductor's multiply scattered light, have B =
// 1 - E(cos theta_i) (render/shading/microfacet.hpp). With the bands a diffuse cache serves those too.
#include <algorithm>
#include <array>

#include "render/math.hpp"

namespace lf {

inline constexpr int kElevationBands = 8;
using ElevationBands = std::array<RGB, kElevationBands>;

// The band of a direction whose cosine to the normal is cos_theta (clamped into the hemisphere).
inline int elevation_band(float cos_theta) {
  const float below_zenith = 1.0f - std::clamp(cos_theta, 0.0f, 1.0f);
  return std::min(kElevationBands - 1, static_cast<int>(below_zenith * kElevationBands));
}

}  // namespace lf
