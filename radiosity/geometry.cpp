#include "radiosity/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace lf::radiosity {

Vec3 Polygon::normal() const {
  Vec3 c = cross(v[1] - v[0], v[2] - v[0]);
  if (count == 4) c += cross(v[2] - v[0], v[3] - v[0]);
  return normalize(c);
}

float Polygon::area() const {
  float a = 0.5f * length(cross(v[1] - v[0], v[2] - v[0]));
  if (count == 4) a += 0.5f * length(cross(v[2] - v[0], v[3] - v[0]));
  return a;
}

Vec3 Polygon::centroid() const {
  Vec3 c;
  for (int i = 0; i < count; ++i) c += v[static_cast<size_t>(i)];
  return c / static_cast<float>(count);
}

float Polygon::max_edge() const {
  float m = 0;
  for (int i = 0; i < count; ++i) m = std::max(m, length(v[static_cast<size_t>((i + 1) % count)] - v[static_cast<size_t>(i)]));
  return m;
}

static Polygon tri(Vec3 a, Vec3 b, Vec3 c) { return Polygon{{a, b, c, Vec3{}}, 3}; }
static Polygon quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d) { return Polygon{{a, b, c, d}, 4}; }
static Vec3 mid(Vec3 a, Vec3 b) { return (a + b) * 0.5f; }

std::array<Polygon, 4> split4(const Polygon& p) {
  const auto& v = p.v;
  if (p.count == 3) {
    Vec3 ab = mid(v[0], v[1]), bc = mid(v[1], v[2]), ca = mid(v[2], v[0]);
    return {tri(v[0], ab, ca), tri(ab, v[1], bc), tri(ca, bc, v[2]), tri(ab, bc, ca)};
  }
  Vec3 ab = mid(v[0], v[1]), bc = mid(v[1], v[2]), cd = mid(v[2], v[3]), da = mid(v[3], v[0]);
  Vec3 c = mid(ab, cd);
  return {quad(v[0], ab, c, da), quad(ab, v[1], bc, c), quad(c, bc, v[2], cd), quad(da, c, cd, v[3])};
}

std::vector<Polygon> tile_quad(const Polygon& p, int ku, int kv) {
  std::vector<Polygon> out;
  out.reserve(static_cast<size_t>(ku * kv));
  const auto& v = p.v;
  auto at = [&](int i, int j) {
    float s = static_cast<float>(i) / static_cast<float>(ku), t = static_cast<float>(j) / static_cast<float>(kv);
    return v[0] * ((1 - s) * (1 - t)) + v[1] * (s * (1 - t)) + v[2] * (s * t) + v[3] * ((1 - s) * t);
  };
  for (int j = 0; j < kv; ++j)
    for (int i = 0; i < ku; ++i) out.push_back(quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)));
  return out;
}

std::vector<Polygon> tile(const Polygon& p, int k) {
  if (k <= 1) return {p};
  if (p.count == 4) return tile_quad(p, k, k);
  std::vector<Polygon> out;
  out.reserve(static_cast<size_t>(k * k));
  const float inv = 1.0f / static_cast<float>(k);
  const auto& v = p.v;
  auto at = [&](int i, int j) {  // v0 + i/k (v1 - v0) + j/k (v2 - v0)
    return v[0] + (v[1] - v[0]) * (static_cast<float>(i) * inv) + (v[2] - v[0]) * (static_cast<float>(j) * inv);
  };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i + j < k; ++i) {
      out.push_back(tri(at(i, j), at(i + 1, j), at(i, j + 1)));
      if (i + j + 1 < k) out.push_back(tri(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)));
    }
  return out;
}

std::vector<Vec3> sample_points(const Polygon& p) {
  const Vec3 c = p.centroid();
  const float pull = p.count == 4 ? 0.57735027f : 0.5f;
  std::vector<Vec3> out;
  for (int i = 0; i < p.count; ++i) out.push_back(c + (p.v[static_cast<size_t>(i)] - c) * pull);
  return out;
}

namespace {
struct D3 {
  double x, y, z;
};
D3 sub(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dotd(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 crossd(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
D3 lerp(D3 a, D3 b, double t) { return {a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t}; }
D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
}  // namespace

double point_to_polygon(Vec3 x_, Vec3 n_, const Polygon& q) {
  const D3 x = d3(x_), n = d3(n_);
  // Only the emitting (front) side of q sends light.
  if (dotd(d3(q.normal()), sub(x, d3(q.v[0]))) <= 0) return 0;
  // Clip q to the part above x's tangent plane (Sutherland-Hodgman against one plane): light from below the
  // horizon does not reach a surface.
  D3 in[4], out[8];
  int n_in = q.count, n_out = 0;
  for (int i = 0; i < n_in; ++i) in[i] = sub(d3(q.v[static_cast<size_t>(i)]), x);
  for (int i = 0; i < n_in; ++i) {
    const D3 a = in[i], b = in[(i + 1) % n_in];
    const double da = dotd(a, n), db = dotd(b, n);
    if (da > 0) out[n_out++] = a;
    if ((da > 0) != (db > 0)) out[n_out++] = lerp(a, b, da / (da - db));
  }
  if (n_out < 3) return 0;
  double sum = 0;
  for (int i = 0; i < n_out; ++i) {
    D3 a = out[i], b = out[(i + 1) % n_out];
    const double la = std::sqrt(dotd(a, a)), lb = std::sqrt(dotd(b, b));
    if (la <= 0 || lb <= 0) continue;
    const D3 c = crossd(a, b);
    const double lc = std::sqrt(dotd(c, c));
    if (lc <= 0) continue;
    const double angle = std::atan2(lc, dotd(a, b));
    sum += angle * dotd(n, c) / lc;
  }
  return std::abs(sum) / (2 * M_PI);
}

}  // namespace lf::radiosity
