#include "render/lights/environment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/byte_io.hpp"
#include "render/shading/bsdf.hpp"

namespace lf {

namespace {

constexpr double kPiD = 3.14159265358979323846;

// Where a cdf of n entries first exceeds k / g, for k = 0..g: the bounds a guided search starts from.
void guide(const float* cdf, size_t n, size_t g, uint32_t* out) {
  for (size_t k = 0; k <= g; ++k)
    out[k] = static_cast<uint32_t>(std::upper_bound(cdf, cdf + n, static_cast<float>(k) / static_cast<float>(g)) - cdf);
}

// The index i with cdf[i - 1] <= u < cdf[i] (cdf[-1] = 0), and where u falls within it, rescaled to [0, 1). By
// its guide table (guide() over g bins) the search runs between the bounds of u's bin, and over the whole cdf only
// where rounding put u outside them: the same i either way.
size_t pick(const float* cdf, size_t n, float u, float& remainder, const uint32_t* bounds, size_t g) {
  const size_t k = std::min(static_cast<size_t>(u * static_cast<float>(g)), g - 1);
  const size_t lo = bounds[k], hi = std::min<size_t>(bounds[k + 1] + 1, n);
  size_t found = static_cast<size_t>(std::upper_bound(cdf + lo, cdf + hi, u) - cdf);
  if ((lo > 0 && cdf[lo - 1] > u) || (found == hi && hi < n))
    found = static_cast<size_t>(std::upper_bound(cdf, cdf + n, u) - cdf);
  const size_t i = std::min(found, n - 1);
  const float low = i > 0 ? cdf[i - 1] : 0.0f, width = cdf[i] - low;
  remainder = width > 0 ? std::clamp((u - low) / width, 0.0f, 0x1.fffffep-1f) : 0.5f;
  return i;
}

// Turns a distribution's weights into its cdf and pdf (uniform where every weight is 0: never drawn from then).
double tabulate(const double* weights, size_t n, float* cdf, float* pdf) {
  double total = 0;
  for (size_t i = 0; i < n; ++i) total += weights[i];
  double running = 0;
  for (size_t i = 0; i < n; ++i) {
    running += weights[i];
    const double share = total > 0 ? weights[i] / total : 1.0 / static_cast<double>(n);
    cdf[i] = static_cast<float>(total > 0 ? running / total : static_cast<double>(i + 1) / static_cast<double>(n));
    pdf[i] = static_cast<float>(share);
  }
  cdf[n - 1] = 1.0f;
  return total;
}

RGB non_negative(RGB c) {
  return {std::isfinite(c.x) ? std::max(c.x, 0.0f) : 0.0f, std::isfinite(c.y) ? std::max(c.y, 0.0f) : 0.0f,
          std::isfinite(c.z) ? std::max(c.z, 0.0f) : 0.0f};
}

}  // namespace

Environment::Environment(RGB radiance) : constant_(non_negative(radiance)) { build(); }

Environment::Environment(int width, int height, std::vector<RGB> pixels, float intensity, float rotation)
    : width_(width), height_(height), pixels_(std::move(pixels)), intensity_(intensity), rotation_(rotation) {
  for (RGB& p : pixels_) p = non_negative(p);
  build();
}

void Environment::set_sun(const Sun& sun) {
  sun_ = sun;
  sun_->direction = normalize(sun.direction);
  sun_->irradiance = non_negative(sun.irradiance);
  build_sun();  // the map's distribution does not depend on the sun
}

Vec3 Environment::direction_of(float u, float v) {
  const float theta = kPi * v, phi = 2.0f * kPi * (u - 0.5f);
  const float s = std::sin(theta);
  return {s * std::cos(phi), std::cos(theta), s * std::sin(phi)};
}

void Environment::image_coordinates(Vec3 wi, float& u, float& v) {
  v = std::acos(std::clamp(wi.y, -1.0f, 1.0f)) / kPi;
  u = std::atan2(wi.z, wi.x) / (2.0f * kPi) + 0.5f;
}

Vec3 Environment::to_map(Vec3 wi) const {
  return {cos_rot_ * wi.x - sin_rot_ * wi.z, wi.y, sin_rot_ * wi.x + cos_rot_ * wi.z};
}
Vec3 Environment::from_map(Vec3 d) const {
  return {cos_rot_ * d.x + sin_rot_ * d.z, d.y, -sin_rot_ * d.x + cos_rot_ * d.z};
}

void Environment::build() {
  map_weight_total_ = 0;
  if (has_map()) {
    // Each texel's weight is the integral of radiance()'s bilinear interpolation over it (9/16 of the texel, 3/32
    // of each side neighbour, 1/64 of each corner one), times sin(theta) at its centre: the texels of a row near a
    // pole cover less of the sphere. So the density is positive wherever the interpolated radiance is.
    const size_t w = static_cast<size_t>(width_), h = static_cast<size_t>(height_);
    row_cdf_.assign(h, 0);
    row_pdf_.assign(h, 0);
    col_cdf_.assign(w * h, 0);
    col_pdf_.assign(w * h, 0);
    std::vector<double> weights(w), row_weights(h);
    auto brightness = [&](size_t x, long y) {
      const size_t row = static_cast<size_t>(std::clamp<long>(y, 0, static_cast<long>(h) - 1));
      return static_cast<double>(average(pixels_[row * w + x % w]));
    };
    for (size_t y = 0; y < h; ++y) {
      const double sin_theta = std::sin(kPiD * (static_cast<double>(y) + 0.5) / static_cast<double>(h));
      const long yl = static_cast<long>(y);
      for (size_t x = 0; x < w; ++x) {
        const size_t left = x + w - 1, right = x + 1;
        const double sides = brightness(left, yl) + brightness(right, yl) + brightness(x, yl - 1) + brightness(x, yl + 1);
        const double corners = brightness(left, yl - 1) + brightness(right, yl - 1) + brightness(left, yl + 1) +
                               brightness(right, yl + 1);
        weights[x] = (brightness(x, yl) * 9.0 / 16 + sides * 3.0 / 32 + corners / 64.0) * sin_theta;
      }
      row_weights[y] = tabulate(weights.data(), w, &col_cdf_[y * w], &col_pdf_[y * w]);
    }
    map_weight_total_ = tabulate(row_weights.data(), h, row_cdf_.data(), row_pdf_.data());
    row_guide_.assign(kGuide + 1, 0);
    guide(row_cdf_.data(), h, kGuide, row_guide_.data());
    col_guide_.assign(h * (kGuide + 1), 0);
    for (size_t y = 0; y < h; ++y) guide(&col_cdf_[y * w], w, kGuide, &col_guide_[y * (kGuide + 1)]);
  }
  build_power();
}

void Environment::build_power() {
  cos_rot_ = std::cos(rotation_);
  sin_rot_ = std::sin(rotation_);
  // The integral of brightness over the sphere: each texel spans (2 pi / w) (pi / h) sin(theta) steradians.
  map_power_ = has_map() ? map_weight_total_ * intensity_ * (2 * kPiD / static_cast<double>(width_)) *
                               (kPiD / static_cast<double>(height_))
                         : average(constant_) * 4 * kPiD;
  build_sun();
}

void Environment::set_map_look(float intensity, float rotation) {
  intensity_ = intensity;
  rotation_ = rotation;
  build_power();
}

void Environment::set_constant(RGB radiance) {
  constant_ = non_negative(radiance);
  build_power();
}

void Environment::build_sun() {
  sun_power_ = 0;
  sun_share_ = 0;
  if (sun_) {
    const double half = std::clamp(static_cast<double>(sun_->angle) / 2, 1e-6, kPiD / 2);
    const double one_minus_cos = 2 * std::sin(half / 2) * std::sin(half / 2);
    sun_one_minus_cos_ = static_cast<float>(one_minus_cos);
    sun_sin2_ = static_cast<float>(std::sin(half) * std::sin(half));
    // A disc of radiance L and half angle a gives pi L sin^2(a) on a surface facing it.
    sun_radiance_scale_ = static_cast<float>(1.0 / (kPiD * std::sin(half) * std::sin(half)));
    sun_power_ = average(sun_->irradiance) * sun_radiance_scale_ * 2 * kPiD * one_minus_cos;
    basis(sun_->direction, sun_u_, sun_v_);
    // Both parts keep some samples, so neither's directions rely on the other's density alone.
    if (sun_power_ > 0)
      sun_share_ = map_power_ > 0 ? std::clamp(static_cast<float>(sun_power_ / (sun_power_ + map_power_)), 0.1f, 0.9f)
                                  : 1.0f;
  }
}

RGB Environment::sun_radiance(Vec3 wi) const { return in_sun(wi) ? sun_->irradiance * sun_radiance_scale_ : RGB{}; }

float Environment::sun_pdf(Vec3 wi) const {
  return sun_share_ > 0 && in_sun(wi) ? sun_share_ / (2.0f * kPi * sun_one_minus_cos_) : 0.0f;
}

bool Environment::in_sun(Vec3 wi) const {
  if (!sun_) return false;
  // The cross product's length is the angle's sine, precise for the small angles a sun has (a cosine near 1 is not).
  const Vec3 c = cross(wi, sun_->direction);
  return dot(wi, sun_->direction) > 0 && dot(c, c) <= sun_sin2_;
}

RGB Environment::map_radiance(Vec3 wi) const {
  if (!has_map()) return constant_;
  float u, v;
  image_coordinates(to_map(wi), u, v);
  return map_radiance_at(u, v);
}

RGB Environment::map_radiance_at(float u, float v) const {
  // Bilinear between texel centres, around the azimuth and clamped at the poles (as Cycles' linear lookup is).
  const float fx = u * static_cast<float>(width_) - 0.5f, fy = v * static_cast<float>(height_) - 0.5f;
  const float x0f = std::floor(fx), y0f = std::floor(fy);
  const float tx = fx - x0f, ty = fy - y0f;
  const int x0 = (static_cast<int>(x0f) % width_ + width_) % width_, x1 = (x0 + 1) % width_;
  const int y0 = std::clamp(static_cast<int>(y0f), 0, height_ - 1), y1 = std::clamp(static_cast<int>(y0f) + 1, 0, height_ - 1);
  auto at = [&](int x, int y) { return pixels_[texel(x, y)]; };
  const RGB top = at(x0, y0) * (1 - tx) + at(x1, y0) * tx, bottom = at(x0, y1) * (1 - tx) + at(x1, y1) * tx;
  return (top * (1 - ty) + bottom * ty) * intensity_;
}

double Environment::texel_probability(int x, int y) const {
  if (!has_map() || x < 0 || y < 0 || x >= width_ || y >= height_) return 0;
  return static_cast<double>(row_pdf_[static_cast<size_t>(y)]) * col_pdf_[texel(x, y)];
}

RGB Environment::radiance(Vec3 wi) const { return map_radiance(wi) + sun_radiance(wi); }

float Environment::map_pdf(Vec3 wi) const {
  if (map_power_ <= 0) return 0;
  if (!has_map()) return 1.0f / (4.0f * kPi);
  const Vec3 d = to_map(wi);
  float u, v;
  image_coordinates(d, u, v);
  const int x = std::clamp(static_cast<int>(u * static_cast<float>(width_)), 0, width_ - 1);
  const int y = std::clamp(static_cast<int>(v * static_cast<float>(height_)), 0, height_ - 1);
  return map_pdf_at(x, y, d.y);
}

float Environment::map_pdf_at(int x, int y, float pole_cosine) const {
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - pole_cosine * pole_cosine));
  if (!(sin_theta > 0)) return 0;
  const float p = row_pdf_[static_cast<size_t>(y)] * col_pdf_[texel(x, y)];
  return p * static_cast<float>(width_) * static_cast<float>(height_) / (2.0f * kPi * kPi * sin_theta);
}

