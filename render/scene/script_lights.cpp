// The lights and shapes a farm script adds to a scene (light { quad | sphere | point }, environment { }, sun { },
// shape { plane | sphere }).
#include "render/scene/scene.hpp"

#include "render/images/image.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace lf {

static bool vec3_of(const Value* v, Vec3& out) {
  if (!v || !v->is_array() || v->as_array().size() != 3) return false;
  for (const auto& e : v->as_array())
    if (!e.is_number()) return false;
  const auto& a = v->as_array();
  out = {static_cast<float>(a[0].as_double()), static_cast<float>(a[1].as_double()), static_cast<float>(a[2].as_double())};
  return true;
}

static float number_or(const Value& table, const char* key, float fallback) {
  const Value* v = table.find(key);
  return v && v->is_number() ? static_cast<float>(v->as_double()) : fallback;
}

// environment { map | radiance, intensity, rotation (degrees), camera } as farm/spec_readers.cpp checked it; the map
// is read here, once, and travels in the shipped scene from then on.
static Result<Environment> script_environment(const Value& e) {
  Environment env;
  if (const Value* map = e.find("map"); map && map->is_string()) {
    auto image = read_image(map->as_string());
    if (!image) return make_error("environment map '" + map->as_string() + "': " + image.error().message);
    if (image->width < 2 || image->height < 1 || image->width > 32768 || image->height > 16384)
      return make_error("environment map '" + map->as_string() + "': " + std::to_string(image->width) + "x" +
                        std::to_string(image->height) + " is not an equirectangular map's size (2x1 to 32768x16384)");
    env = Environment(image->width, image->height, std::move(image->pixels), number_or(e, "intensity", 1),
                      number_or(e, "rotation", 0) * kPi / 180);
  } else {
    RGB radiance;
    if (!vec3_of(e.find("radiance"), radiance)) return make_error("environment needs map = \"file\" or radiance = {r, g, b}");
    env = Environment(radiance * number_or(e, "intensity", 1));
  }
  if (const Value* c = e.find("camera"); c && c->is_bool()) env.set_camera_visible(c->as_bool());
  return env;
}

// A sun as sun { } gives it (farm/spec_readers.hpp, read_sun): towards it, its irradiance, its angle in degrees.
static Result<Sun> sun_of(const Value& sv) {
  Sun made;
  if (!vec3_of(sv.find("direction"), made.direction) || !(length(made.direction) > 0))
    return make_error("sun needs a direction {x, y, z} (towards the sun) that is not 0");
  if (!vec3_of(sv.find("irradiance"), made.irradiance)) return make_error("sun needs irradiance = {r, g, b}");
  const float degrees = number_or(sv, "angle", made.angle * 180 / kPi);
  if (!(degrees > 0 && degrees < 90)) return make_error("sun: angle must be above 0 and below 90 degrees");
  made.angle = degrees * kPi / 180;
  return made;
}

