#pragma once
// What the farm-script functions share (lua/scene_functions.cpp, lua/farm_functions.cpp, lua/script.cpp): the
// builder a script fills, and how a function reads its arguments. Internal to lua/.
#include <lua.hpp>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "farm/farm_spec.hpp"
#include "lua/script.hpp"

namespace lf::lua_binding {

namespace fs = std::filesystem;

constexpr const char* kActorMeta = "lightfarm.actor";
constexpr const char* kHostMeta = "lightfarm.host";

struct Builder {
  FarmSpec spec;
  ScriptOptions options;
  fs::path script_dir;
  std::set<std::string> consumed_params;
  bool have_scene = false, have_camera = false, have_image = false, have_renderers = false;
  bool have_radiosity = false;
  std::optional<std::vector<std::string>> material_names;  // the scene's, read once for material { } checks
};

inline Builder& builder(lua_State* L) { return *static_cast<Builder*>(lua_touserdata(L, lua_upvalueindex(1))); }

// Where the script called the function running now ("farm.lua:12").
SourceLoc caller_loc(lua_State* L);
// Lua value at idx -> Value. Actor and host handles are refused: only wiring keys may hold them.
Value to_value(lua_State* L, int idx, const std::string& what, int depth = 0);
// Runs fn, turning ParamError into a Lua error at the caller's line.
template <class Fn>
void with_params(lua_State* L, Fn&& fn) {
  std::string failure;
  try {
    fn();
    return;
  } catch (const ParamError& e) {
    failure = e.what();
  }
  luaL_error(L, "%s", failure.c_str());
}

// Reads a table argument into a ParamTable named `owner`.
ParamTable table_params(lua_State* L, int idx, const std::string& owner);
// The actor a handle at idx stands for (an error naming `what` for anything else), and a new handle.
int actor_index(lua_State* L, int idx, const char* what);
void push_actor(lua_State* L, int index);
// Takes `host = h` or `host = {h1, h2, ...}` out of a table (if present): the hosts, in order; empty when absent.
std::vector<std::string> take_hosts(lua_State* L, int table, Builder& b);
// One host for an actor that is a single process.
std::string take_host(lua_State* L, int table, Builder& b);
// Takes the wiring keys (input, inputs, name, host) out of the table at index 1 into `a`; returns the wanted name.
std::string take_wiring(lua_State* L, Builder& b, ActorSpec& a, const std::string& what, const std::string& default_name);
// NAME "x" { ... } (host, material): a function of the name returning the one that takes the table, with the
// builder and the name as its upvalues.
int with_name(lua_State* L, lua_CFunction takes_table);
// The handles' metamethods.
int actor_tostring(lua_State* L);
int host_gc(lua_State* L);

// The functions a script sees, each a closure over the builder: scene, camera, image, light, material; host,
// slurm_hosts, lightop (with lightop.exec), multiplexer, renderers, radiosity, partition, farm, param.
void register_scene_functions(lua_State* L, Builder& b);
void register_farm_functions(lua_State* L, Builder& b);
// frames (lua/job_functions.cpp).
void register_job_functions(lua_State* L, Builder& b);

}  // namespace lf::lua_binding
