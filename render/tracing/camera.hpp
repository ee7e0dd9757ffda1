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
  float lens_radius() const { return lens_radius_; }
  Vec3 eye() const { return eye_; }
  // The angle one pixel spans (radians, near the centre): a pixel is about distance x this wide.
  float pixel_angle() const { return 2.0f * half_height_ / static_cast<float>(height_); }
  // Point p in the camera's frame: x to the right, y up, z along the view (depth in front of the eye).
  Vec3 to_view(Vec3 p) const;
  // Where a point of the camera's frame in front of the eye (z > 0) lands on the image, in pixel units as ray()
  // takes them: ray(x, y) passes through it (a pinhole's; through a lens, the point's image where it is in focus).
  Vec2 to_image(Vec3 view) const;
  // How far (in pixels) the lens spreads the image of a point at this depth around to_image's: 0 without a lens
  // and at the focus distance.
  float blur_radius(float depth) const;

 private:
  Vec3 eye_, forward_, right_, up_;
  float half_height_, half_width_;
  float lens_radius_ = 0, focus_distance_ = 0;
  int width_, height_;
};

}  // namespace lf