Status Scene::add_script_lights(const Value::Array& lights) {
  std::optional<Environment> environment;
  std::optional<Sun> sun;
  for (size_t i = 0; i < lights.size(); ++i) {
    const Value& l = lights[i];
    if (const Value* e = l.find("environment")) {
      if (environment) return make_error("environment is declared twice");
      auto env = script_environment(*e);
      if (!env) return env.error();
      environment = std::move(*env);
      continue;
    }
    if (const Value* sv = l.find("sun")) {
      if (sun) return make_error("sun is declared twice");
      auto made = sun_of(*sv);
      if (!made) return made.error();
      sun = *made;
      continue;
    }
    const std::string which = "light " + std::to_string(i + 1);
    // Where the script said it ("farm.lua:12"), for diagnostics about what it lights (light_checks.hpp).
    const Value* at = l.find("at");
    const Value* given = l.find("name");  // what a job's frames change it by (frames { materials })
    const std::string material_name = given && given->is_string() ? given->as_string()
                                      : at && at->is_string()     ? "light at " + at->as_string()
                                                                  : "light (script)";
    Vec3 colour;
    if (const Value* q = l.find("quad")) {
      if (!vec3_of(l.find("radiance"), colour)) return make_error(which + ": radiance must be {r, g, b}");
      Vec3 c[4];
      if (!q->is_array() || q->as_array().size() != 4) return make_error(which + ": quad needs 4 corners");
      for (int k = 0; k < 4; ++k)
        if (!vec3_of(&q->as_array()[static_cast<size_t>(k)], c[k])) return make_error(which + ": a corner is not {x, y, z}");
      // Two triangles of a bent quad would emit in two directions: refuse it rather than light something else.
      const Vec3 n = normalize(cross(c[1] - c[0], c[2] - c[0]));
      const float size = std::max(length(c[2] - c[0]), length(c[3] - c[1]));
      const float off = std::abs(dot(c[3] - c[0], n));
      if (!(size > 0)) return make_error(which + ": the quad has no area");
      if (!(off <= 1e-4f * size))
        return make_error(which + ": the quad is not planar (its 4th corner is " + std::to_string(off) +
                          " off the plane of the first three)");
      add_quad(c[0], c[1], c[2], c[3], add_material({material_name, {}, colour}));
    } else if (const Value* sph = l.find("sphere")) {
      Vec3 centre;
      const Value* r = l.find("radius");
      if (!vec3_of(sph, centre) || !r || !r->is_number() || !(r->as_double() > 0))
        return make_error(which + ": sphere needs a centre {x, y, z} and a radius > 0");
      if (!vec3_of(l.find("radiance"), colour)) return make_error(which + ": radiance must be {r, g, b}");
      add_sphere(centre, static_cast<float>(r->as_double()), 3, add_material({material_name, {}, colour}));
    } else if (const Value* p = l.find("point")) {
      Vec3 at;
      if (!vec3_of(p, at)) return make_error(which + ": point must be {x, y, z}");
      if (!vec3_of(l.find("intensity"), colour)) return make_error(which + ": intensity must be {r, g, b}");
      add_point_light(at, colour);
    } else {
      return make_error(which + ": give quad, sphere or point");
    }
  }
  if (environment || sun) {
    // What the script gives replaces the scene file's own (a glTF's sun), part by part.
    if (!sun && environment_ && environment_->sun()) sun = *environment_->sun();
    if (!environment) environment = environment_ ? *environment_ : Environment();
    if (sun) environment->set_sun(*sun);
    set_environment(std::move(*environment));
  }
  return Ok{};
}

// The scene's extent before the script's shapes: a ground plane's default size follows it.
static float scene_diagonal(const Scene& s, size_t triangles) {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t t = 0; t < triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3 v = s.vertex(t, k);
      lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
      hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
    }
  return triangles > 0 ? length(hi - lo) : 0.0f;
}

Status Scene::add_script_shapes(const Value::Array& shapes) {
  // Measured once, and only for a plane that needs it: every scene load passes here, most with no shapes.
  std::optional<float> diagonal;
  const size_t scene_triangles = triangle_count();
  for (const Value& shape : shapes) {
    const Value* name = shape.find("name");
    if (!name || !name->is_string()) return make_error("a shape has no name");
    const std::string which = "shape '" + name->as_string() + "'";
    uint32_t material = 0;
    if (const Value* m = shape.find("material"); m && m->is_string()) {
      bool found = false;
      for (uint32_t i = 0; i < materials_.size() && !found; ++i)
        if (materials_[i].name == m->as_string()) material = i, found = true;
      if (!found) return make_error(which + ": material '" + m->as_string() + "' is not in the scene");
    } else {
      material = add_material({name->as_string(), {0.5f, 0.5f, 0.5f}, {}});
    }
    Vec3 at;
    if (const Value* p = shape.find("plane")) {
      Vec3 n{0, 1, 0};
      if (!vec3_of(p, at) || (shape.find("normal") && !vec3_of(shape.find("normal"), n)) || !(length(n) > 0))
        return make_error(which + ": plane needs a point {x, y, z} and a normal {x, y, z} that is not 0");
      n = normalize(n);
      const Value* size = shape.find("size");
      // A ground for what the scene holds: ten times its extent, so its edge is far outside any view of it.
      if (!(size && size->is_number()) && !diagonal) diagonal = scene_diagonal(*this, scene_triangles);
      const float side = size && size->is_number() ? static_cast<float>(size->as_double()) : 10 * *diagonal;
      if (!(side > 0)) return make_error(which + ": plane needs a size > 0 (the scene is empty, so give one)");
      const Vec3 u = normalize(cross(n, std::abs(n.y) < 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0})), v = cross(n, u);
      const float h = side / 2;
      // Counter-clockwise around n, so that it faces n (it would emit that way).
      add_quad(at - u * h - v * h, at + u * h - v * h, at + u * h + v * h, at - u * h + v * h, material);
    } else if (const Value* c = shape.find("sphere")) {
      const Value* r = shape.find("radius");
      if (!vec3_of(c, at) || !r || !r->is_number() || !(r->as_double() > 0))
        return make_error(which + ": sphere needs a centre {x, y, z} and a radius > 0");
      add_sphere(at, static_cast<float>(r->as_double()), 4, material, /*smooth=*/true);
    } else {
      return make_error(which + ": give plane or sphere");
    }
  }
  return Ok{};
}

