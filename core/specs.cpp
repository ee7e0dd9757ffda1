#include "core/specs.hpp"

#include <cmath>
#include <cstdio>
#include <string>

namespace lf {

bool is_material_change_list(const Value& v) {
  if (!v.is_array()) return false;
  for (const Value& change : v.as_array()) {
    const Value* name = change.find("name");
    if (!change.is_map() || !name || !name->is_string()) return false;
  }
  return true;
}

static Value vec3(const std::array<double, 3>& a) { return Value::Array{a[0], a[1], a[2]}; }

static std::string str(const Value& v, const char* key) {
  const Value* e = v.find(key);
  return e && e->is_string() ? e->as_string() : std::string();
}

Value SceneSpec::to_value() const {
  Value::Map m{{"builtin", builtin}, {"file", file}, {"lights", lights}};
  if (!materials.empty()) m["materials"] = materials;
  if (!shapes.empty()) m["shapes"] = shapes;
  if (!cache.empty()) {
    m["cache"] = cache;
    m["hash"] = hash;
  }
  return m;
}

SceneSpec SceneSpec::from_value(const Value& v) {
  SceneSpec s;
  s.builtin = str(v, "builtin");
  s.file = str(v, "file");
  s.cache = str(v, "cache");
  s.hash = str(v, "hash");
  if (const Value* l = v.find("lights"); l && l->is_array()) s.lights = l->as_array();
  if (const Value* m = v.find("materials"); m && m->is_array()) s.materials = m->as_array();
  if (const Value* g = v.find("shapes"); g && g->is_array()) s.shapes = g->as_array();
  return s;
}

CameraSpec CameraSpec::read(const ParamTable& p, const CameraSpec& defaults) {
  CameraSpec c = defaults;
  c.eye = p.get_vec3("eye", c.eye);
  c.at = p.get_vec3("at", c.at);
  c.up = p.get_vec3("up", c.up);
  c.fov = p.get_float("fov", c.fov, 0.1, 179.0);
  c.aperture = p.get_float("aperture", c.aperture, 0.0, 1e30);
  c.focus_distance = p.get_float("focus_distance", c.focus_distance, 0.0, 1e30);
  const double dx = c.at[0] - c.eye[0], dy = c.at[1] - c.eye[1], dz = c.at[2] - c.eye[2];
  if (dx * dx + dy * dy + dz * dz == 0) throw ParamError("camera: eye and at are the same point");
  const double cx = dy * c.up[2] - dz * c.up[1], cy = dz * c.up[0] - dx * c.up[2], cz = dx * c.up[1] - dy * c.up[0];
  if (cx * cx + cy * cy + cz * cz == 0) throw ParamError("camera: up is parallel to the viewing direction");
  if (p.has("focus")) {  // a point to keep sharp: its distance along the view
    if (p.has("focus_distance")) throw ParamError("camera: give focus or focus_distance, not both");
    const auto f = p.get_vec3("focus", c.at);
    const double vx = c.at[0] - c.eye[0], vy = c.at[1] - c.eye[1], vz = c.at[2] - c.eye[2];
    const double along = ((f[0] - c.eye[0]) * vx + (f[1] - c.eye[1]) * vy + (f[2] - c.eye[2]) * vz) /
                         std::sqrt(vx * vx + vy * vy + vz * vz);
    if (!(along > 0)) throw ParamError("camera: the focus point is not in front of the camera");
    c.focus_distance = along;
  }
  return c;
}

Value CameraSpec::to_value() const {
  Value::Map m{{"eye", vec3(eye)}, {"at", vec3(at)}, {"up", vec3(up)}, {"fov", fov}};
  if (aperture > 0) m["aperture"] = aperture;
  if (focus_distance > 0) m["focus_distance"] = focus_distance;
  return m;
}

// CONFIG's camera and image are read by the script's own readers: an actor takes nothing a script could not say.
template <class Spec>
static Result<Spec> read_back(const Value& v, const char* what) {
  if (!v.is_map()) return make_error(std::string("CONFIG '") + what + "' must be a map", ErrorCode::bad_request);
  try {
    ParamTable p(v.as_map(), what);
    Spec spec = Spec::read(p);
    p.report_unused();
    return spec;
  } catch (const ParamError& e) {
    return make_error(std::string("CONFIG: ") + e.what(), ErrorCode::bad_request);
  }
}

Result<CameraSpec> CameraSpec::from_value(const Value& v) { return read_back<CameraSpec>(v, "camera"); }

const std::vector<std::string>& ImageSpec::tonemaps() {
  static const std::vector<std::string> names{"clamp", "reinhard", "aces"};
  return names;
}

// A lit sample costs the network's whole work, a seen one a camera ray: 16 seen for each of the spp. Chosen by that
// cost, not against other ratios; on Lost Empire it did not show in the farm's time (docs/lua-api.md, "image").
int ImageSpec::default_edge_spp(int spp) { return std::max(spp, std::min(4096, 16 * spp)); }

// Adaptive sampling is on wherever it can be: a pixel's spread needs two lit samples, and a time-limited frame's
// passes take every pixel's next spp samples, which a second round would have taken already. Up to 16 x spp lit
// samples, as the outline's seen ones; the threshold (a share of display white) stops most pixels long before.
int ImageSpec::default_adaptive_spp(const ImageSpec& i) {
  if (i.shaded_per_pixel() < 2 || i.time_limit > 0) return 0;
  return std::max(i.shaded_per_pixel() + 1, std::min(4096, 16 * i.spp));
}

ImageSpec ImageSpec::read(const ParamTable& p) {
  ImageSpec i;
  i.width = static_cast<int>(p.get_int("width", i.width, 1, 16384));
  i.height = static_cast<int>(p.get_int("height", i.height, 1, 16384));
  i.spp = static_cast<int>(p.get_int("spp", i.spp, 1, 65536));
  i.shade_spp = static_cast<int>(p.get_int("shade_spp", i.spp, 1, i.spp));
  if (i.shade_spp == i.spp) i.shade_spp = 0;  // all of them: the plain pixel mean
  i.time_limit = p.get_float("time_limit", 0, 0, 1e7);
  // Read as a number first: 0 (off) is outside the range of counts it may otherwise be.
  const double asked = p.get_float("adaptive_spp", -1, -1e300, 1e300);  // -1: not given
  if (asked == 0) {
    i.adaptive_spp = 0;  // off
    if (p.has("adaptive_threshold"))
      throw ParamError("image: adaptive_threshold needs adaptive sampling, which adaptive_spp = 0 turns off");
  } else if (p.has("adaptive_spp")) {
    if (i.shaded_per_pixel() == 1)
      throw ParamError("image: adaptive_spp needs shade_spp (or spp) of at least 2 (a pixel's spread needs two samples)");
    if (i.time_limit > 0)
      throw ParamError("image: time_limit renders passes of spp samples while the time lasts; adaptive_spp, which "
                       "shades more of one pass's samples where they are noisy, cannot be combined with it");
    // Past spp the extra samples go on along each pixel's sequence, lit only.
    const int least = i.shaded_per_pixel() + 1;
    if (asked != std::floor(asked) || asked < least || asked > 65536) {
      char got[32];
      std::snprintf(got, sizeof got, "%.17g", asked);
      throw ParamError("image: parameter 'adaptive_spp' must be 0 (off) or an integer in [" + std::to_string(least) +
                       ", 65536], got " + got);
    }
    i.adaptive_spp = static_cast<int>(asked);
  } else {
    i.adaptive_spp = default_adaptive_spp(i);
    if (p.has("adaptive_threshold") && i.adaptive_spp == 0)
      throw ParamError(i.time_limit > 0
                           ? "image: adaptive_threshold needs adaptive sampling, which time_limit turns off"
                           : "image: adaptive_threshold needs adaptive sampling, which needs shade_spp (or spp) of at "
                             "least 2 (a pixel's spread needs two samples)");
  }
  if (p.has("adaptive_threshold"))
    i.adaptive_threshold = p.get_float("adaptive_threshold", i.adaptive_threshold, 1e-6, 1);
  i.edge_spp = static_cast<int>(p.get_int("edge_spp", default_edge_spp(i.spp), 0, 1 << 20));
  i.tile = static_cast<int>(p.get_int("tile", i.tile, 1, 1024));
  i.output = p.get_string("output", i.output);
  i.exposure = p.get_float("exposure", i.exposure, -20, 20);
  i.tonemap = p.get_string("tonemap", i.tonemap, tonemaps());
  i.sampler = p.get_string("sampler", i.sampler, {"independent", "sobol"});
  return i;
}

Value ImageSpec::to_value() const {
  Value::Map m{{"width", width},   {"height", height},     {"spp", spp},         {"tile", tile},
               {"output", output}, {"exposure", exposure}, {"tonemap", tonemap}, {"sampler", sampler}};
  if (shade_spp > 0) m["shade_spp"] = shade_spp;
  m["edge_spp"] = edge_spp;
  if (time_limit > 0) m["time_limit"] = time_limit;
  m["adaptive_spp"] = adaptive_spp;  // 0 too: read back, its absence would be the default
  if (adaptive_spp > 0) m["adaptive_threshold"] = adaptive_threshold;
  return m;
}

Result<ImageSpec> ImageSpec::from_value(const Value& v) { return read_back<ImageSpec>(v, "image"); }

}  // namespace lf
