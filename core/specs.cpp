#include "core/specs.hpp"

namespace lf {

static Value vec3(const std::array<double, 3>& a) { return Value::Array{a[0], a[1], a[2]}; }

static std::array<double, 3> vec3_of(const Value* v, std::array<double, 3> fallback) {
  if (!v || !v->is_array() || v->as_array().size() != 3) return fallback;
  const auto& a = v->as_array();
  for (const auto& e : a)
    if (!e.is_number()) return fallback;
  return {a[0].as_double(), a[1].as_double(), a[2].as_double()};
}

static double num(const Value& v, const char* key, double fallback) {
  const Value* e = v.find(key);
  return e && e->is_number() ? e->as_double() : fallback;
}

static std::string str(const Value& v, const char* key) {
  const Value* e = v.find(key);
  return e && e->is_string() ? e->as_string() : std::string();
}

Value SceneSpec::to_value() const {
  Value::Map m{{"builtin", builtin}, {"file", file}, {"lights", lights}};
  if (!materials.empty()) m["materials"] = materials;
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
  return s;
}

Value CameraSpec::to_value() const {
  return Value::Map{{"eye", vec3(eye)}, {"at", vec3(at)}, {"up", vec3(up)}, {"fov", fov}};
}

CameraSpec CameraSpec::from_value(const Value& v) {
  CameraSpec c;
  c.eye = vec3_of(v.find("eye"), c.eye);
  c.at = vec3_of(v.find("at"), c.at);
  c.up = vec3_of(v.find("up"), c.up);
  c.fov = num(v, "fov", c.fov);
  return c;
}

Value ImageSpec::to_value() const {
  return Value::Map{{"width", width}, {"height", height},   {"spp", spp}, {"shade_spp", shade_spp}, {"adaptive_spp", adaptive_spp},
                    {"adaptive_threshold", adaptive_threshold}, {"tile", tile},
                    {"output", output}, {"exposure", exposure}, {"tonemap", tonemap}, {"sampler", sampler}};
}

ImageSpec ImageSpec::from_value(const Value& v) {
  ImageSpec i;
  i.width = static_cast<int>(num(v, "width", i.width));
  i.height = static_cast<int>(num(v, "height", i.height));
  i.spp = static_cast<int>(num(v, "spp", i.spp));
  i.shade_spp = static_cast<int>(num(v, "shade_spp", 0));
  i.adaptive_spp = static_cast<int>(num(v, "adaptive_spp", 0));
  i.adaptive_threshold = num(v, "adaptive_threshold", i.adaptive_threshold);
  i.tile = static_cast<int>(num(v, "tile", i.tile));
  i.output = str(v, "output");
  i.exposure = num(v, "exposure", 0);
  if (const Value* t = v.find("tonemap"); t && t->is_string()) i.tonemap = t->as_string();
  if (const Value* s = v.find("sampler"); s && s->is_string()) i.sampler = s->as_string();
  return i;
}

}  // namespace lf
