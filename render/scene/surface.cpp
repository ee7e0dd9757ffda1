// Surface detail of a scene's triangles: barycentrics, interpolated vertex normals, texture coordinates, and the
// textures they look up (albedo, alpha cut-outs).
#include <algorithm>
#include <array>
#include <cmath>

#include "render/scene/scene.hpp"

namespace lf {

namespace {

// 8-bit sRGB to linear, once.
const std::array<float, 256>& srgb_to_linear() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const float v = static_cast<float>(i) / 255.0f;
      t[static_cast<size_t>(i)] = srgb_decode(v);
    }
    return t;
  }();
  return table;
}

// Where an alpha map's coverage is below this, the surface is not there (map_d's cut).
constexpr float kCoverageCut = 0.5f;

// Wraps a texel index into [0, n) (textures repeat, as OBJ coordinates outside [0, 1] expect).
uint32_t wrap(int64_t i, uint32_t n) {
  const int64_t m = i % static_cast<int64_t>(n);
  return static_cast<uint32_t>(m < 0 ? m + n : m);
}

}  // namespace

uint64_t Texture::pyramid_bytes(uint32_t w, uint32_t h, uint32_t c) {
  uint64_t total = 0;
  while (true) {
    total += uint64_t{w} * h * c;
    if (w == 1 && h == 1) return total;
    w = std::max(1u, w / 2);
    h = std::max(1u, h / 2);
  }
}

void Texture::build_pyramid() {
  const uint64_t base = uint64_t{width} * height * channels;
  owned.resize(base);
  owned.reserve(pyramid_bytes(width, height, channels));
  const bool colour = channels == 3 && !linear;
  auto encode = [&](float l) {
    const float v = colour ? srgb_encode(l) : l;
    return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
  };
  uint32_t w = width, h = height;
  size_t at = 0;  // where the level being halved starts
  while (w > 1 || h > 1) {
    const uint32_t nw = std::max(1u, w / 2), nh = std::max(1u, h / 2);
    const size_t next = owned.size();
    owned.resize(next + size_t{nw} * nh * channels);
    for (uint32_t y = 0; y < nh; ++y)
      for (uint32_t x = 0; x < nw; ++x)
        for (uint32_t c = 0; c < channels; ++c) {
          // The 2x2 texels below (one row or column where the level above has an odd or unit size).
          float sum = 0;
          int n = 0;
          for (uint32_t dy = 0; dy < 2 && 2 * y + dy < h; ++dy)
            for (uint32_t dx = 0; dx < 2 && 2 * x + dx < w; ++dx) {
              const uint8_t v = owned[at + (size_t{2 * y + dy} * w + 2 * x + dx) * channels + c];
              sum += colour ? srgb_to_linear()[v] : static_cast<float>(v) / 255.0f;
              ++n;
            }
          owned[next + (size_t{y} * nw + x) * channels + c] = encode(sum / static_cast<float>(n));
        }
    at = next;
    w = nw;
    h = nh;
  }
  texels = owned;
}

