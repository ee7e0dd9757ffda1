// The farm-script library. Like Lua's own libraries: one registration table, every argument checked with
// luaL_check*, so a mistake comes back as "farm.lua:12: what is wrong".
//
// Globals a script sees: scene, camera, image, light, material, lightop, multiplexer, radiosity, partition, renderers, host, farm, param (and Lua's base, string, table,
// math and utf8 libraries; no io or os, so a script describes a farm and does nothing else).
#include "lua/script.hpp"

#include <lua.hpp>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "core/params.hpp"
#include "farm/builders.hpp"
#include "farm/slurm_hosts.hpp"
#include "farm/spec_readers.hpp"
#include "radiosity/config.hpp"
#include "render/image.hpp"
#include "render/lightop_registry.hpp"
#include "render/scene.hpp"

namespace lf {
namespace {

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

Builder& builder(lua_State* L) { return *static_cast<Builder*>(lua_touserdata(L, lua_upvalueindex(1))); }

SourceLoc caller_loc(lua_State* L) {
  lua_Debug ar;
  for (int level = 1; lua_getstack(L, level, &ar); ++level) {
    lua_getinfo(L, "Sl", &ar);
    if (ar.currentline > 0) return SourceLoc{ar.short_src, ar.currentline};
  }
  return SourceLoc{};
}

// Lua value at idx -> Value. Actor and host handles are refused: only wiring keys may hold them.
Value to_value(lua_State* L, int idx, const std::string& what, int depth = 0) {
  idx = lua_absindex(L, idx);
  if (depth > 16) luaL_error(L, "%s nests too deeply", what.c_str());
  switch (lua_type(L, idx)) {
    case LUA_TNIL: return Value();
    case LUA_TBOOLEAN: return Value(static_cast<bool>(lua_toboolean(L, idx)));
    case LUA_TNUMBER:
      if (lua_isinteger(L, idx)) return Value(static_cast<int64_t>(lua_tointeger(L, idx)));
      return Value(static_cast<double>(lua_tonumber(L, idx)));
    case LUA_TSTRING: return Value(std::string(lua_tostring(L, idx)));
    case LUA_TTABLE: {
      lua_Integer n = luaL_len(L, idx);
      size_t count = 0;
      lua_pushnil(L);
      while (lua_next(L, idx)) {
        ++count;
        lua_pop(L, 1);
      }
      if (n > 0 && static_cast<size_t>(n) == count) {
        Value::Array a;
        for (lua_Integer i = 1; i <= n; ++i) {
          lua_geti(L, idx, i);
          a.push_back(to_value(L, -1, what, depth + 1));
          lua_pop(L, 1);
        }
        return Value(std::move(a));
      }
      Value::Map m;
      lua_pushnil(L);
      while (lua_next(L, idx)) {
        if (lua_type(L, -2) != LUA_TSTRING) luaL_error(L, "%s: table keys must be names", what.c_str());
        std::string key = lua_tostring(L, -2);
        m.emplace(key, to_value(L, -1, what + "." + key, depth + 1));
        lua_pop(L, 1);
      }
      return Value(std::move(m));
    }
    case LUA_TUSERDATA:
      if (luaL_testudata(L, idx, kActorMeta) || luaL_testudata(L, idx, kHostMeta))
        luaL_error(L, "%s cannot hold an actor or host here", what.c_str());
      [[fallthrough]];
    default: luaL_error(L, "%s: a %s is not a valid value", what.c_str(), luaL_typename(L, idx));
  }
  return Value();
}

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
ParamTable table_params(lua_State* L, int idx, const std::string& owner) {
  luaL_checktype(L, idx, LUA_TTABLE);
  Value v = to_value(L, idx, owner);
  return ParamTable(v.is_map() ? v.as_map() : Value::Map{}, owner);
}

int actor_index(lua_State* L, int idx, const char* what) {
  auto* handle = static_cast<int*>(luaL_testudata(L, idx, kActorMeta));
  if (!handle) {
    luaL_error(L, "%s must be a LightOp (made with lightop \"kind\" { ... }), got a %s", what, luaL_typename(L, idx));
  }
  return *handle;
}

void push_actor(lua_State* L, int index) {
  auto* handle = static_cast<int*>(lua_newuserdatauv(L, sizeof(int), 0));
  *handle = index;
  luaL_setmetatable(L, kActorMeta);
}

// One host: a handle made by host "name" { ... }, or a declared host's name.
std::string host_name(lua_State* L, int idx, Builder& b) {
  if (auto* name = static_cast<std::string*>(luaL_testudata(L, idx, kHostMeta))) return *name;
  if (lua_type(L, idx) != LUA_TSTRING) luaL_error(L, "host must be a host (made with host \"name\" { ... }) or its name");
  std::string host = lua_tostring(L, idx);
  bool known = host == "local";
  for (const auto& h : b.spec.hosts) known = known || h.name == host;
  if (!known) luaL_error(L, "host '%s' is not declared (declare it with host \"%s\" { ... })", host.c_str(), host.c_str());
  return host;
}

// Takes `host = h` or `host = {h1, h2, ...}` out of a table (if present): the hosts, in order; empty when absent.
std::vector<std::string> take_hosts(lua_State* L, int table, Builder& b) {
  lua_getfield(L, table, "host");
  std::vector<std::string> hosts;
  if (lua_istable(L, -1) && !luaL_testudata(L, -1, kHostMeta)) {
    const lua_Integer n = luaL_len(L, -1);
    if (n < 1) luaL_error(L, "host = { ... } needs at least one host");
    for (lua_Integer i = 1; i <= n; ++i) {
      lua_geti(L, -1, i);
      hosts.push_back(host_name(L, -1, b));
      lua_pop(L, 1);
    }
  } else if (!lua_isnil(L, -1)) {
    hosts.push_back(host_name(L, -1, b));
  }
  lua_pop(L, 1);
  lua_pushnil(L);
  lua_setfield(L, table, "host");
  return hosts;
}

// One host for an actor that is a single process.
std::string take_host(lua_State* L, int table, Builder& b) {
  auto hosts = take_hosts(L, table, b);
  if (hosts.size() > 1) luaL_error(L, "one actor runs on one host; a list of hosts is for multiplexer, renderers and radiosity");
  return hosts.empty() ? "local" : hosts[0];
}

// scene { builtin = "cornell" } | scene { file = "room.obj" }
int l_scene(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_scene) luaL_error(L, "scene is declared twice");
  ParamTable p = table_params(L, 1, "scene");
  with_params(L, [&] {
    SceneSpec read = read_scene(p, b.script_dir);
    p.report_unused();
    b.spec.scene.builtin = read.builtin;
    b.spec.scene.file = read.file;
  });
  b.spec.scene.loc = caller_loc(L);
  b.have_scene = true;
  return 0;
}

// camera { eye = {x,y,z}, at = {x,y,z}, up = {0,1,0}, fov = 39.3 }
int l_camera(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_camera) luaL_error(L, "camera is declared twice");
  ParamTable p = table_params(L, 1, "camera");
  with_params(L, [&] {
    b.spec.camera = CameraSpec::read(p);
    p.report_unused();
  });
  b.have_camera = true;
  return 0;
}

