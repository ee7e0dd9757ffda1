#pragma once
#include "core/specs.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {

// Pinhole camera; fov is vertical. Right-handed: looking from eye to at with `up` up, +x of the image is
// forward x up.
class Camera {
 public:
  Camera(const CameraSpec& spec, int width, int height);
  // (px + jx, py + jy) in pixel units, (0,0) at the top-left corner of the image.
  Ray ray(float image_x, float image_y) const;
  Vec3 eye() const { return eye_; }
  // The angle one pixel spans (radians, near the centre): a pixel is about distance x this wide.
  float pixel_angle() const { return 2.0f * half_height_ / static_cast<float>(height_); }

 private:
  Vec3 eye_, forward_, right_, up_;
  float half_height_, half_width_;
  int width_, height_;
};

}  // namespace lf
