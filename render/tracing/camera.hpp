#pragma once
#include "core/specs.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

// A pinhole or thin-lens camera; fov is vertical. Right-handed: looking from eye to at with `up` up, +x of the
// image is forward x up. With a lens, every ray through a pixel's point meets the pinhole's ray at the focal plane
// (perpendicular to the view, focus_distance ahead of the eye) and leaves from a point on the lens: a disk of
// diameter `aperture` around the eye, facing the view.
class Camera {
 public:
  Camera(const CameraSpec& spec, int width, int height);
  // (px + jx, py + jy) in pixel units, (0,0) at the top-left corner of the image: the pinhole's ray.
  Ray ray(float image_x, float image_y) const;
  // The same through the lens point that `lens` (uniform in [0,1)^2) picks; the pinhole's ray without a lens.
  Ray ray(float image_x, float image_y, float lens_u, float lens_v) const;
  bool has_lens() const { return lens_radius_ > 0; }
  Vec3 eye() const { return eye_; }
  // The angle one pixel spans (radians, near the centre): a pixel is about distance x this wide.
  float pixel_angle() const { return 2.0f * half_height_ / static_cast<float>(height_); }

 private:
  Vec3 eye_, forward_, right_, up_;
  float half_height_, half_width_;
  float lens_radius_ = 0, focus_distance_ = 0;
  int width_, height_;
};

}  // namespace lf