namespace {

// Channels c .. c + N - 1 of one level (w x h texels at `texels`), bilinear and repeating: the texel coordinates
// once for all of them (a colour's three lookups cost little more than one), each channel the same arithmetic.
template <int N>
std::array<float, N> bilinear(const uint8_t* texels, uint32_t w, uint32_t h, uint32_t channels, bool linear, Vec2 uv,
                              uint32_t c) {
  std::array<float, N> out{};
  // Texel centres sit at half-integers; v = 0 is the bottom row, and files store the top row first.
  const float x = uv.u * static_cast<float>(w) - 0.5f;
  const float y = (1.0f - uv.v) * static_cast<float>(h) - 0.5f;
  if (!std::isfinite(x) || !std::isfinite(y)) return out;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  // Far-off coordinates are reduced first so that the integer conversion cannot overflow (inside the image fmod
  // would return them unchanged, so it is skipped there).
  const float wide = static_cast<float>(w) * 1024.0f, high = static_cast<float>(h) * 1024.0f;
  const auto ix = static_cast<int64_t>(fx >= 0 && fx < static_cast<float>(w) ? fx : std::fmod(fx, wide));
  const auto iy = static_cast<int64_t>(fy >= 0 && fy < static_cast<float>(h) ? fy : std::fmod(fy, high));
  const uint32_t x0 = wrap(ix, w), x1 = wrap(ix + 1, w), y0 = wrap(iy, h), y1 = wrap(iy + 1, h);
  const bool colour = channels == 3 && !linear;
  const uint8_t* row0 = texels + static_cast<size_t>(y0) * w * channels;
  const uint8_t* row1 = texels + static_cast<size_t>(y1) * w * channels;
  for (int k = 0; k < N; ++k) {
    const uint32_t ch = c + static_cast<uint32_t>(k);
    auto texel = [&](const uint8_t* row, uint32_t tx) {
      const uint8_t v = row[static_cast<size_t>(tx) * channels + ch];
      return colour ? srgb_to_linear()[v] : static_cast<float>(v) / 255.0f;
    };
    out[k] = (texel(row0, x0) * (1 - ax) + texel(row0, x1) * ax) * (1 - ay) +
             (texel(row1, x0) * (1 - ax) + texel(row1, x1) * ax) * ay;
  }
  return out;
}

}  // namespace

float Texture::texel(int64_t x, int64_t y, uint32_t c) const {
  if (width == 0 || height == 0 || c >= channels) return 1.0f;
  // Most lookups are inside the image: the wrap's division only for those that are not.
  const uint32_t tx = x >= 0 && x < width ? static_cast<uint32_t>(x) : wrap(x, width);
  const uint32_t ty = y >= 0 && y < height ? static_cast<uint32_t>(y) : wrap(y, height);
  const uint8_t v = texels[(static_cast<size_t>(ty) * width + tx) * channels + c];
  return channels == 3 && !linear ? srgb_to_linear()[v] : static_cast<float>(v) / 255.0f;
}

namespace {

// Channels c .. c + N - 1 at uv and `lod` (Texture::sample's arithmetic for each).
template <int N>
std::array<float, N> sample_channels(const Texture& tex, Vec2 uv, uint32_t c, float lod) {
  const uint8_t* texels = tex.texels.data();
  if (!(lod > 0)) return bilinear<N>(texels, tex.width, tex.height, tex.channels, tex.linear, uv, c);
  // Walk down to the level below `lod`, then blend it with the next.
  const int below = static_cast<int>(std::min(lod, 30.0f));
  const float blend = std::min(lod, 30.0f) - static_cast<float>(below);
  uint32_t w = tex.width, h = tex.height;
  size_t at = 0;
  for (int l = 0; l < below && (w > 1 || h > 1); ++l) {
    at += size_t{w} * h * tex.channels;
    w = std::max(1u, w / 2);
    h = std::max(1u, h / 2);
  }
  std::array<float, N> fine = bilinear<N>(texels + at, w, h, tex.channels, tex.linear, uv, c);
  if (blend <= 0 || (w == 1 && h == 1)) return fine;
  const size_t next = at + size_t{w} * h * tex.channels;
  const std::array<float, N> coarse =
      bilinear<N>(texels + next, std::max(1u, w / 2), std::max(1u, h / 2), tex.channels, tex.linear, uv, c);
  for (int k = 0; k < N; ++k) fine[k] = fine[k] * (1 - blend) + coarse[k] * blend;
  return fine;
}

}  // namespace

float Texture::sample(Vec2 uv, uint32_t c, float lod) const {
  if (width == 0 || height == 0 || c >= channels) return 1.0f;
  return sample_channels<1>(*this, uv, c, lod)[0];
}

RGB Texture::sample_rgb(Vec2 uv, float lod) const {
  if (width == 0 || height == 0 || channels < 3) return {sample(uv, 0, lod), sample(uv, 1, lod), sample(uv, 2, lod)};
  const std::array<float, 3> v = sample_channels<3>(*this, uv, 0, lod);
  return {v[0], v[1], v[2]};
}

