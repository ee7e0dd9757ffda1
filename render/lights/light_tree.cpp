#include "render/lights/light_tree.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "render/scene/scene.hpp"

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

// Four floats in one vector register (GCC's vector extension; SSE on x86-64, plain code elsewhere).
using F4 = float __attribute__((vector_size(16)));

F4 load4(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

F4 sqrt4(F4 v) {
#if defined(__SSE__)
  return _mm_sqrt_ps(v);
#else
  for (int i = 0; i < 4; ++i) v[i] = std::sqrt(v[i]);
  return v;
#endif
}

F4 max4(F4 a, F4 b) { return a > b ? a : b; }

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
    const float power = p.spot() ? static_cast<float>(p.power()) : 4 * kPi * average(p.intensity);
    items.push_back({p.position, p.position, p.position, {0, 0, 1}, -1.0f, power,
                     static_cast<uint32_t>(emitters.size() + i)});
  }
  trail_.assign(items.size(), 0);
  if (items.empty()) return;
  std::vector<Node> binary;
  build(binary, items, 0, items.size());
  collapse(binary, 0, 0, 0);
}

uint32_t LightTree::build(std::vector<Node>& nodes, std::vector<Item>& items, size_t first, size_t last) {
  const uint32_t index = static_cast<uint32_t>(nodes.size());
  nodes.emplace_back();
  if (last - first == 1) {
    const Item& it = items[first];
    Node& leaf = nodes[index];
    leaf.lo = it.lo;
    leaf.hi = it.hi;
    leaf.axis = it.axis;
    leaf.cos_spread = it.cos_spread;
    leaf.power = it.power;
    leaf.light = it.light;
    leaf.leaf = true;
    return index;
  }
  // Halve at the median along the widest extent of the centroids: a balanced tree (depth ceil(log2 n), so the
  // four-way tree's levels, two bits each, fit one 64-bit trail). Ties go by light number, so every standard
  // library splits alike.
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
  const uint32_t left = build(nodes, items, first, mid);
  const uint32_t right = build(nodes, items, mid, last);
  const Node& l = nodes[left];
  const Node& r = nodes[right];
  Node node;
  node.lo = min3(l.lo, r.lo);
  node.hi = max3(l.hi, r.hi);
  node.power = l.power + r.power;
  merge_cones(l.axis, l.cos_spread, r.axis, r.cos_spread, node.axis, node.cos_spread);
  node.right = right;
  nodes[index] = node;
  return index;
}

// The four-way node standing for binary node `at` (and what lies below it): its slots are at's descendants two
// levels down, or fewer where a leaf comes first (a lone light is a root with one slot).
int32_t LightTree::collapse(const std::vector<Node>& binary, uint32_t at, int depth, uint64_t trail) {
  std::vector<uint32_t> slots{at};
  for (;;) {
    const auto interior = std::find_if(slots.begin(), slots.end(), [&](uint32_t s) { return !binary[s].leaf; });
    if (interior == slots.end() || slots.size() + 1 > static_cast<size_t>(kWidth)) break;
    const uint32_t s = *interior;
    *interior = binary[s].right;
    slots.insert(interior, s + 1);
  }
  if (depth >= 32) throw std::length_error("light tree: too deep for its trails");
  depth_ = std::max(depth_, depth);
  const int32_t index = static_cast<int32_t>(nodes_.size());
  nodes_.emplace_back();
  Wide wide{};
  for (int k = 0; k < kWidth; ++k) {
    wide.child[k] = -1;
    wide.cos_spread[k] = 1;
  }
  for (size_t k = 0; k < slots.size(); ++k) {
    const Node& b = binary[slots[k]];
    const Vec3 centre = (b.lo + b.hi) * 0.5f;
    wide.cx[k] = centre.x;
    wide.cy[k] = centre.y;
    wide.cz[k] = centre.z;
    wide.radius[k] = length(b.hi - b.lo) * 0.5f;
    wide.ax[k] = b.axis.x;
    wide.ay[k] = b.axis.y;
    wide.az[k] = b.axis.z;
    wide.cos_spread[k] = b.cos_spread;
    wide.sin_spread[k] = sine_of(b.cos_spread);
    wide.power[k] = b.power;
    const uint64_t to_slot = trail | (static_cast<uint64_t>(k) << (2 * depth));
    if (b.leaf) {
      wide.child[k] = ~static_cast<int32_t>(b.light);
      trail_[b.light] = to_slot;
    } else {
      wide.child[k] = collapse(binary, slots[k], depth + 1, to_slot);
    }
  }
  nodes_[static_cast<size_t>(index)] = wide;
  return index;
}

