// The lights a farm script adds to a scene (light { quad | sphere | point }).
#include "render/scene/scene.hpp"

#include <algorithm>
#include <cmath>

namespace lf {

static bool vec3_of(const Value* v, Vec3& out) {
  if (!v || !v->is_array() || v->as_array().size() != 3) return false;
  for (const auto& e : v->as_array())
    if (!e.is_number()) return false;
  const auto& a = v->as_array();
  out = {static_cast<float>(a[0].as_double()), static_cast<float>(a[1].as_double()), static_cast<float>(a[2].as_double())};
  return true;
}

Status Scene::add_script_lights(const Value::Array& lights) {
  for (size_t i = 0; i < lights.size(); ++i) {
    const Value& l = lights[i];
    const std::string which = "light " + std::to_string(i + 1);
    // Where the script said it ("farm.lua:12"), for diagnostics about what it lights (light_checks.hpp).
    const Value* at = l.find("at");
    const std::string material_name = at && at->is_string() ? "light at " + at->as_string() : "light (script)";
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
  return Ok{};
}

Status Scene::apply_material_overrides(const Value::Array& overrides) {
  for (const Value& o : overrides) {
    const Value* name = o.find("name");
    if (!name || !name->is_string()) return make_error("a material change names no material");
    Material* m = nullptr;
    for (auto& candidate : materials_)
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
      else return make_error(which + ": unknown type '" + t + "'");
    }
    if (m->specular()) m->kr = {};  // a mirror's reflectance is ks, and glass has none beside its Fresnel
    const RGB sum = m->kd + m->ks + m->kr;
    if (m->type != Material::Type::glass && std::max({sum.x, sum.y, sum.z}) > 1.0f + 1e-6f)
      return make_error(which + ": kd + ks + mirror exceeds 1 in some channel, so the surface would create energy");
  }
  return Ok{};
}

}  // namespace lf
