#include "render/lights/spherical_triangle.hpp"

#include <algorithm>
#include <cmath>

namespace lf {
namespace {

struct D3 {
  double x, y, z;
};
D3 d3(Vec3 a) { return {a.x, a.y, a.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double length(D3 a) { return std::sqrt(dot(a, a)); }

// The corners seen from x as unit vectors, and the triangle's angles there; false when it is degenerate from x.
struct Seen {
  D3 a, b, c;
  double alpha, cos_alpha, area;  // alpha: the angle at a
};

bool see(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2, Seen& s) {
  const D3 o = d3(x);
  D3 corners[3] = {d3(p0) - o, d3(p1) - o, d3(p2) - o};
  for (D3& c : corners) {
    const double l = length(c);
    if (!(l > 0)) return false;
    c = c * (1 / l);
  }
  s.a = corners[0];
  s.b = corners[1];
  s.c = corners[2];
  D3 n_ab = cross(s.a, s.b), n_bc = cross(s.b, s.c), n_ca = cross(s.c, s.a);
  const double l_ab = length(n_ab), l_bc = length(n_bc), l_ca = length(n_ca);
  if (!(l_ab > 1e-12 && l_bc > 1e-12 && l_ca > 1e-12)) return false;
  n_ab = n_ab * (1 / l_ab);
  n_bc = n_bc * (1 / l_bc);
  n_ca = n_ca * (1 / l_ca);
  auto cos_angle = [](D3 u, D3 v) { return std::clamp(dot(u, v), -1.0, 1.0); };
  s.cos_alpha = cos_angle(n_ab, n_ca * -1);
  s.alpha = std::acos(s.cos_alpha);
  const double beta = std::acos(cos_angle(n_bc, n_ab * -1)), gamma = std::acos(cos_angle(n_ca, n_bc * -1));
  s.area = std::max(0.0, s.alpha + beta + gamma - M_PI);
  return true;
}

// The part of v orthogonal to unit vector w, normalised (v and w not parallel).
D3 orthogonal_unit(D3 v, D3 w) {
  const D3 r = v - w * dot(v, w);
  const double l = length(r);
  return l > 0 ? r * (1 / l) : r;
}

}  // namespace

double spherical_triangle_solid_angle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2) {
  Seen s;
  return see(x, p0, p1, p2, s) ? s.area : 0.0;
}

std::optional<Vec3> sample_spherical_triangle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2, float u, float v, double& omega) {
  Seen s;
  omega = see(x, p0, p1, p2, s) ? s.area : 0.0;
  if (omega < kMinSampledSolidAngle) return std::nullopt;
  // Arvo's construction: cut off the sub-triangle (A, B, C') of area u * omega by choosing C' on arc AC, then a
  // point on arc BC' whose cosine to B is uniform in [cos(BC'), 1].
  const double area_u = static_cast<double>(u) * omega;
  const double sn = std::sin(area_u - s.alpha), cs = std::cos(area_u - s.alpha);
  const double cos_alpha = s.cos_alpha, sin_alpha = std::sqrt(std::max(0.0, 1 - cos_alpha * cos_alpha));
  const double cos_c = dot(s.a, s.b);
  const double uu = cs - cos_alpha;
  const double vv = sn + sin_alpha * cos_c;
  const double den = (vv * sn + uu * cs) * sin_alpha;
  double q = den != 0 ? ((vv * cs - uu * sn) * cos_alpha - vv) / den : 1.0;
  q = std::clamp(q, -1.0, 1.0);
  const D3 c_hat = s.a * q + orthogonal_unit(s.c, s.a) * std::sqrt(std::max(0.0, 1 - q * q));
  const double z = std::clamp(1 - static_cast<double>(v) * (1 - dot(c_hat, s.b)), -1.0, 1.0);
  const D3 d = s.b * z + orthogonal_unit(c_hat, s.b) * std::sqrt(std::max(0.0, 1 - z * z));
  const double l = length(d);
  if (!(l > 0)) return std::nullopt;
  return Vec3{static_cast<float>(d.x / l), static_cast<float>(d.y / l), static_cast<float>(d.z / l)};
}

}  // namespace lf