// An upper bound, up to a constant, of what a child's lights can give x: power x cos(theta') x cos(theta_i') /
// distance², where theta' bounds the angle between a light's emitting direction and x (reduced by the cone's spread
// and the angle the child's bounding sphere subtends) and theta_i' the angle between n and a light (reduced by that
// angle too). Zero when every light of the child faces away from x or lies below x's horizon: those cannot
// contribute. All emitters are one-sided and Lambertian: nothing leaves beyond 90 degrees of a normal.
// The four children lane by lane; each lane computes what the scalar formula would.
void LightTree::importance(const Wide& node, Vec3 x, Vec3 n, float out[kWidth]) const {
  const F4 zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
  const F4 dx = x.x - load4(node.cx), dy = x.y - load4(node.cy), dz = x.z - load4(node.cz);
  const F4 radius = load4(node.radius);
  const F4 d2 = dx * dx + dy * dy + dz * dz, r2 = radius * radius;
  const F4 tiny = {1e-20f, 1e-20f, 1e-20f, 1e-20f};
  const F4 falloff = load4(node.power) / max4(max4(d2, r2), tiny);
  // Lanes with x among the lights (d2 <= r2) bound no angle; their d2 may be 0, so they divide by 1 instead.
  const auto among = d2 <= r2;
  const F4 inverse_d = one / sqrt4(among ? one : d2);
  const F4 sin_b = radius * inverse_d, cos_b = sqrt4(max4(zero, one - sin_b * sin_b));
  const F4 wx = dx * inverse_d, wy = dy * inverse_d, wz = dz * inverse_d;  // from the lights to x
  // cos of max(0, theta_w - theta_o - theta_b) at the lights.
  const F4 cos_spread = load4(node.cos_spread), sin_spread = load4(node.sin_spread);
  const F4 cos_w = load4(node.ax) * wx + load4(node.ay) * wy + load4(node.az) * wz;
  const F4 sin_w = sqrt4(max4(zero, one - cos_w * cos_w));
  const auto outside_cone = cos_w < cos_spread;
  const F4 cos_x = outside_cone ? cos_w * cos_spread + sin_w * sin_spread : one;
  const F4 sin_x = outside_cone ? sin_w * cos_spread - cos_w * sin_spread : zero;
  const F4 cos_at_lights = cos_x >= cos_b ? one : cos_x * cos_b + sin_x * sin_b;
  // cos of max(0, theta_i - theta_b) at x.
  const F4 cos_i = -(n.x * wx + n.y * wy + n.z * wz);
  const F4 sin_i = sqrt4(max4(zero, one - cos_i * cos_i));
  // A point that gathers light from every side (n = 0: rough glass) bounds no angle at x.
  const bool any_side = n.x == 0 && n.y == 0 && n.z == 0;
  const F4 cos_at_x = any_side ? one : (cos_i >= cos_b ? one : cos_i * cos_b + sin_i * sin_b);
  const auto dark = (cos_at_lights <= zero) | (cos_at_x <= zero);
  const F4 bounded = dark ? zero : falloff * cos_at_lights * cos_at_x;
  const F4 result = among ? falloff : bounded;
  std::memcpy(out, &result, sizeof result);
}

float LightTree::weigh(const Wide& node, Vec3 x, Vec3 n, float weight[kWidth]) const {
  importance(node, x, n, weight);
  // One order of additions for pick() and probability(), so that they agree bit for bit.
  return weight[0] + weight[1] + weight[2] + weight[3];
}

namespace {

// The slot a descent takes at a node whose children weigh `weight` (total > 0) for u in [0, 1): the slots share
// [0, 1) in proportion to their weights. `below` is the weight of the slots before it. Never a slot of weight 0.
int choose_slot(const float* weight, float total, float u, float& below) {
  const float target = u * total;
  int chosen = -1;
  float sum = 0;
  for (int k = 0; k < 4; ++k) {
    if (!(weight[k] > 0)) continue;
    chosen = k;
    below = sum;
    if (target < sum + weight[k]) break;
    sum += weight[k];
  }
  return chosen;
}

}  // namespace

bool LightTree::reaches(Vec3 x, Vec3 n) const {
  if (nodes_.empty()) return false;
  float weight[kWidth];
  return weigh(nodes_[0], x, n, weight) > 0;
}

bool LightTree::pick(Vec3 x, Vec3 n, float u, size_t& light, float& probability, float* remainder) const {
  if (nodes_.empty()) return false;
  int32_t at = 0;
  float p = 1;
  for (;;) {
    const Wide& node = nodes_[static_cast<size_t>(at)];
    float weight[kWidth];
    const float total = weigh(node, x, n, weight);
    if (!(total > 0)) return false;
    float below = 0;
    const int k = choose_slot(weight, total, u, below);
    p *= weight[k] / total;
    u = std::clamp((u * total - below) / weight[k], 0.0f, 0x1.fffffep-1f);
    if (node.child[k] < 0) {
      light = static_cast<size_t>(~node.child[k]);
      break;
    }
    at = node.child[k];
  }
  probability = p;
  if (remainder) *remainder = u;
  return p > 0;
}

float LightTree::probability(Vec3 x, Vec3 n, size_t light) const {
  if (light >= trail_.size()) return 0;
  int32_t at = 0;
  float p = 1;
  for (int level = 0;; ++level) {
    const Wide& node = nodes_[static_cast<size_t>(at)];
    float weight[kWidth];
    const float total = weigh(node, x, n, weight);
    const int k = static_cast<int>((trail_[light] >> (2 * level)) & 3);
    if (!(total > 0) || !(weight[k] > 0)) return 0;
    p *= weight[k] / total;
    if (node.child[k] < 0) return p;
    at = node.child[k];
  }
}

}  // namespace lf
