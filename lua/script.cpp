// The farm-script library. Like Lua's own libraries: every argument checked with luaL_check*, so a mistake comes
// back as "farm.lua:12: what is wrong". This file runs a script under its budgets; the functions it sees are in
// scene_functions.cpp and farm_functions.cpp, what their tables mean in farm/spec_readers.cpp and core/specs.cpp.
//
// Globals a script sees: scene, camera, image, light, material, shape, lightop, pool (or multiplexer), radiosity, partition,
// renderers, host, slurm_hosts, farm, frames, param (and Lua's base, string, table, math and utf8 libraries; no io or os,
// so a script describes a farm and does nothing else).
#include "lua/script.hpp"

#include <cstdio>
#include <cstdlib>

#include "farm/builders.hpp"
#include "lua/binding.hpp"

namespace lf {
namespace {

using namespace lua_binding;

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
  // A job's frames, each with its camera and output (farm/job.hpp).
  const JobSpec& job = b.spec.job;
  if (!job.declared && !job.camera_keys.empty())
    return job.keys_loc.str() + ": camera: keys need frames { first = ..., last = ... }, the frames to render";
  if (!job.declared && !b.options.frames.empty()) return "--frames: the script declares no frames { } to choose from";
  if (job.declared) {
    try {
      b.spec.frames = expand_frames(job, b.spec.camera, b.spec.image.output, b.options.frames);
    } catch (const ParamError& e) {
      return job.loc.line > 0 ? job.loc.str() + ": " + e.what() : std::string(e.what());
    }
  }
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
  register_scene_functions(L, b);
  register_farm_functions(L, b);
  register_job_functions(L, b);

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
  if (!options.output.empty()) b.spec.image.output = options.output;
  if (std::string e = finish(b); !e.empty()) return make_error(e.find(path) == 0 ? e : path + ": " + e);
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
