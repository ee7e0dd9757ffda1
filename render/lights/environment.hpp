#pragma once
// Light from infinitely far away: an environment (an equirectangular map, or one radiance in every direction) and a
// sun (a disc of given angular size and irradiance). Together they are one light "at infinity": a direction's
// radiance is the map's there plus the sun's where the direction falls in its disc, and one density covers both
// ways of drawing a direction (from the map by its brightness, from the sun's cone), so that a light sample and a
// BSDF ray that leaves the scene weigh each other by multiple importance sampling.
//
// Directions are the scene's, y up. The map is laid out as Blender lays out a world's equirectangular image, seen
// through a glTF export (Blender's z up is the scene's y, its -y the scene's +z): the image's top row is straight
// up, its middle column looks along +x, and the azimuth grows from +x towards +z (Blender's u = 0.5 -
// atan2(y, x) / 2 pi). A map rendered with Cycles as a
// world and a glTF of the same scene then light the scene the same way. `rotation` turns the map about the up axis
// (counter-clockwise seen from above).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.hpp"
#include "render/math.hpp"

namespace lf {

struct Sun {
  Vec3 direction{0, 1, 0};  // towards the sun, unit length
  float angle = 0.00918f;   // angular diameter, radians (the real sun's 0.526 degrees)
  RGB irradiance{};         // on a surface facing the sun, W/m^2 per channel
};

class Environment {
 public:
  // One radiance from every direction (black: none, e.g. a sun alone).
  explicit Environment(RGB radiance = {});
  // An equirectangular map, `width` x `height` RGB values row by row from the top, times `intensity`, turned by
  // `rotation` radians about the up axis.
  Environment(int width, int height, std::vector<RGB> pixels, float intensity, float rotation);

  void set_sun(const Sun& sun);
  // A job frame's change of a map's intensity and rotation (radians), or of a constant environment's radiance.
  // The map's sampling distribution does not depend on either, so it is kept: the result equals an environment
  // made with these values, bit for bit.
  void set_map_look(float intensity, float rotation);
  void set_constant(RGB radiance);
  float intensity() const { return intensity_; }
  float rotation() const { return rotation_; }
  // Whether camera rays that leave the scene see it (else they see black; it still lights the scene).
  void set_camera_visible(bool visible) { camera_visible_ = visible; }
  bool camera_visible() const { return camera_visible_; }
  bool has_map() const { return width_ > 0; }
  const std::optional<Sun>& sun() const { return sun_; }
  // Whether it sends any light at all.
  bool emits() const { return map_power_ > 0 || sun_power_ > 0; }

  // The radiance arriving from direction `wi` (unit, pointing away from the scene).
  RGB radiance(Vec3 wi) const;

  struct Sample {
    Vec3 wi;      // towards the light
    RGB radiance;
    float pdf;    // per solid angle, of every way it could have been drawn
  };
  // A direction for a uniform point u, v in [0, 1)^2: in proportion to the map's brightness (times sin theta, so
  // per solid angle; piecewise constant over texels, radiance() being bilinear between them), or in the sun's
  // disc, chosen by their power.
  Sample sample(float u, float v) const;
  // The density with which sample() draws direction wi, per solid angle.
  float pdf(Vec3 wi) const;

  // The chance that the map's part of sample() picks texel (x, y) (0 without a map).
  double texel_probability(int x, int y) const;
  // The chance that sample() draws from the sun's disc rather than the map.
  float sun_share() const { return sun_share_; }
  // Integral of luminance over the sphere (the map's or constant's, the sun's), for reports and choices.
  double map_power() const { return map_power_; }
  double sun_power() const { return sun_power_; }

  // The unrotated map's direction at image coordinates u, v in [0, 1] (u across, v down from the top row), and the
  // coordinates of a direction.
  static Vec3 direction_of(float u, float v);
  static void image_coordinates(Vec3 wi, float& u, float& v);

  // A self-contained binary form (little-endian, native floats) for the shipped scene: the inputs, from which the
  // same distribution is built again bit for bit. `read` fails on a short or inconsistent form.
  void write(std::string& out) const;
  static Result<Environment> read(std::string_view bytes);

  std::string describe() const;  // for the scene report

 private:
  void build();      // the map's distribution, then map_power() and build_sun()
  void build_power();  // map_power_ from the distribution's total, the intensity or the constant; then build_sun()
  void build_sun();  // the sun's disc and its share of the samples (over the map's power)
  Vec3 to_map(Vec3 wi) const;    // scene direction -> the unrotated map's frame
  Vec3 from_map(Vec3 d) const;
  float map_pdf(Vec3 wi) const;
  // The same at a place in the image already known (a texel x, y and the map-frame direction's cosine to the
  // pole; image coordinates u, v): what sample() uses for the point it drew, without finding it again by
  // inverse trigonometry.
  float map_pdf_at(int x, int y, float pole_cosine) const;
  RGB map_radiance(Vec3 wi) const;
  RGB map_radiance_at(float u, float v) const;
  bool in_sun(Vec3 wi) const;
  // The sun's part of radiance() and of pdf() at wi (0 outside its disc).
  RGB sun_radiance(Vec3 wi) const;
  float sun_pdf(Vec3 wi) const;
  size_t texel(int x, int y) const { return static_cast<size_t>(y) * static_cast<size_t>(width_) + static_cast<size_t>(x); }

  RGB constant_{};
  int width_ = 0, height_ = 0;
  std::vector<RGB> pixels_;  // raw, before intensity
  float intensity_ = 1, rotation_ = 0;
  float cos_rot_ = 1, sin_rot_ = 0;
  std::optional<Sun> sun_;
  bool camera_visible_ = true;
  // The map's distribution: rows by their weight, then a column within the row.
  std::vector<float> row_cdf_, row_pdf_;    // height_
  std::vector<float> col_cdf_, col_pdf_;    // width_ * height_
  // Guide tables (kGuide + 1 per cdf): where the cdf first exceeds k / kGuide, so that a search looks at a few
  // entries instead of the whole row (a row's cdf is 4 KB; the searches were 8 % of a path tracer's time).
  static constexpr size_t kGuide = 64;
  std::vector<uint32_t> row_guide_, col_guide_;
  double map_power_ = 0, sun_power_ = 0;
  double map_weight_total_ = 0;  // the texels' weights summed (map_power_ before intensity and texel area)
  float sun_share_ = 0;
  // The sun's half angle a as 1 - cos a and sin^2 a (each computed where it is precise); Le = E * scale.
  float sun_one_minus_cos_ = 0, sun_sin2_ = 0, sun_radiance_scale_ = 0;
  Vec3 sun_u_, sun_v_;                          // a frame around the sun's direction
};

}  // namespace lf
