#pragma once
// Farm scripts: Lua 5.4, declarative. Evaluating a script yields a FarmSpec or an error that names the script's
// file and line. The functions a script may call are documented in docs/lua-api.md. This is only a binding:
// what the graph means lives in farm/builders.hpp.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "farm/farm_spec.hpp"
#include "core/result.hpp"

namespace lf {

struct ScriptOptions {
  std::map<std::string, std::string> set;  // --set name=value, read by param(name, default)
  std::string output;                      // --output FILE, overrides image { output = ... }
  std::vector<int> frames;                 // --frames: which of the job's frames to render (empty: all)
  // A script describes a farm and must end: it may run this many Lua instructions and hold this much memory;
  // beyond, an error at the line it was running (an endless loop, a table that keeps growing).
  uint64_t instruction_budget = 200'000'000;
  size_t memory_budget = 256u << 20;
};

Result<FarmSpec> evaluate_script(const std::string& path, const ScriptOptions& options = {});
// The same for a script's text; `label` stands for its path (messages, files named relative to it).
Result<FarmSpec> evaluate_script_text(const std::string& label, const std::string& text,
                                      const ScriptOptions& options = {});

}  // namespace lf