// image { width = 512, height = 512, spp = 16, shade_spp = 16, adaptive_spp = 64, adaptive_threshold = 0.05,
//         tile = 16, output = "cornell.png", exposure = 0, tonemap = "clamp", sampler = "sobol" }
int l_image(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_image) luaL_error(L, "image is declared twice");
  ParamTable p = table_params(L, 1, "image");
  with_params(L, [&] {
    b.spec.image = ImageSpec::read(p);
    p.report_unused();
  });
  b.have_image = true;
  return 0;
}

// host "name" { launcher = "local" | "ssh", address = "10.0.0.11", user, port, ssh_config, lightfarm } -> host handle
int l_host_table(lua_State* L) {
  Builder& b = builder(L);
  const char* name = luaL_checkstring(L, lua_upvalueindex(2));
  ParamTable p = table_params(L, 1, std::string("host '") + name + "'");
  HostSpec h;
  with_params(L, [&] { h = read_host(name, p, b.script_dir); });
  for (const auto& other : b.spec.hosts)
    if (other.name == h.name) luaL_error(L, "host '%s' is declared twice", name);
  h.loc = caller_loc(L);
  b.spec.hosts.push_back(h);
  auto* ud = static_cast<std::string*>(lua_newuserdatauv(L, sizeof(std::string), 0));
  new (ud) std::string(h.name);
  luaL_setmetatable(L, kHostMeta);
  return 1;
}

