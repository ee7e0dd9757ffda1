// libFuzzer target: farm scripts (Lua 5.4 and our farm API). A script may be anything a user writes; it gets an
// error at a line or a farm, never a crash. Small budgets keep endless loops and memory bombs short here. The text
// is loaded from memory (luaL_loadbuffer), as a file's would be, without a file per input.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lua/script.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  lf::ScriptOptions options;
  options.instruction_budget = 200'000;
  options.memory_budget = 16u << 20;
  options.output = "/tmp/fuzz.exr";
  (void)lf::evaluate_script_text("/tmp/lightfarm-fuzz/farm.lua",
                                 std::string(reinterpret_cast<const char*>(data), size), options);
  return 0;
}
