#pragma once
#include "core/specs.hpp"
#include "render/tracer.hpp"

namespace lf {

// Pinhole camera; fov is vertical. Right-handed: looking from eye to at with `up` up, +x of the image is
// forward x up.
class Camera {
 public:
  Camera(const CameraSpec& spec, int width, int height);
  // (px + jx, py + jy) in pixel units, (0,0) at the top-left corner of the image.
  Ray ray(float image_x, float image_y) const;

 private:
  Vec3 eye_, forward_, right_, up_;
  float half_height_, half_width_;
  int width_, height_;
};

}  // namespace lf