// slurm_hosts() -> {host, ...}: the nodes of the Slurm allocation the farm runs in (farm/slurm_hosts.hpp).
int l_slurm_hosts(lua_State* L) {
  Builder& b = builder(L);
  auto hosts = slurm_allocation_hosts();
  if (!hosts) luaL_error(L, "%s", hosts.error().message.c_str());
  lua_createtable(L, static_cast<int>(hosts->size()), 0);
  int i = 0;
  for (HostSpec& h : *hosts) {
    bool known = false;
    for (const auto& other : b.spec.hosts) known = known || other.name == h.name;
    if (!known) {
      h.loc = caller_loc(L);
      b.spec.hosts.push_back(h);
    }
    auto* ud = static_cast<std::string*>(lua_newuserdatauv(L, sizeof(std::string), 0));
    new (ud) std::string(h.name);
    luaL_setmetatable(L, kHostMeta);
    lua_rawseti(L, -2, ++i);
  }
  return 1;
}

// NAME "x" { ... } (host, material): a function of the name returning the one that takes the table, with the
// builder and the name as its upvalues.
int with_name(lua_State* L, lua_CFunction takes_table) {
  luaL_checkstring(L, 1);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_pushvalue(L, 1);
  lua_pushcclosure(L, takes_table, 2);
  return 1;
}

int l_host(lua_State* L) { return with_name(L, l_host_table); }

// Takes the wiring keys (input, inputs, name, host) out of the table at index 1 into `a`; returns the wanted name.
std::string take_wiring(lua_State* L, Builder& b, ActorSpec& a, const std::string& what, const std::string& default_name) {
  lua_getfield(L, 1, "input");
  if (!lua_isnil(L, -1)) a.inputs.push_back(actor_index(L, -1, "input"));
  lua_pop(L, 1);
  lua_getfield(L, 1, "inputs");
  if (!lua_isnil(L, -1)) {
    if (!a.inputs.empty()) luaL_error(L, "%s: give either input or inputs, not both", what.c_str());
    luaL_checktype(L, -1, LUA_TTABLE);
    lua_Integer n = luaL_len(L, -1);
    for (lua_Integer i = 1; i <= n; ++i) {
      lua_geti(L, -1, i);
      a.inputs.push_back(actor_index(L, -1, "each of inputs"));
      lua_pop(L, 1);
    }
  }
  lua_pop(L, 1);
  lua_getfield(L, 1, "name");
  std::string wanted = lua_isnil(L, -1) ? default_name : luaL_checkstring(L, -1);
  lua_pop(L, 1);
  a.host = take_host(L, 1, b);
  for (const char* key : {"input", "inputs", "name"}) {
    lua_pushnil(L);
    lua_setfield(L, 1, key);
  }
  if (wanted.empty() || wanted.size() > 64) luaL_error(L, "%s: name must be 1 to 64 characters", what.c_str());
  return wanted;
}

// lightop "kind" { params..., input = op | inputs = {op, ...}, name = "...", host = h } -> LightOp handle
int l_lightop_table(lua_State* L) {
  Builder& b = builder(L);
  const std::string kind_name = luaL_checkstring(L, lua_upvalueindex(2));
  luaL_checktype(L, 1, LUA_TTABLE);
  const LightOpKind* kind = find_lightop_kind(kind_name);  // checked in l_lightop already

  ActorSpec a;
  a.kind = kind_name;
  a.loc = caller_loc(L);
  // Wiring keys come out of the table before the rest becomes the op's parameters.
  std::string wanted = take_wiring(L, b, a, "lightop '" + kind_name + "'", kind_name);
  const int n_inputs = static_cast<int>(a.inputs.size());
  if (n_inputs < kind->min_inputs || (kind->max_inputs >= 0 && n_inputs > kind->max_inputs)) {
    std::string want = kind->max_inputs == kind->min_inputs ? std::to_string(kind->min_inputs)
                       : kind->max_inputs < 0 ? "at least " + std::to_string(kind->min_inputs)
                                              : std::to_string(kind->min_inputs) + " to " + std::to_string(kind->max_inputs);
    const bool one = want.size() >= 1 && want.back() == '1' && (want.size() == 1 || want[want.size() - 2] == ' ');
    luaL_error(L, "lightop '%s' takes %s input%s, got %d", kind_name.c_str(), want.c_str(), one ? "" : "s", n_inputs);
  }
  ParamTable params = table_params(L, 1, "lightop '" + kind_name + "'");
  with_params(L, [&] { create_lightop(*kind, params); });  // the op validates its own parameters
  a.params = params.values();
  a.name = wanted;
  push_actor(L, add_actor(b.spec, std::move(a)));
  return 1;
}