Vec3 Scene::barycentrics(uint32_t t, Vec3 p) const {
  const Vec3 a = vertex(t, 0), e1 = vertex(t, 1) - a, e2 = vertex(t, 2) - a, d = p - a;
  const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2), d1 = dot(d, e1), d2 = dot(d, e2);
  const float det = d11 * d22 - d12 * d12;
  if (!(det > 0)) return {1, 0, 0};
  // Clamped to the triangle: a point offset a little off it still gets its nearest detail.
  const float b1 = std::clamp((d22 * d1 - d12 * d2) / det, 0.0f, 1.0f);
  const float b2 = std::clamp((d11 * d2 - d12 * d1) / det, 0.0f, 1.0f - b1);
  return {1 - b1 - b2, b1, b2};
}

Vec3 Scene::shading_normal(uint32_t t, Vec3 b) const {
  if (corner_normal_view_.empty()) return normal(t);
  const Vec3* n = &corner_normal_view_[3 * static_cast<size_t>(t)];
  Vec3 s = n[0] * b.x + n[1] * b.y + n[2] * b.z;
  const float l = length(s);
  if (!(l > 1e-6f)) return normal(t);
  s = s / l;
  // Vertex normals wound against the face (a mirrored export) still mean the face's side.
  return dot(s, normal(t)) < 0 ? -s : s;
}

Vec2 Scene::uv(uint32_t t, Vec3 b) const {
  if (corner_uv_view_.empty()) return {};
  const Vec2* c = &corner_uv_view_[3 * static_cast<size_t>(t)];
  return {c[0].u * b.x + c[1].u * b.y + c[2].u * b.z, c[0].v * b.x + c[1].v * b.y + c[2].v * b.z};
}

// The mip level at which triangle t shows `tex` for a pixel `footprint` wide (0: the full image).
static float texture_lod(const Scene& s, uint32_t t, const Texture& tex, float footprint) {
  if (!(footprint > 0)) return 0;
  // Texels per scene unit on this triangle: the square root of its texel area over its area.
  const Vec2 c[3] = {s.corner_uv(t, 0), s.corner_uv(t, 1), s.corner_uv(t, 2)};
  const float uv_area = 0.5f * std::abs((c[1].u - c[0].u) * (c[2].v - c[0].v) - (c[2].u - c[0].u) * (c[1].v - c[0].v));
  const float density = std::sqrt(uv_area * static_cast<float>(tex.width) * static_cast<float>(tex.height) / s.area(t));
  const float texels = footprint * density;
  return texels > 1 && std::isfinite(texels) ? std::log2(texels) : 0.0f;
}

bool Scene::file_tangent_frame(uint32_t t, Vec3 b, Vec3 n, Vec3& tangent, Vec3& bitangent) const {
  if (corner_tangent_view_.empty()) return false;
  const CornerTangent* c = &corner_tangent_view_[3 * static_cast<size_t>(t)];
  // Interpolated as vertex normals are, then made orthonormal around the shading normal (MikkTSpace's frames are
  // per vertex, shared by the faces around it: no seams where the faces' own uv frames would turn).
  const Vec3 d = c[0].direction * b.x + c[1].direction * b.y + c[2].direction * b.z;
  const Vec3 along = d - n * dot(n, d);
  if (!(dot(along, along) > 1e-12f) || !std::isfinite(dot(along, along))) return false;
  tangent = normalize(along);
  bitangent = cross(n, tangent) * (c[0].sign < 0 ? -1.0f : 1.0f);
  return true;
}

