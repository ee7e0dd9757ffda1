#pragma once
// What an op's settings become when the script leaves them unset: derived from the scene's scale, the camera's
// pixel footprint and the image's lit samples a pixel, instead of constants chosen on one scene. The image's
// `spp` (with `shade_spp`) is the one knob that trades time for quality: ops whose estimates are averaged by the
// pixel's samples (direct light, own values) need no more of their own as it rises, and caches, whose values every
// sample of a pixel shares, sample their hemispheres in proportion to it, so that a cached value is never the
// noisiest part of a pixel (docs/lua-api.md, "One knob for time against quality").
#include "render/lightops/lightop.hpp"

namespace lf {

// The strata of a cache record's hemisphere: theta x phi with phi = 3 theta.
struct HemisphereStrata {
  int theta = 8, phi = 24;
  int count() const { return theta * phi; }
};

// A record's hemisphere from the lit samples a pixel (image shade_spp, else spp): about 12 rays per lit sample, so
// that the record's noise, which every sample of the pixels it serves shares, stays at or below the pixel's own
// noise from its lit samples; 8 x 24 at 16 lit samples, at least 6 x 18 and at most 24 x 72.
// The cache's error bound a where the script leaves it unset (0): 0.2 at 16 lit samples a pixel, halved for every
// fourfold more (the interpolation error then stays under the pixel's noise as that noise falls), within 0.05-0.3.
float cache_accuracy(int lit_samples);
HemisphereStrata cache_hemisphere(int lit_samples);

// The least R a cache record at x (shading normal n) may have so that it reaches `reach_pixels` of the camera's
// pixels under error bound a (a record serves |x - x_i| / R < a): its pre-pass candidates lie that many pixels
// apart, and a record that reaches fewer leaves the points between them to compute their own values. A surface
// seen at a grazing angle spreads a pixel over more of it (the cosine is bounded at 1/4). 0 without a camera.
float record_radius_floor(const SceneContext& ctx, Vec3 x, Vec3 n, float reach_pixels, float a);

}  // namespace lf