// lightop.exec { cmd = {"python3", "my_op.py"}, params..., input(s), name, host } -> LightOp handle
// Any executable that speaks docs/PROTOCOL.md. It runs in the script's folder with the arguments every actor gets
// appended (--kind exec --name NAME --director ENDPOINT); its parameters reach it in CONFIG, unchecked here.
int l_lightop_exec(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  ActorSpec a;
  a.kind = "exec";
  a.loc = caller_loc(L);
  lua_getfield(L, 1, "cmd");
  if (!lua_istable(L, -1) || luaL_len(L, -1) < 1)
    luaL_error(L, "lightop.exec needs cmd = {\"program\", \"arg\", ...}");
  Value::Array cmd;
  for (lua_Integer i = 1; i <= luaL_len(L, -1); ++i) {
    lua_geti(L, -1, i);
    if (lua_type(L, -1) != LUA_TSTRING) luaL_error(L, "lightop.exec: every entry of cmd must be a string");
    cmd.push_back(std::string(lua_tostring(L, -1)));
    lua_pop(L, 1);
  }
  lua_pop(L, 1);
  lua_pushnil(L);
  lua_setfield(L, 1, "cmd");
  const std::string program = cmd[0].as_string();
  std::string resolved = resolve_program(program, b.script_dir);
  if (resolved.empty()) luaL_error(L, "lightop.exec: program '%s' not found or not executable", program.c_str());
  cmd[0] = resolved;
  std::string wanted = take_wiring(L, b, a, "lightop.exec", fs::path(program).stem().string());
  a.params = to_value(L, 1, "lightop.exec").as_map();
  a.runtime["cmd"] = std::move(cmd);
  a.runtime["cwd"] = b.script_dir.string();
  a.name = wanted;
  push_actor(L, add_actor(b.spec, std::move(a)));
  return 1;
}

int l_lightop(lua_State* L) {
  if (lua_istable(L, 1)) lua_remove(L, 1);  // called through the lightop table's __call
  const char* kind = luaL_checkstring(L, 1);
  if (!find_lightop_kind(kind))
    luaL_error(L, "unknown LightOp kind '%s' (known kinds: %s)", kind, lightop_kind_list().c_str());
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_pushvalue(L, 1);
  lua_pushcclosure(L, l_lightop_table, 2);
  return 1;
}

// multiplexer { op, replicas = 2, strategy = "least_loaded", split = 0, window = 4, slowdown = {...}, name, host }
// The op (a lightop or another multiplexer, freshly declared) becomes replica 0; replicas 1.. are copies
// (farm/builders.hpp: replicate).
int l_multiplexer(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  PoolSpec pool;
  lua_geti(L, 1, 1);
  if (lua_isnil(L, -1)) luaL_error(L, "multiplexer needs a LightOp to replicate as its first entry");
  pool.op = actor_index(L, -1, "a multiplexer's first entry");
  lua_pop(L, 1);
  lua_pushnil(L);
  lua_seti(L, 1, 1);
  lua_getfield(L, 1, "name");
  if (!lua_isnil(L, -1)) pool.name = luaL_checkstring(L, -1);
  lua_pop(L, 1);
  lua_pushnil(L);
  lua_setfield(L, 1, "name");
  pool.hosts = take_hosts(L, 1, b);
  ParamTable p = table_params(L, 1, "multiplexer");
  with_params(L, [&] {
    pool.replicas = static_cast<int>(p.get_int("replicas", 2, 1, 64));
    pool.params = MultiplexerParams::read(p);
    // A test knob (docs/lua-api.md): replica i rests (factor - 1) x its compute time after each request.
    if (p.has("slowdown")) pool.slowdown = p.get_numbers("slowdown", {}, 1, 1000);
    p.report_unused();
  });
  pool.loc = caller_loc(L);
  auto index = replicate(b.spec, pool);
  if (!index) luaL_error(L, "%s", index.error().message.c_str());
  push_actor(L, *index);
  return 1;
}