Vec3 Scene::normal_mapped(uint32_t t, Vec3 b, Vec3 n) const {
  const Material& m = materials_[material_view_[t]];
  if (m.normal_map < 0 || corner_uv_view_.empty()) return n;
  const Vec2 at = uv(t, b);
  if (!std::isfinite(at.u) || !std::isfinite(at.v)) return n;
  Vec3 tangent, bitangent;
  if (!file_tangent_frame(t, b, n, tangent, bitangent)) {
    // The tangent frame: dP/du and dP/dv over the triangle (v up, as texture coordinates are kept), made
    // orthonormal around n; the bitangent keeps the side dP/dv is on (a mirrored UV layout flips it).
    const Vec3 e1 = vertex(t, 1) - vertex(t, 0), e2 = vertex(t, 2) - vertex(t, 0);
    const Vec2 c0 = corner_uv(t, 0), c1 = corner_uv(t, 1), c2 = corner_uv(t, 2);
    const float du1 = c1.u - c0.u, dv1 = c1.v - c0.v, du2 = c2.u - c0.u, dv2 = c2.v - c0.v;
    const float det = du1 * dv2 - du2 * dv1;
    if (!(std::abs(det) > 0)) return n;  // degenerate texture coordinates: no frame
    const Vec3 dpdu = (e1 * dv2 - e2 * dv1) / det, dpdv = (e2 * du1 - e1 * du2) / det;
    const Vec3 along = dpdu - n * dot(n, dpdu);
    if (!(dot(along, along) > 0)) return n;
    tangent = normalize(along);
    bitangent = cross(n, tangent);
    if (dot(bitangent, dpdv) < 0) bitangent = -bitangent;
  }
  const Texture& tex = textures_[static_cast<size_t>(m.normal_map)];
  const RGB texel = tex.sample_rgb(at);
  const float x = (2 * texel.x - 1) * m.normal_scale, y = (2 * texel.y - 1) * m.normal_scale, z = 2 * texel.z - 1;
  const Vec3 turned = tangent * x + bitangent * y + n * z;
  const float len = length(turned);
  return len > 0 && std::isfinite(len) ? turned / len : n;
}

void Scene::metal_rough_at(uint32_t t, Vec3 b, float footprint, float& metallic, float& roughness) const {
  const Material& m = materials_[material_view_[t]];
  metallic = m.metallic;
  roughness = m.roughness;
  if ((m.metallic_map < 0 && m.roughness_map < 0) || corner_uv_view_.empty()) return;
  const Vec2 at = uv(t, b);
  if (!std::isfinite(at.u) || !std::isfinite(at.v)) return;
  for (auto [map, value] : {std::pair{m.metallic_map, &metallic}, std::pair{m.roughness_map, &roughness}}) {
    if (map < 0) continue;
    const Texture& tex = textures_[static_cast<size_t>(map)];
    *value = std::clamp(*value * tex.sample(at, 0, texture_lod(*this, t, tex, footprint)), 0.0f, 1.0f);
  }
}

RGB Scene::albedo(uint32_t t, Vec3 b, float footprint) const {
  const Material& m = materials_[material_view_[t]];
  if (m.kd_map < 0 || corner_uv_view_.empty()) return m.kd;
  const Texture& tex = textures_[static_cast<size_t>(m.kd_map)];
  const Vec2 at = uv(t, b);
  if (!std::isfinite(at.u) || !std::isfinite(at.v)) return m.kd;  // a face without texture coordinates
  const float lod = texture_lod(*this, t, tex, footprint);
  return tex.sample_rgb(at, lod);
}

bool Scene::opaque(uint32_t t, Vec3 b) const {
  const Material& m = materials_[material_view_[t]];
  if (m.alpha_map < 0 || corner_uv_view_.empty()) return true;
  const Vec2 at = uv(t, b);
  if (!std::isfinite(at.u) || !std::isfinite(at.v)) return true;
  return textures_[static_cast<size_t>(m.alpha_map)].sample(at, 0) >= kCoverageCut;
}

