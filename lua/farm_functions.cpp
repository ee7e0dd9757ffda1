// The script functions that build the farm: host, slurm_hosts, lightop (and lightop.exec), multiplexer,
// renderers, radiosity, partition, farm, param. They take wiring out of their tables and call farm/builders.
#include <algorithm>

#include "farm/builders.hpp"
#include "farm/slurm_hosts.hpp"
#include "farm/spec_readers.hpp"
#include "lua/binding.hpp"
#include "radiosity/config.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf::lua_binding {
namespace {
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

int l_host(lua_State* L) { return with_name(L, l_host_table); }
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
  if (const std::string wrong = kind->input_count_error(static_cast<int>(a.inputs.size())); !wrong.empty())
    luaL_error(L, "%s", wrong.c_str());
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
  a.kind = kPlugin.name;
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

// renderers { count = 2, lighting = op, batch = 16384, window = 4, tiles_in_flight = 3, tiles_per_message = 1,
//             mode = "async", host = h }
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

// farm { heartbeat_timeout = 10, request_timeout = 120, director_address, security = "curve", monitor,
// host_agents = true, light_paths = "check" }: settings of the farm as a whole.
int l_farm(lua_State* L) {
  Builder& b = builder(L);
  ParamTable p = table_params(L, 1, "farm");
  with_params(L, [&] { read_farm_settings(p, b.spec); });
  return 0;
}

// partition { parts = N, colocate = false, host = h | {h1, h2, ...} }: the scene split by space into N parts, each held
// by a `geometry` actor; `direct` and `pathtrace` then trace their rays through the parts (render/tracing/partition.hpp).
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

}  // namespace

void register_farm_functions(lua_State* L, Builder& b) {
  const luaL_Reg functions[] = {{"host", l_host},           {"slurm_hosts", l_slurm_hosts}, {"pool", l_multiplexer}, {"multiplexer", l_multiplexer},
                                {"renderers", l_renderers}, {"radiosity", l_radiosity},     {"partition", l_partition},
                                {"farm", l_farm},           {"param", l_param}};
  for (const luaL_Reg& f : functions) {
    lua_pushlightuserdata(L, &b);
    lua_pushcclosure(L, f.func, 1);
    lua_setglobal(L, f.name);
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
}

}  // namespace lf::lua_binding