// renderers { count = 2, lighting = op, batch = 16384, window = 4, tiles_in_flight = 3, mode = "async", host = h }
int l_renderers(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_renderers) luaL_error(L, "renderers is declared twice");
  luaL_checktype(L, 1, LUA_TTABLE);
  lua_getfield(L, 1, "lighting");
  if (lua_isnil(L, -1)) luaL_error(L, "renderers needs lighting = <a LightOp>");
  int lighting = actor_index(L, -1, "lighting");
  lua_pop(L, 1);
  lua_pushnil(L);
  lua_setfield(L, 1, "lighting");
  const auto hosts = take_hosts(L, 1, b);
  ParamTable p = table_params(L, 1, "renderers");
  int count = 1;
  RendererParams params;
  with_params(L, [&] {
    count = static_cast<int>(p.get_int("count", 1, 1, 256));
    params = RendererParams::read(p);
    p.report_unused();
  });
  add_renderers(b.spec, count, lighting, params, hosts, caller_loc(L));
  b.have_renderers = true;
  return 0;
}

// radiosity { rings = 2, ring_length = 4, samples_per_packet = 50, shooter_samples = 16, balance = "static+dynamic",
//             patch_size, element_size, subdivide, max_depth, converge, max_iterations, max_visits, ply, name, host }
// -> the `radiosity` LightOp. Declares the ring nodes (NAME.RING.POSITION, one process each) that solve the scene
// in the setup phase, and the LightOp that shades with their solution.
int l_radiosity(lua_State* L) {
  Builder& b = builder(L);
  if (b.have_radiosity) luaL_error(L, "radiosity is declared twice (a farm has one radiosity ring)");
  luaL_checktype(L, 1, LUA_TTABLE);
  ActorSpec op;
  op.kind = "radiosity";
  op.loc = caller_loc(L);
  const auto hosts = take_hosts(L, 1, b);  // before take_wiring, which allows one host only
  const std::string wanted = take_wiring(L, b, op, "radiosity", "radiosity");
  if (!op.inputs.empty()) luaL_error(L, "radiosity takes no inputs (it solves the scene itself)");
  ParamTable p = table_params(L, 1, "radiosity");
  radiosity::RingConfig config;
  with_params(L, [&] {
    config = radiosity::read_ring_config(p);
    p.report_unused();
  });
  Value::Map params = p.values();
  if (!config.ply.empty()) params["ply"] = fs::absolute(config.ply).lexically_normal().string();
  auto index = expand_ring(b.spec, config, params, unique_name(b.spec, wanted), hosts, op.loc);
  if (!index) luaL_error(L, "%s", index.error().message.c_str());
  b.have_radiosity = true;
  push_actor(L, *index);
  return 1;
}

// light { quad = {c1, c2, c3, c4}, radiance = {r,g,b} } | light { sphere = {x,y,z}, radius = r, radiance = ... }
// | light { point = {x,y,z}, intensity = {r,g,b} }: a light added to the scene (any number of them). A quad emits
// on the side its corners wind counter-clockwise around.
int l_light(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  Value light;
  with_params(L, [&] { light = read_light(to_value(L, 1, "light")); });
  if (const SourceLoc at = caller_loc(L); at.line > 0) light.as_map()["at"] = at.str();
  b.spec.scene.lights.push_back(std::move(light));
  return 0;
}

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

// farm { heartbeat_timeout = 10, request_timeout = 120, director_address, security = "curve", monitor,
// host_agents = true, light_paths = "check" }: settings of the farm as a whole.
int l_farm(lua_State* L) {
  Builder& b = builder(L);
  ParamTable p = table_params(L, 1, "farm");
  with_params(L, [&] { read_farm_settings(p, b.spec); });
  return 0;
}

// partition { parts = N, colocate = false, host = h | {h1, h2, ...} }: the scene split by space into N parts, each held
// by a `geometry` actor; `direct` and `pathtrace` then trace their rays through the parts (render/partition.hpp).
// colocate: a pool's replica j of such an op holds part j mod N too and is sent the points that lie there.
int l_partition(lua_State* L) {
  Builder& b = builder(L);
  luaL_checktype(L, 1, LUA_TTABLE);
  const auto hosts = take_hosts(L, 1, b);
  ParamTable p = table_params(L, 1, "partition");
  int parts = 1;
  bool colocate = false;
  with_params(L, [&] {
    parts = static_cast<int>(p.get_int("parts", 2, 1, 64));
    colocate = p.get_bool("colocate", false);
    p.report_unused();
  });
  if (auto st = add_partition(b.spec, parts, colocate, hosts, caller_loc(L)); !st) luaL_error(L, "%s", st.error().message.c_str());
  return 0;
}