bool Scene::opaque_everywhere(uint32_t t) const {
  const Material& m = materials_[material_view_[t]];
  if (m.alpha_map < 0 || corner_uv_view_.empty()) return true;
  const Texture& tex = textures_[static_cast<size_t>(m.alpha_map)];
  if (tex.width == 0 || tex.height == 0) return true;  // sample() reads 1 then
  // The texel coordinates bilinear() computes for every point of the triangle lie within the corners' box; its
  // lookups reach the texel below each coordinate and the next, and one more on each side covers rounding.
  const Vec2* c = &corner_uv_view_[3 * static_cast<size_t>(t)];
  const float w = static_cast<float>(tex.width), h = static_cast<float>(tex.height);
  float x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (int i = 0; i < 3; ++i) {
    const float x = c[i].u * w - 0.5f, y = (1.0f - c[i].v) * h - 0.5f;
    // Far-off coordinates are reduced by bilinear()'s fmod, which this box does not follow.
    if (!(std::abs(x) < 1000.0f * w) || !(std::abs(y) < 1000.0f * h)) return false;
    x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x), y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
  }
  const auto x0 = static_cast<int64_t>(std::floor(x_lo)) - 1, x1 = static_cast<int64_t>(std::floor(x_hi)) + 2;
  const auto y0 = static_cast<int64_t>(std::floor(y_lo)) - 1, y1 = static_cast<int64_t>(std::floor(y_hi)) + 2;
  if ((x1 - x0 + 1) * (y1 - y0 + 1) > 4096) return false;
  // A bilinear blend of values at or above the cut plus a margin cannot round below the cut.
  for (int64_t y = y0; y <= y1; ++y)
    for (int64_t x = x0; x <= x1; ++x)
      if (!(tex.texel(x, y, 0) >= kCoverageCut + 1e-3f)) return false;
  return true;
}

size_t Scene::put_opaque_first(std::vector<uint32_t>& triangles) const {
  const auto cut = std::stable_partition(triangles.begin(), triangles.end(), [&](uint32_t t) { return opaque_everywhere(t); });
  return static_cast<size_t>(cut - triangles.begin());
}

bool Scene::has_cutouts() const {
  if (corner_uv_view_.empty()) return false;
  return std::any_of(materials_.begin(), materials_.end(), [](const Material& m) { return m.alpha_map >= 0; });
}

float Scene::opaque_fraction(uint32_t t) const {
  const Material& m = materials_[material_view_[t]];
  if (m.alpha_map < 0 || corner_uv_view_.empty()) return 1.0f;
  // The centres of a 16 x 16 split of the triangle into 256 equal sub-triangles (both orientations).
  constexpr int kSplit = 16;
  int inside = 0;
  for (int i = 0; i < kSplit; ++i)
    for (int j = 0; i + j < kSplit; ++j) {
      const float b1 = (static_cast<float>(i) + 1.0f / 3) / kSplit, b2 = (static_cast<float>(j) + 1.0f / 3) / kSplit;
      inside += opaque(t, {1 - b1 - b2, b1, b2}) ? 1 : 0;
      if (i + j + 1 < kSplit) {
        const float c1 = (static_cast<float>(i) + 2.0f / 3) / kSplit, c2 = (static_cast<float>(j) + 2.0f / 3) / kSplit;
        inside += opaque(t, {1 - c1 - c2, c1, c2}) ? 1 : 0;
      }
    }
  return static_cast<float>(inside) / (kSplit * kSplit);
}

float Scene::emitted_power(uint32_t t) const {
  const Material& m = materials_[material_view_[t]];
  return area(t) * average(m.emission_map < 0 ? m.ke : mean_emission(m)) * kPi * opaque_fraction(t);
}

RGB Scene::mapped_emission(uint32_t t, Vec3 b) const {
  const Material& m = materials_[material_view_[t]];
  const Vec2 at = uv(t, b);
  if (!std::isfinite(at.u) || !std::isfinite(at.v)) return m.ke;
  const Texture& tex = textures_[static_cast<size_t>(m.emission_map)];
  return m.ke * tex.sample_rgb(at);
}

RGB Scene::mean_emission(const Material& m) const {
  if (m.emission_map < 0 || !has_uvs()) return m.ke;
  // The pyramid's last level is the image's mean (levels average in linear values).
  const Texture& tex = textures_[static_cast<size_t>(m.emission_map)];
  return m.ke * tex.sample_rgb({0.5f, 0.5f}, 64);
}

}  // namespace lf
