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
  lens_radius_ = static_cast<float>(spec.aperture / 2);
  focus_distance_ = spec.focus_distance > 0 ? static_cast<float>(spec.focus_distance) : length(to_vec(spec.at) - eye_);
}

Ray Camera::ray(float image_x, float image_y) const {
  float sx = (2.0f * image_x / static_cast<float>(width_) - 1.0f) * half_width_;
  float sy = (1.0f - 2.0f * image_y / static_cast<float>(height_)) * half_height_;
  return Ray{eye_, normalize(forward_ + right_ * sx + up_ * sy)};
}

Vec3 Camera::to_view(Vec3 p) const {
  const Vec3 d = p - eye_;
  return {dot(d, right_), dot(d, up_), dot(d, forward_)};
}

Vec2 Camera::to_image(Vec3 view) const {
  const float sx = view.x / view.z / half_width_, sy = view.y / view.z / half_height_;
  return {(sx + 1.0f) * 0.5f * static_cast<float>(width_), (1.0f - sy) * 0.5f * static_cast<float>(height_)};
}

float Camera::blur_radius(float depth) const {
  if (lens_radius_ <= 0) return 0;
  // Through lens point l a point at depth z lands l (1 - focus / z) away from its pinhole image on the focus plane,
  // where a pixel is 2 half_height focus / height wide.
  const float pixel_on_focus_plane = 2.0f * half_height_ * focus_distance_ / static_cast<float>(height_);
  return lens_radius_ * std::abs(1.0f - focus_distance_ / depth) / pixel_on_focus_plane;
}

}  // namespace lf

namespace lf {

// Shirley and Chiu's concentric map of the unit square onto the unit disk: strata stay compact, so a pixel's
// stratified lens samples cover the lens evenly.
static void concentric_disk(float u, float v, float& x, float& y) {
  const float a = 2 * u - 1, b = 2 * v - 1;
  if (a == 0 && b == 0) {
    x = y = 0;
    return;
  }
  float r, phi;
  if (std::abs(a) > std::abs(b)) {
    r = a;
    phi = kPi / 4 * (b / a);
  } else {
    r = b;
    phi = kPi / 2 - kPi / 4 * (a / b);
  }
  x = r * std::cos(phi);
  y = r * std::sin(phi);
}

Ray Camera::ray(float image_x, float image_y, float lens_u, float lens_v) const {
  const Ray pinhole = ray(image_x, image_y);
  if (lens_radius_ <= 0) return pinhole;
  const Vec3 focus = eye_ + pinhole.direction * (focus_distance_ / dot(pinhole.direction, forward_));
  float lx, ly;
  concentric_disk(lens_u, lens_v, lx, ly);
  const Vec3 origin = eye_ + (right_ * lx + up_ * ly) * lens_radius_;
  return Ray{origin, normalize(focus - origin)};
}

}  // namespace lf