Status Scene::apply_material_overrides(const Value::Array& overrides) { return change_materials(materials_, overrides); }

// A frame's environment as read_frame_environment gives it: a map's intensity and rotation (degrees), each
// defaulting to the declared environment's, or a constant environment's radiance times its intensity.
static Status environment_change(const Environment& declared, const Value& change, Environment* out) {
  RGB radiance;
  const bool constant = change.find("radiance") != nullptr;
  if (declared.has_map() == constant)
    return make_error(declared.has_map() ? "the environment is a map: a frame changes its intensity and rotation, not its radiance"
                                         : "the environment is one radiance: a frame gives its radiance (and intensity), it has no map to rotate");
  if (constant && !vec3_of(change.find("radiance"), radiance)) return make_error("environment: radiance must be {r, g, b}");
  if (!out) return Ok{};
  if (constant) {
    out->set_constant(radiance * number_or(change, "intensity", 1));
  } else {
    // Degrees to radians as script_environment converts them, so the frame equals a farm that declares it.
    const float rotation = change.find("rotation") ? number_or(change, "rotation", 0) * kPi / 180 : declared.rotation();
    out->set_map_look(number_or(change, "intensity", declared.intensity()), rotation);
  }
  return Ok{};
}

// A frame's point light as job_functions reads it: {index, of, point?, intensity?}, the index-th of the script's `of`
// point lights, which are the scene's last (the scene file's own come before them). Checked: where it is among
// `lights`, and the light as the change leaves it.
static Result<std::pair<size_t, PointLight>> point_light_change(const std::vector<PointLight>& lights,
                                                                const Value& change, const std::string& name) {
  // A count as a packet may carry it: a whole number (not NaN, not 0.5), else -1.
  auto whole = [](const Value* v) {
    const double x = v && v->is_number() ? v->as_double() : -1;
    return x >= 0 && x <= 1e9 && std::floor(x) == x ? static_cast<int64_t>(x) : int64_t{-1};
  };
  const int64_t index = whole(change.find("index")), of = whole(change.find("of"));
  if (index < 0 || index >= of || of > static_cast<int64_t>(lights.size()))
    return make_error("point light '" + name + "' is not among the scene's point lights");
  const size_t at = lights.size() - static_cast<size_t>(of) + static_cast<size_t>(index);
  PointLight light = lights[at];
  if (change.find("point") && !vec3_of(change.find("point"), light.position))
    return make_error("point light '" + name + "': point must be {x, y, z}");
  if (change.find("intensity") && !vec3_of(change.find("intensity"), light.intensity))
    return make_error("point light '" + name + "': intensity must be {r, g, b}");
  return std::pair{at, light};
}

Status Scene::check_light_changes(const Value::Array& changes) const {
  for (const Value& c : changes) {
    if (const Value* lv = c.find("light")) {
      const Value* name = c.find("name");
      if (auto made = point_light_change(point_lights_, *lv, name && name->is_string() ? name->as_string() : "?"); !made)
        return made.error();
      continue;
    }
    const Value* sv = c.find("sun");
    const Value* ev = c.find("environment");
    if (sv && (!environment_ || !environment_->sun()))
      return make_error("the sun changes, but the scene has none (declare its first state with sun { })");
    if (ev && !environment_)
      return make_error("the environment changes, but the scene has none (declare its first state with environment { })");
    if (sv)
      if (auto made = sun_of(*sv); !made) return made.error();
    if (ev)
      if (auto st = environment_change(*environment_, *ev, nullptr); !st) return st;
  }
  return Ok{};
}

Status Scene::apply_light_changes(const Value::Array& changes) {
  if (auto st = check_light_changes(changes); !st) return st;
  std::optional<Environment> sky;  // one copy for all of a frame's changes: the map and its distribution as they are
  for (const Value& c : changes) {
    if (const Value* lv = c.find("light")) {
      const auto made = point_light_change(point_lights_, *lv, "");  // checked above
      point_lights_[made->first] = made->second;
      continue;
    }
    const Value* sv = c.find("sun");
    const Value* ev = c.find("environment");
    if (!sv && !ev) continue;
    if (!sky) sky = *environment_;
    if (sv) sky->set_sun(*sun_of(*sv));
    if (ev) environment_change(*environment_, *ev, &*sky);
  }
  if (sky) set_environment(std::move(*sky));
  return Ok{};
}