float Environment::pdf(Vec3 wi) const { return (1.0f - sun_share_) * map_pdf(wi) + sun_pdf(wi); }

Environment::Sample Environment::sample(float u, float v) const {
  Vec3 wi;
  if (u < sun_share_) {
    // Uniform over the sun's cone.
    const float r = std::min(u / sun_share_, 0x1.fffffep-1f);
    const float cos_t = 1.0f - r * sun_one_minus_cos_;
    const float sin_t = std::sqrt(std::max(0.0f, r * sun_one_minus_cos_ * (1.0f + cos_t)));
    const float phi = 2.0f * kPi * v;
    wi = normalize(sun_u_ * (sin_t * std::cos(phi)) + sun_v_ * (sin_t * std::sin(phi)) + sun_->direction * cos_t);
  } else {
    const float r = sun_share_ > 0 ? std::min((u - sun_share_) / (1.0f - sun_share_), 0x1.fffffep-1f) : u;
    if (!has_map()) {  // uniform over the sphere
      const float z = 1.0f - 2.0f * r, s = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = 2.0f * kPi * v;
      wi = {s * std::cos(phi), z, s * std::sin(phi)};
    } else {
      float du, dv;
      const size_t y = pick(row_cdf_.data(), row_cdf_.size(), r, du, row_guide_.data(), kGuide);
      const size_t x = pick(&col_cdf_[y * static_cast<size_t>(width_)], static_cast<size_t>(width_), v, dv,
                            &col_guide_[y * (kGuide + 1)], kGuide);
      const float mu = (static_cast<float>(x) + dv) / static_cast<float>(width_);
      const float mv = (static_cast<float>(y) + du) / static_cast<float>(height_);
      const Vec3 d = direction_of(mu, mv);
      wi = from_map(d);
      // The point's radiance and density from where it was drawn in the image; the sun's part added if it lies in
      // the sun's disc (then the sun could have drawn it too).
      const float map_p = map_power_ > 0 ? map_pdf_at(static_cast<int>(x), static_cast<int>(y), d.y) : 0.0f;
      return Sample{wi, map_radiance_at(mu, mv) + sun_radiance(wi), (1.0f - sun_share_) * map_p + sun_pdf(wi)};
    }
  }
  // Radiance and density of the direction itself, whichever part drew it: a direction in the sun's disc could have
  // come from the map too.
  return Sample{wi, radiance(wi), pdf(wi)};
}

