#include "render/tracing/camera.hpp"

#include <cmath>

namespace lf {

static Vec3 to_vec(const std::array<double, 3>& a) {
  return {static_cast<float>(a[0]), static_cast<float>(a[1]), static_cast<float>(a[2])};
}

Camera::Camera(const CameraSpec& spec, int width, int height) : width_(width), height_(height) {
  eye_ = to_vec(spec.eye);
  forward_ = normalize(to_vec(spec.at) - eye_);
  right_ = normalize(cross(forward_, to_vec(spec.up)));
  up_ = cross(right_, forward_);
  half_height_ = std::tan(static_cast<float>(spec.fov) * kPi / 360.0f);
  half_width_ = half_height_ * static_cast<float>(width) / static_cast<float>(height);
}

Ray Camera::ray(float image_x, float image_y) const {
  float sx = (2.0f * image_x / static_cast<float>(width_) - 1.0f) * half_width_;
  float sy = (1.0f - 2.0f * image_y / static_cast<float>(height_)) * half_height_;
  return Ray{eye_, normalize(forward_ + right_ * sx + up_ * sy)};
}

}  // namespace lf
