#include "render/light_tree.hpp"

#include <algorithm>
#include <cmath>

#include "render/scene.hpp"

namespace lf {

namespace {

Vec3 min3(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
Vec3 max3(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
float sine_of(float c) { return std::sqrt(std::max(0.0f, 1.0f - c * c)); }

// The smallest cone (axis, cosine of its half-angle) holding cones a and b; -1 when it is every direction. Widened
// by a hair so that rounding never leaves a light's direction outside its ancestors' cones.
void merge_cones(Vec3 a, float cos_a, Vec3 b, float cos_b, Vec3& axis, float& cos_out) {
  axis = a;
  cos_out = -1;
  if (cos_a <= -1 || cos_b <= -1) return;
  float theta_a = std::acos(std::clamp(cos_a, -1.0f, 1.0f)), theta_b = std::acos(std::clamp(cos_b, -1.0f, 1.0f));
  if (theta_b > theta_a) {
    std::swap(a, b);
    std::swap(theta_a, theta_b);
  }
  const float theta_d = std::acos(std::clamp(dot(a, b), -1.0f, 1.0f));
  if (std::min(theta_d + theta_b, kPi) <= theta_a) {  // a holds b
    axis = a;
    cos_out = std::cos(std::min(theta_a + 1e-4f, kPi));
    return;
  }
  const float theta_o = (theta_a + theta_d + theta_b) / 2 + 1e-4f;
  const Vec3 w = cross(a, b);
  if (theta_o >= kPi || dot(w, w) < 1e-12f) return;
  // Rotate a towards b by what the new cone needs beyond a's (Rodrigues; a is perpendicular to w).
  const Vec3 wn = normalize(w);
  const float turn = theta_o - theta_a;
  axis = normalize(a * std::cos(turn) + cross(wn, a) * std::sin(turn));
  cos_out = std::cos(theta_o);
}

}  // namespace

LightTree::LightTree(const Scene& scene) {
  std::vector<Item> items;
  const auto& emitters = scene.emitters();
  for (size_t i = 0; i < emitters.size(); ++i) {
    const uint32_t t = emitters[i];
    const Vec3 a = scene.vertex(t, 0), b = scene.vertex(t, 1), c = scene.vertex(t, 2);
    const float power = scene.emitted_power(t);
    items.push_back({min3(a, min3(b, c)), max3(a, max3(b, c)), (a + b + c) / 3.0f, scene.normal(t), 1.0f, power,
                     static_cast<uint32_t>(i)});
  }
  for (size_t i = 0; i < scene.point_lights().size(); ++i) {
    const PointLight& p = scene.point_lights()[i];
    items.push_back({p.position, p.position, p.position, {0, 0, 1}, -1.0f, 4 * kPi * average(p.intensity),
                     static_cast<uint32_t>(emitters.size() + i)});
  }
  trail_.assign(items.size(), 0);
  if (!items.empty()) build(items, 0, items.size(), 0, 0);
}

void LightTree::finish(Node& node) {
  node.centre = (node.lo + node.hi) * 0.5f;
  node.radius = length(node.hi - node.lo) * 0.5f;
  node.sin_spread = sine_of(node.cos_spread);
}

uint32_t LightTree::build(std::vector<Item>& items, size_t first, size_t last, int depth, uint64_t trail) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  depth_ = std::max(depth_, depth);
  if (last - first == 1) {
    const Item& it = items[first];
    Node& leaf = nodes_[index];
    leaf.lo = it.lo;
    leaf.hi = it.hi;
    leaf.axis = it.axis;
    leaf.cos_spread = it.cos_spread;
    leaf.power = it.power;
    leaf.light = it.light;
    leaf.leaf = true;
    finish(leaf);
    trail_[it.light] = trail;
    return index;
  }
  // Halve at the median along the widest extent of the centroids: a balanced tree (depth ceil(log2 n), so a
  // light's turns fit one 64-bit trail). Ties go by light number, so every standard library splits alike.
  Vec3 lo = items[first].centroid, hi = lo;
  for (size_t i = first; i < last; ++i) {
    lo = min3(lo, items[i].centroid);
    hi = max3(hi, items[i].centroid);
  }
  const Vec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const size_t mid = first + (last - first) / 2;
  std::nth_element(items.begin() + static_cast<std::ptrdiff_t>(first), items.begin() + static_cast<std::ptrdiff_t>(mid),
                   items.begin() + static_cast<std::ptrdiff_t>(last), [axis](const Item& a, const Item& b) {
                     return a.centroid[axis] != b.centroid[axis] ? a.centroid[axis] < b.centroid[axis] : a.light < b.light;
                   });
  const uint32_t left = build(items, first, mid, depth + 1, trail);
  const uint32_t right = build(items, mid, last, depth + 1, trail | (uint64_t{1} << depth));
  const Node& l = nodes_[left];
  const Node& r = nodes_[right];
  Node node;
  node.lo = min3(l.lo, r.lo);
  node.hi = max3(l.hi, r.hi);
  node.power = l.power + r.power;
  merge_cones(l.axis, l.cos_spread, r.axis, r.cos_spread, node.axis, node.cos_spread);
  node.right = right;
  finish(node);
  nodes_[index] = node;
  return index;
}

// An upper bound, up to a constant, of what the node's lights can give x: power x cos(theta') x cos(theta_i') /
// distance², where theta' bounds the angle between a light's emitting direction and x (reduced by the cone's spread
// and the angle the node's bounding sphere subtends) and theta_i' the angle between n and a light (reduced by that
// angle too). Zero when every light of the node faces away from x or lies below x's horizon: those cannot
// contribute. All emitters are one-sided and Lambertian: nothing leaves beyond 90 degrees of a normal.
float LightTree::importance(const Node& node, Vec3 x, Vec3 n) const {
  const Vec3 d = x - node.centre;
  const float d2 = dot(d, d), r2 = node.radius * node.radius;
  const float falloff = node.power / std::max({d2, r2, 1e-20f});
  if (d2 <= r2) return falloff;  // x among the lights: no angle can be bounded
  const float inverse_d = 1.0f / std::sqrt(d2);
  const float sin_b = node.radius * inverse_d, cos_b = sine_of(sin_b);
  const Vec3 wi = d * inverse_d;  // from the lights to x
  // cos of max(0, theta_w - theta_o - theta_b) at the lights.
  float cos_x = 1, sin_x = 0;
  const float cos_w = dot(node.axis, wi);
  if (cos_w < node.cos_spread) {
    const float sin_w = sine_of(cos_w);
    cos_x = cos_w * node.cos_spread + sin_w * node.sin_spread;
    sin_x = sin_w * node.cos_spread - cos_w * node.sin_spread;
  }
  const float cos_at_lights = cos_x >= cos_b ? 1.0f : cos_x * cos_b + sin_x * sin_b;
  if (cos_at_lights <= 0) return 0;
  // cos of max(0, theta_i - theta_b) at x.
  const float cos_i = -dot(n, wi), sin_i = sine_of(cos_i);
  const float cos_at_x = cos_i >= cos_b ? 1.0f : cos_i * cos_b + sin_i * sin_b;
  if (cos_at_x <= 0) return 0;
  return falloff * cos_at_lights * cos_at_x;
}

bool LightTree::pick(Vec3 x, Vec3 n, float u, size_t& light, float& probability, float* remainder) const {
  if (nodes_.empty()) return false;
  uint32_t at = 0;
  float p = 1;
  while (!nodes_[at].leaf) {
    const uint32_t left = at + 1, right = nodes_[at].right;
    const float il = importance(nodes_[left], x, n), ir = importance(nodes_[right], x, n);
    if (!(il + ir > 0)) return false;
    const float pl = il / (il + ir);
    if (u < pl) {
      u = std::min(u / pl, 0x1.fffffep-1f);
      p *= pl;
      at = left;
    } else {
      u = std::min((u - pl) / (1 - pl), 0x1.fffffep-1f);
      p *= 1 - pl;
      at = right;
    }
  }
  light = nodes_[at].light;
  probability = p;
  if (remainder) *remainder = u;
  return p > 0;
}

float LightTree::probability(Vec3 x, Vec3 n, size_t light) const {
  if (light >= trail_.size()) return 0;
  uint32_t at = 0;
  float p = 1;
  for (int level = 0; !nodes_[at].leaf; ++level) {
    const uint32_t left = at + 1, right = nodes_[at].right;
    const float il = importance(nodes_[left], x, n), ir = importance(nodes_[right], x, n);
    if (!(il + ir > 0)) return 0;
    const bool go_right = (trail_[light] >> level) & 1;
    p *= (go_right ? ir : il) / (il + ir);
    at = go_right ? right : left;
  }
  return p;
}

}  // namespace lf