// param(name, default): the value of --set name=..., converted to default's type, or default.
int l_param(lua_State* L) {
  Builder& b = builder(L);
  const char* name = luaL_checkstring(L, 1);
  luaL_checkany(L, 2);
  auto it = b.options.set.find(name);
  if (it == b.options.set.end()) {
    lua_pushvalue(L, 2);
    return 1;
  }
  b.consumed_params.insert(name);
  const std::string& text = it->second;
  switch (lua_type(L, 2)) {
    case LUA_TNUMBER:
      if (!lua_stringtonumber(L, text.c_str()))
        luaL_error(L, "--set %s=%s: param '%s' is a number", name, text.c_str(), name);
      return 1;
    case LUA_TBOOLEAN:
      if (text != "true" && text != "false")
        luaL_error(L, "--set %s=%s: param '%s' is true or false", name, text.c_str(), name);
      lua_pushboolean(L, text == "true");
      return 1;
    case LUA_TSTRING: lua_pushstring(L, text.c_str()); return 1;
    default: return luaL_error(L, "param '%s': the default must be a number, boolean or string", name);
  }
}

int actor_tostring(lua_State* L) {
  lua_pushfstring(L, "lightop #%d", *static_cast<int*>(luaL_checkudata(L, 1, kActorMeta)));
  return 1;
}

int host_gc(lua_State* L) {
  static_cast<std::string*>(luaL_checkudata(L, 1, kHostMeta))->~basic_string();
  return 0;
}

const luaL_Reg kFarmLib[] = {{"scene", l_scene},   {"camera", l_camera},       {"image", l_image},
                             {"renderers", l_renderers}, {"host", l_host}, {"slurm_hosts", l_slurm_hosts},
                             {"param", l_param},   {"farm", l_farm},       {"multiplexer", l_multiplexer},
                             {"light", l_light},   {"radiosity", l_radiosity}, {"material", l_material},
                             {"partition", l_partition},
                             {nullptr, nullptr}};

void open_libs(lua_State* L) {
  // A farm script describes; it does not read files or run programs.
  const luaL_Reg libs[] = {{LUA_GNAME, luaopen_base},
                           {LUA_TABLIBNAME, luaopen_table},
                           {LUA_STRLIBNAME, luaopen_string},
                           {LUA_MATHLIBNAME, luaopen_math},
                           {LUA_UTF8LIBNAME, luaopen_utf8}};
  for (const auto& lib : libs) {
    luaL_requiref(L, lib.name, lib.func, 1);
    lua_pop(L, 1);
  }
  for (const char* unsafe : {"dofile", "loadfile", "load", "require", "collectgarbage"}) {
    lua_pushnil(L);
    lua_setglobal(L, unsafe);
  }
}

std::string finish(Builder& b) {
  if (!b.have_scene) return "the script declares no scene (add scene { builtin = \"cornell\" })";
  if (!b.have_renderers) return "the script declares no renderers (add renderers { lighting = ... })";
  for (const auto& [name, value] : b.options.set)
    if (!b.consumed_params.count(name)) return "--set " + name + "=" + value + ": the script has no param '" + name + "'";
  if (auto st = validate(b.spec); !st) return st.error().message;
  settle_pool_dispatch(b.spec);
  return {};
}

}  // namespace