Status Scene::change_materials(std::vector<Material>& materials, const Value::Array& overrides) {
  for (const Value& o : overrides) {
    if (o.find("sun") || o.find("environment") || o.find("light")) continue;  // a frame's lights (apply_light_changes)
    const Value* name = o.find("name");
    if (!name || !name->is_string()) return make_error("a material change names no material");
    Material* m = nullptr;
    for (auto& candidate : materials)
      if (candidate.name == name->as_string()) m = &candidate;
    if (!m) return make_error("material '" + name->as_string() + "' is not in the scene");
    const std::string which = "material '" + m->name + "'";
    // A colour the change gives, into `field`; false when it gives one that is not {r, g, b}.
    auto colour = [&](const char* key, RGB& field) {
      const Value* v = o.find(key);
      return !v || vec3_of(v, field);
    };
    for (auto [key, field] : {std::pair<const char*, RGB*>{"emission", &m->ke}, {"ks", &m->ks}, {"mirror", &m->kr},
                              {"tf", &m->tf}})
      if (!colour(key, *field)) return make_error(which + ": " + key + " must be {r, g, b}");
    if (o.find("kd")) {
      if (!colour("kd", m->kd)) return make_error(which + ": kd must be {r, g, b}");
      m->kd_map = -1;  // a flat colour from the script replaces the texture too
    }
    if (const Value* v = o.find("ns"); v && v->is_number()) m->ns = static_cast<float>(v->as_double());
    if (const Value* v = o.find("ior"); v && v->is_number()) m->ior = static_cast<float>(v->as_double());
    if (const Value* v = o.find("type"); v && v->is_string()) {
      const std::string& t = v->as_string();
      if (t == "diffuse") m->type = Material::Type::diffuse;
      else if (t == "glossy") m->type = Material::Type::glossy;
      else if (t == "mirror") m->type = Material::Type::mirror;
      else if (t == "glass") m->type = Material::Type::glass;
      else if (t == "metal_rough") m->type = Material::Type::metal_rough;
      else return make_error(which + ": unknown type '" + t + "'");
    }
    // The microfacet model's parameters make a material metal_rough where no type is given; its base colour is kd
    // (the material's own colour and texture unless base_color replaces them).
    const bool microfacet_params =
        o.find("metallic") || o.find("roughness") || o.find("base_color") || o.find("transmission");
    if (microfacet_params) {
      if (o.find("type") && m->type != Material::Type::metal_rough)
        return make_error(which + ": metallic, roughness, base_color and transmission belong to type \"metal_rough\"");
      m->type = Material::Type::metal_rough;
    }
    if (m->type == Material::Type::metal_rough) {
      if (o.find("ks") || o.find("ns") || o.find("mirror") || o.find("kd"))
        return make_error(which + ": a metal_rough material takes base_color, metallic and roughness, not kd, ks, ns "
                                  "or mirror");
      if (o.find("base_color")) {
        if (!colour("base_color", m->kd)) return make_error(which + ": base_color must be {r, g, b}");
        m->kd_map = -1;
      }
      for (auto [key, field] : {std::pair<const char*, float*>{"metallic", &m->metallic}, {"roughness", &m->roughness},
                                {"transmission", &m->transmission}})
        if (const Value* v = o.find(key); v && v->is_number()) {
          const double x = v->as_double();
          if (!(x >= 0 && x <= 1)) return make_error(which + ": " + key + " must be between 0 and 1");
          *field = static_cast<float>(x);
        }
      m->ks = {};  // the lobes of the model it replaces
      m->kr = {};
      m->ns = 0;
    }
    if (m->specular()) m->kr = {};  // a mirror's reflectance is ks, and glass has none beside its Fresnel
    const RGB sum = m->kd + m->ks + m->kr;
    if (m->type != Material::Type::glass && std::max({sum.x, sum.y, sum.z}) > 1.0f + 1e-6f)
      return make_error(which + ": kd + ks + mirror exceeds 1 in some channel, so the surface would create energy");
  }
  return Ok{};
}

}  // namespace lf
