// The script function that makes a farm a job of frames: frames { first, last, step, camera = function(frame) }.
// What it means, and camera { keys }, is farm/job.hpp; the frames to render are made when the script ends
// (script.cpp, with --frames).
#include "lua/binding.hpp"

namespace lf::lua_binding {
namespace {

// frames { first = 1, last = 240, step = 1, camera = function(frame) return { eye = ..., at = ... } end }
int l_frames(lua_State* L) {
  Builder& b = builder(L);
  if (b.spec.job.declared) luaL_error(L, "frames is declared twice");
  luaL_checktype(L, 1, LUA_TTABLE);
  // The camera function is called for each frame here, while the script runs (under its budget); its tables are
  // read over camera { } when the script ends.
  lua_settop(L, 1);
  lua_getfield(L, 1, "camera");  // stays at index 2
  const bool has_function = lua_isfunction(L, 2);
  if (!has_function && !lua_isnil(L, 2)) luaL_error(L, "frames: camera must be a function of the frame number");
  lua_pushnil(L);
  lua_setfield(L, 1, "camera");
  ParamTable p = table_params(L, 1, "frames");
  JobSpec& job = b.spec.job;
  with_params(L, [&] { read_frames(p, job); });
  job.declared = true;
  job.loc = caller_loc(L);
  if (!has_function) return 0;
  for (int frame : job.numbers()) {
    lua_pushvalue(L, 2);
    lua_pushinteger(L, frame);
    lua_call(L, 1, 1);
    if (!lua_istable(L, -1))
      luaL_error(L, "frames: the camera function returned a %s for frame %d, not a camera table", luaL_typename(L, -1), frame);
    job.camera_of_frame[frame] = to_value(L, -1, "frames: the camera function's table for frame " + std::to_string(frame));
    lua_pop(L, 1);
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
