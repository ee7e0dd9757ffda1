#pragma once
// Small vector math for the renderer. Float, because Embree and the wire both use float32.
#include <cmath>

namespace lf {

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(Vec3 b) const { return {x + b.x, y + b.y, z + b.z}; }
  constexpr Vec3 operator-(Vec3 b) const { return {x - b.x, y - b.y, z - b.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3 operator*(Vec3 b) const { return {x * b.x, y * b.y, z * b.z}; }  // per channel (colours)
  Vec3& operator+=(Vec3 b) { x += b.x; y += b.y; z += b.z; return *this; }
  Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vec3&) const = default;
};

using RGB = Vec3;

// Texture coordinates (OBJ `vt`): u to the right, v up.
struct Vec2 {
  float u = 0, v = 0;
  constexpr bool operator==(const Vec2&) const = default;
};

constexpr Vec3 operator*(float s, Vec3 v) { return v * s; }
constexpr float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) { return a / length(a); }
constexpr float average(RGB c) { return (c.x + c.y + c.z) / 3.0f; }
constexpr bool is_black(RGB c) { return c.x <= 0 && c.y <= 0 && c.z <= 0; }
inline float largest_coordinate(Vec3 a) {
  const float x = std::fabs(a.x), y = std::fabs(a.y), z = std::fabs(a.z);
  const float xy = x > y ? x : y;  // not fmax: no NaN here, and this stays a max instruction
  return xy > z ? xy : z;
}

inline constexpr float kPi = 3.14159265358979323846f;

// The sRGB transfer function (IEC 61966-2-1), on values in [0, 1]: what 8-bit colour files store, and back.
inline float srgb_encode(float linear) {
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}
inline float srgb_decode(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

}  // namespace lf
