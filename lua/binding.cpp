#include "lua/binding.hpp"

#include <string>

#include "farm/builders.hpp"

namespace lf::lua_binding {

SourceLoc caller_loc(lua_State* L) {
  lua_Debug ar;
  for (int level = 1; lua_getstack(L, level, &ar); ++level) {
    lua_getinfo(L, "Sl", &ar);
    if (ar.currentline > 0) return SourceLoc{ar.short_src, ar.currentline};
  }
  return SourceLoc{};
}

// Lua value at idx -> Value. Actor and host handles are refused: only wiring keys may hold them.
Value to_value(lua_State* L, int idx, const std::string& what, int depth) {
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


// NAME "x" { ... } (host, material): a function of the name returning the one that takes the table, with the
// builder and the name as its upvalues.
int with_name(lua_State* L, lua_CFunction takes_table) {
  luaL_checkstring(L, 1);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_pushvalue(L, 1);
  lua_pushcclosure(L, takes_table, 2);
  return 1;
}

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


int actor_tostring(lua_State* L) {
  lua_pushfstring(L, "lightop #%d", *static_cast<int*>(luaL_checkudata(L, 1, kActorMeta)));
  return 1;
}

int host_gc(lua_State* L) {
  static_cast<std::string*>(luaL_checkudata(L, 1, kHostMeta))->~basic_string();
  return 0;
}

}  // namespace lf::lua_binding
