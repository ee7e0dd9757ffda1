// The script functions that say what is rendered: scene, camera, image, light, environment, sun, material, shape. Each reads its table
// through a reader (core/specs, farm/spec_readers) and adds the script's line to what goes wrong.
#include "farm/spec_readers.hpp"
#include "lua/binding.hpp"

namespace lf::lua_binding {
namespace {
// scene { builtin = "cornell" } | scene { file = "room.obj" }
int l_scene(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_scene) luaL_error(L, "scene is declared twice");
  ParamTable p = table_params(L, 1, "scene");
  with_params(L, [&] {
    SceneSpec read = read_scene(p, b.script_dir);
    b.spec.scene.builtin = read.builtin;
    b.spec.scene.file = read.file;
  });
  b.spec.scene.loc = caller_loc(L);
  b.have_scene = true;
  return 0;
}

// A table a script gives once (camera, image), read by `read` into `into`.
template <class Spec, class Read>
int declare_once(lua_State* L, bool& declared, const char* name, Spec& into, Read read) {
  if (declared) luaL_error(L, "%s is declared twice", name);
  ParamTable p = table_params(L, 1, name);
  with_params(L, [&] {
    into = read(p);
    p.report_unused();
  });
  declared = true;
  return 0;
}

// camera { eye = {x,y,z}, at = {x,y,z}, up = {0,1,0}, fov = 39.3 } | camera { gltf = "Camera", fps = 24, ... }
// | camera { keys = { {frame = 1, eye = ..., at = ...}, ... }, fov = ... }: keyframes over the table's other keys
// (farm/job.hpp; read when the script ends, with frames { }).
int l_camera(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  lua_getfield(L, 1, "keys");
  if (!lua_isnil(L, -1)) {
    const Value keys = to_value(L, -1, "camera: keys");
    if (!keys.is_array() || keys.as_array().empty())
      luaL_error(L, "camera: keys must be a list of tables, each a frame and camera keys ({frame = 1, eye = ..., at = ...})");
    b.spec.job.camera_keys = keys.as_array();
    b.spec.job.keys_loc = caller_loc(L);
    lua_pushnil(L);
    lua_setfield(L, 1, "keys");
  }
  lua_pop(L, 1);
  return declare_once(L, b.have_camera, "camera", b.spec.camera,
                      [&b](const ParamTable& p) { return read_camera(p, b.spec.scene, &b.spec.job); });
}

// image { width = 512, height = 512, spp = 16, shade_spp = 16, adaptive_spp = 64, adaptive_threshold = 0.05,
//         tile = 16, output = "cornell.png", exposure = 0, tonemap = "clamp", sampler = "sobol" }
int l_image(lua_State* L) {
  Builder& b = builder(L);
  return declare_once(L, b.have_image, "image", b.spec.image, [](const ParamTable& p) { return ImageSpec::read(p); });
}

// light { quad = {c1, c2, c3, c4}, radiance = {r,g,b} } | light { sphere = {x,y,z}, radius = r, radiance = ... }
// | light { point = {x,y,z}, intensity = {r,g,b} }: a light added to the scene (any number of them). A quad emits
// on the side its corners wind counter-clockwise around. `name` names a quad's or sphere's material, for a job's
// frames to change (frames { materials }).
int l_light(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  Value light;
  with_params(L, [&] { light = read_light(to_value(L, 1, "light")); });
  if (const Value* name = light.find("name")) {
    for (const Value& other : b.spec.scene.lights)
      if (const Value* n = other.find("name"); n && *n == *name)
        luaL_error(L, "light: name '%s' is given twice", name->as_string().c_str());
    if (b.have_scene) {
      if (!b.material_names) b.material_names = scene_material_names(b.spec.scene);
      for (const auto& m : *b.material_names)
        if (m == name->as_string()) luaL_error(L, "light: name '%s' is a material of the scene already", m.c_str());
    }
  }
  if (const SourceLoc at = caller_loc(L); at.line > 0) light.as_map()["at"] = at.str();
  b.spec.scene.lights.push_back(std::move(light));
  return 0;
}

// environment { map = "sky.exr", intensity = 1, rotation = 0, camera = true } | environment { radiance = {r,g,b} }:
// light from every direction beyond the scene; sun { direction = {x,y,z}, irradiance = {r,g,b}, angle = 0.526 }: a
// distant disc. Each at most once (farm/spec_readers.hpp).
template <class Read>
int declare_distant_light(lua_State* L, const char* name, Read read) {
  Builder& b = builder(L);
  ParamTable p = table_params(L, 1, name);
  with_params(L, [&] {
    Value light = read(p);
    for (const Value& l : b.spec.scene.lights)
      if (l.find(name)) throw ParamError(std::string(name) + " is declared twice");
    b.spec.scene.lights.push_back(std::move(light));
  });
  return 0;
}
int l_environment(lua_State* L) {
  const fs::path dir = builder(L).script_dir;
  return declare_distant_light(L, "environment", [&dir](const ParamTable& p) { return read_environment(p, dir); });
}
int l_sun(lua_State* L) { return declare_distant_light(L, "sun", [](const ParamTable& p) { return read_sun(p); }); }

// material "Name" { emission = {r, g, b}, kd = {r, g, b}, ks = {r, g, b}, mirror = {r, g, b}, tf = {r, g, b}, ns = 20,
// ior = 1.5, type = "glossy" }:
// changes a material of the scene by name (an OBJ's MTL, or a built-in scene's); the scene must come first.
int l_material_table(lua_State* L) {
  Builder& b = builder(L);
  const std::string name = luaL_checkstring(L, lua_upvalueindex(2));
  if (!b.have_scene) luaL_error(L, "material \"%s\" needs scene { ... } before it", name.c_str());
  if (!b.material_names) b.material_names = scene_material_names(b.spec.scene);
  for (const auto& m : b.spec.scene.materials)
    if (m.find("name")->as_string() == name) luaL_error(L, "material '%s' is changed twice", name.c_str());
  ParamTable p = table_params(L, 1, "material '" + name + "'");
  with_params(L, [&] { b.spec.scene.materials.push_back(read_material_change(name, p, *b.material_names)); });
  return 0;
}

int l_material(lua_State* L) { return with_name(L, l_material_table); }

// shape "ground" { plane = {x, y, z}, normal = {0, 1, 0}, size = 100, kd = {0.5, 0.5, 0.5} }
// | shape "ball" { sphere = {x, y, z}, radius = 1, material = "chrome" }: geometry the script adds to the scene,
// with a material of its own (named after the shape; material { }'s parameters) or one of the scene's.
int l_shape_table(lua_State* L) {
  Builder& b = builder(L);
  const std::string name = luaL_checkstring(L, lua_upvalueindex(2));
  if (!b.have_scene) luaL_error(L, "shape \"%s\" needs scene { ... } before it", name.c_str());
  if (!b.material_names) b.material_names = scene_material_names(b.spec.scene);
  luaL_checktype(L, 1, LUA_TTABLE);
  const Value table = to_value(L, 1, "shape '" + name + "'");
  with_params(L, [&] {
    for (const auto& s : b.spec.scene.shapes)
      if (s.find("name")->as_string() == name) throw ParamError("shape '" + name + "' is declared twice");
    ShapeRead read = read_shape(name, table.as_map(), *b.material_names);
    b.spec.scene.shapes.push_back(std::move(read.shape));
    if (read.material_change) b.spec.scene.materials.push_back(std::move(*read.material_change));
  });
  return 0;
}

int l_shape(lua_State* L) { return with_name(L, l_shape_table); }

}  // namespace

void register_scene_functions(lua_State* L, Builder& b) {
  const luaL_Reg functions[] = {{"scene", l_scene}, {"camera", l_camera}, {"image", l_image},
                                {"light", l_light}, {"environment", l_environment}, {"sun", l_sun},
                                {"material", l_material}, {"shape", l_shape}};
  for (const luaL_Reg& f : functions) {
    lua_pushlightuserdata(L, &b);
    lua_pushcclosure(L, f.func, 1);
    lua_setglobal(L, f.name);
  }
}

}  // namespace lf::lua_binding
