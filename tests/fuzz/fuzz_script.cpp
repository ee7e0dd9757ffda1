// libFuzzer target: farm scripts (Lua 5.4 and our farm API). A script may be anything a user writes; it gets an
// error at a line or a farm, never a crash. Small budgets keep endless loops and memory bombs short here.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "lua/script.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/lightfarm-fuzz-script-" + std::to_string(::getpid()) + ".lua";
  std::ofstream(path, std::ios::binary | std::ios::trunc) << std::string(reinterpret_cast<const char*>(data), size);
  lf::ScriptOptions options;
  options.instruction_budget = 200'000;
  options.memory_budget = 16u << 20;
  options.output = "/tmp/fuzz.exr";
  (void)lf::evaluate_script(path, options);
  return 0;
}