namespace {

// The script's budgets (ScriptOptions): memory through Lua's allocator, instructions through a count hook, which
// also remembers the line last seen so that a memory error can name it.
struct Budget {
  size_t used = 0, memory_limit = 0;
  uint64_t instructions = 0, instruction_limit = 0;
  std::string where;  // "file:line" last seen by the hook
  bool out_of_memory = false;
};
constexpr int kHookEvery = 1000;

void* budget_alloc(void* ud, void* ptr, size_t osize, size_t nsize) {
  auto* b = static_cast<Budget*>(ud);
  const size_t old = ptr ? osize : 0;  // without a block, osize is a type tag
  if (nsize == 0) {
    std::free(ptr);
    b->used -= old;
    return nullptr;
  }
  if (nsize > old && b->used - old + nsize > b->memory_limit) {
    b->out_of_memory = true;
    return nullptr;  // Lua raises "not enough memory"
  }
  void* p = std::realloc(ptr, nsize);
  if (p) b->used = b->used - old + nsize;
  return p;
}

void budget_hook(lua_State* L, lua_Debug* ar) {
  Budget* b = nullptr;
  lua_getallocf(L, reinterpret_cast<void**>(&b));
  b->instructions += kHookEvery;
  if (lua_getinfo(L, "Sl", ar) && ar->currentline > 0) b->where = std::string(ar->short_src) + ":" + std::to_string(ar->currentline);
  if (b->instructions > b->instruction_limit) {
    // Named at the line running now (luaL_error would name the caller's, which the main chunk has not).
    lua_pushfstring(L, "%s: the script ran for more than %d million Lua instructions (an endless loop?); a farm "
                    "script describes a farm and ends", b->where.c_str(), static_cast<int>(b->instruction_limit / 1000000));
    lua_error(L);
  }
}

int lua_panic(lua_State* L) {
  std::fprintf(stderr, "lightfarm: error: Lua: %s\n", lua_tostring(L, -1));
  std::abort();
}

}  // namespace

namespace {

// Runs a script's text (nullptr: the file at `path`) under the farm API and the budgets.
Result<FarmSpec> evaluate(const std::string& path, const std::string* text, const ScriptOptions& options) {
  Builder b;
  b.options = options;
  b.spec.script = path;
  b.script_dir = fs::absolute(fs::path(path)).parent_path();

  Budget budget;
  budget.memory_limit = options.memory_budget;
  budget.instruction_limit = options.instruction_budget;
  lua_State* L = lua_newstate(budget_alloc, &budget);
  if (!L) return make_error("cannot create a Lua state");
  lua_atpanic(L, lua_panic);
  lua_sethook(L, budget_hook, LUA_MASKCOUNT, kHookEvery);
  open_libs(L);
  luaL_newmetatable(L, kActorMeta);
  lua_pushcfunction(L, actor_tostring);
  lua_setfield(L, -2, "__tostring");
  lua_pop(L, 1);
  luaL_newmetatable(L, kHostMeta);
  lua_pushcfunction(L, host_gc);
  lua_setfield(L, -2, "__gc");
  lua_pop(L, 1);
  for (const luaL_Reg* f = kFarmLib; f->name; ++f) {
    lua_pushlightuserdata(L, &b);
    lua_pushcclosure(L, f->func, 1);
    lua_setglobal(L, f->name);
  }
  // lightop is a table: called, it declares a built-in kind; lightop.exec declares an external program.
  lua_newtable(L);
  lua_pushlightuserdata(L, &b);
  lua_pushcclosure(L, l_lightop_exec, 1);
  lua_setfield(L, -2, "exec");
  lua_newtable(L);
  lua_pushlightuserdata(L, &b);
  lua_pushcclosure(L, l_lightop, 1);
  lua_setfield(L, -2, "__call");
  lua_setmetatable(L, -2);
  lua_setglobal(L, "lightop");

  std::string failure;
  const int loaded = text ? luaL_loadbuffer(L, text->data(), text->size(), ("@" + path).c_str())
                          : luaL_loadfile(L, path.c_str());
  if (loaded != LUA_OK || lua_pcall(L, 0, 0, 0) != LUA_OK) {
    failure = lua_isstring(L, -1) ? lua_tostring(L, -1) : "script failed with a non-string error";
    if (budget.out_of_memory)
      failure = (budget.where.empty() ? path : budget.where) + ": the script used more than " +
                std::to_string(budget.memory_limit >> 20) + " MiB of memory (a table that keeps growing?)";
  }
  lua_close(L);
  if (!failure.empty()) return make_error(failure);
  if (std::string e = finish(b); !e.empty()) return make_error(e.find(path) == 0 ? e : path + ": " + e);
  if (!options.output.empty()) b.spec.image.output = options.output;
  return std::move(b.spec);
}

}  // namespace

Result<FarmSpec> evaluate_script(const std::string& path, const ScriptOptions& options) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return make_error("script '" + path + "' not found");
  return evaluate(path, nullptr, options);
}

Result<FarmSpec> evaluate_script_text(const std::string& label, const std::string& text,
                                      const ScriptOptions& options) {
  return evaluate(label, &text, options);
}

}  // namespace lf