void Environment::write(std::string& out) const {
  out += "LFENV1";
  bytes::put<uint8_t>(out, has_map() ? 1 : 0);
  if (has_map()) {
    bytes::put<uint32_t>(out, static_cast<uint32_t>(width_));
    bytes::put<uint32_t>(out, static_cast<uint32_t>(height_));
    bytes::put(out, intensity_);
    bytes::put(out, rotation_);
    out.append(reinterpret_cast<const char*>(pixels_.data()), pixels_.size() * sizeof(RGB));
  } else {
    bytes::put_rgb(out, constant_);
  }
  bytes::put<uint8_t>(out, camera_visible_ ? 1 : 0);
  bytes::put<uint8_t>(out, sun_ ? 1 : 0);
  if (sun_) {
    bytes::put_rgb(out, sun_->direction);
    bytes::put(out, sun_->angle);
    bytes::put_rgb(out, sun_->irradiance);
  }
}

Result<Environment> Environment::read(std::string_view in) {
  auto bad = [](const char* what) { return make_error(std::string("environment: ") + what); };
  if (in.substr(0, 6) != "LFENV1") return bad("not an environment's binary form");
  bytes::Reader r(in.substr(6));
  uint8_t has_map = 0, visible = 1, has_sun = 0;
  if (!r.u8(has_map)) return bad("cut short");
  Environment env;
  if (has_map) {
    uint32_t w = 0, h = 0;
    float intensity = 1, rotation = 0;
    if (!r.u32(w) || !r.u32(h) || !r.f32(intensity) || !r.f32(rotation)) return bad("cut short");
    if (w == 0 || h == 0 || w > (1u << 16) || h > (1u << 16) || !r.room(uint64_t{w} * h, sizeof(RGB)))
      return bad("its map's size does not match its data");
    std::vector<RGB> pixels(uint64_t{w} * h);
    for (RGB& p : pixels)
      if (!r.vec(p)) return bad("cut short");
    env = Environment(static_cast<int>(w), static_cast<int>(h), std::move(pixels), intensity, rotation);
  } else {
    RGB c;
    if (!r.vec(c)) return bad("cut short");
    env = Environment(c);
  }
  if (!r.u8(visible) || !r.u8(has_sun)) return bad("cut short");
  env.set_camera_visible(visible != 0);
  if (has_sun) {
    Sun s;
    if (!r.vec(s.direction) || !r.f32(s.angle) || !r.vec(s.irradiance)) return bad("cut short");
    if (!(std::fabs(length(s.direction) - 1) <= 1e-5f) || !(s.angle > 0) || !(s.angle < kPi))
      return bad("its sun is malformed");
    // Written as set_sun made it: kept as it is, so that a shipped scene's sun is the director's bit for bit (set_sun
    // would normalize the direction again, which can move it by an ulp, and a job's frame moves the sun by set_sun).
    s.irradiance = non_negative(s.irradiance);
    env.sun_ = s;
    env.build_sun();
  }
  if (!r.done()) return bad("has bytes after its end");
  return env;
}

std::string Environment::describe() const {
  char buf[256];
  std::string out;
  if (has_map())
    std::snprintf(buf, sizeof buf, "environment map %dx%d, intensity %g, rotation %g deg", width_, height_, intensity_,
                  rotation_ * 180.0 / kPiD);
  else
    std::snprintf(buf, sizeof buf, "environment radiance (%g, %g, %g)", constant_.x, constant_.y, constant_.z);
  out = buf;
  if (!camera_visible_) out += ", hidden from the camera";
  if (sun_) {
    std::snprintf(buf, sizeof buf, "; sun towards (%.3g, %.3g, %.3g), %.3g deg across, irradiance (%g, %g, %g)",
                  sun_->direction.x, sun_->direction.y, sun_->direction.z, sun_->angle * 180.0 / kPiD,
                  sun_->irradiance.x, sun_->irradiance.y, sun_->irradiance.z);
    out += buf;
  }
  return out;
}

}  // namespace lf
