// The script function that makes a farm a job of frames: frames { first, last, step, camera = function(frame),
// materials = function(frame), sun = function(frame), environment = function(frame), lights = function(frame) }.
// What it means, and camera { keys }, is farm/job.hpp; the frames to render are made when the script ends
// (script.cpp, with --frames).
#include "farm/spec_readers.hpp"
#include "lua/binding.hpp"

#include <algorithm>

namespace lf::lua_binding {
namespace {

// A frame's materials as the script's function returned them ({ Name = { emission = ..., kd = ... }, ... }): each
// read as material "Name" { } reads its table, in name order.
Value::Array read_frame_materials(const Value& returned, const std::vector<std::string>& names, int frame) {
  const std::string what = "frames: the materials function's table for frame " + std::to_string(frame);
  if (!returned.is_map()) throw ParamError(what + " is not a table of materials by name");
  Value::Array changes;
  for (const auto& [name, table] : returned.as_map()) {
    if (!table.is_map()) throw ParamError(what + ": material '" + name + "' is not given a table");
    changes.push_back(read_material_change(name, ParamTable(table.as_map(), what + ", material '" + name + "'"), names));
  }
  return changes;
}

// A frame's point lights as the script's function returned them ({ bulb = { point = ..., intensity = ... }, ... }),
// each a named light { point } of the script: {name = "bulb", light = {index, of, point?, intensity?}}, the index-th
// of the script's `of` point lights (the scene's last: Scene::apply_light_changes), in name order.
void read_frame_point_lights(const Value& returned, const Value::Array& lights, int frame, Value::Array& changes) {
  const std::string what = "frames: the lights function's table for frame " + std::to_string(frame);
  if (!returned.is_map()) throw ParamError(what + " is not a table of point lights by name");
  std::vector<std::string> points;  // the script's point lights' names, in order ("" for an unnamed one)
  for (const Value& light : lights)
    if (light.find("point")) points.push_back(light.find("name") ? light.find("name")->as_string() : "");
  for (const auto& [name, table] : returned.as_map()) {
    const auto at = std::find(points.begin(), points.end(), name);
    if (name.empty() || at == points.end()) {
      std::string known;
      for (const auto& n : points)
        if (!n.empty()) known += (known.empty() ? "" : ", ") + n;
      throw ParamError(what + ": '" + name + "' is not a named point light of the script (" +
                       (known.empty() ? std::string("it names none: light { name = \"bulb\", point = ... }") : "named: " + known) + ")");
    }
    if (!table.is_map()) throw ParamError(what + ": point light '" + name + "' is not given a table");
    Value light = read_frame_point_light(ParamTable(table.as_map(), what + ", point light '" + name + "'"));
    light.as_map()["index"] = static_cast<int64_t>(at - points.begin());
    light.as_map()["of"] = static_cast<int64_t>(points.size());
    changes.push_back(Value::Map{{"name", name}, {"light", std::move(light)}});
  }
}

// frames { first = 1, last = 240, step = 1, camera = function(frame) return { eye = ..., at = ... } end,
//          materials = function(frame) return { Torch = { emission = ... } } end,
//          sun = function(frame) return { direction = ..., irradiance = ... } end,
//          environment = function(frame) return { rotation = ..., intensity = ... } end,
//          lights = function(frame) return { bulb = { point = ..., intensity = ... } } end }
// A frame's sun and environment travel with its material changes, as entries {name = "sun", sun = {...}} and
// {name = "environment", environment = {...}}, its point lights as {name = "bulb", light = {...}}
// (Scene::apply_light_changes).
int l_frames(lua_State* L) {
  Builder& b = builder(L);
  if (b.spec.job.declared) luaL_error(L, "frames is declared twice");
  luaL_checktype(L, 1, LUA_TTABLE);
  // The functions are called for each frame here, while the script runs (under its budget); the cameras' tables are
  // read over camera { } when the script ends.
  lua_settop(L, 1);
  constexpr int kFunctions = 5;
  int functions[kFunctions] = {0, 0, 0, 0, 0};  // stack index of each function below, or 0
  const char* names[kFunctions] = {"camera", "materials", "sun", "environment", "lights"};
  static const char* returns[kFunctions] = {"camera table", "table of materials by name", "sun table",
                                            "environment table", "table of point lights by name"};
  for (int i = 0; i < kFunctions; ++i) {
    lua_getfield(L, 1, names[i]);
    if (lua_isfunction(L, -1)) functions[i] = lua_gettop(L);
    else if (!lua_isnil(L, -1)) luaL_error(L, "frames: %s must be a function of the frame number", names[i]);
    else lua_pop(L, 1);
    lua_pushnil(L);
    lua_setfield(L, 1, names[i]);
  }
  ParamTable p = table_params(L, 1, "frames");
  JobSpec& job = b.spec.job;
  with_params(L, [&] { read_frames(p, job); });
  job.declared = true;
  job.loc = caller_loc(L);
  if (functions[1] && !b.have_scene) luaL_error(L, "frames: materials needs scene { ... } before it");
  std::vector<std::string> material_names;
  if (functions[1]) {
    if (!b.material_names) b.material_names = scene_material_names(b.spec.scene);  // the catalogue, read once
    material_names = *b.material_names;
    for (const Value& shape : b.spec.scene.shapes) material_names.push_back(shape.find("name")->as_string());
    for (const Value& light : b.spec.scene.lights)
      if (const Value* name = light.find("name"); name && !light.find("point")) material_names.push_back(name->as_string());
  }
  for (int frame : job.numbers()) {
    for (int i = 0; i < kFunctions; ++i) {
      if (!functions[i]) continue;
      lua_pushvalue(L, functions[i]);
      lua_pushinteger(L, frame);
      lua_call(L, 1, 1);
      if (!lua_istable(L, -1))
        luaL_error(L, "frames: the %s function returned a %s for frame %d, not a %s", names[i], luaL_typename(L, -1),
                   frame, returns[i]);
      const Value returned = to_value(L, -1, std::string("frames: the ") + names[i] + " function's table for frame " + std::to_string(frame));
      lua_pop(L, 1);
      if (i == 0) job.camera_of_frame[frame] = returned;
      else if (i == 1) with_params(L, [&] { job.materials_of_frame[frame] = read_frame_materials(returned, material_names, frame); });
      else if (i == 4) with_params(L, [&] { read_frame_point_lights(returned, b.spec.scene.lights, frame, job.materials_of_frame[frame]); });
      else
        with_params(L, [&] {
          // Read as sun { } reads its table, or as a frame's environment (after the materials, which it joins).
          const std::string key = names[i];
          Value read;
          try {
            ParamTable t(returned.as_map(), key);
            read = i == 2 ? read_sun(t) : read_frame_environment(t);
          } catch (const ParamError& e) {
            throw ParamError("frames: frame " + std::to_string(frame) + ": " + e.what());
          }
          job.materials_of_frame[frame].push_back(Value::Map{{"name", key}, {key, *read.find(key)}});
        });
    }
  }
  return 0;
}

}  // namespace

void register_job_functions(lua_State* L, Builder& b) {
  lua_pushlightuserdata(L, &b);
  lua_pushcclosure(L, l_frames, 1);
  lua_setglobal(L, "frames");
}

}  // namespace lf::lua_binding
