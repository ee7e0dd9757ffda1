#pragma once
// What the remote launchers (ssh, slurm) share: running a command with its output captured, and shipping a scene
// into a host's cache. (Their actors start through a host launcher: actors/launchers/host_launcher.hpp.)
#include <string>
#include <vector>

#include "actors/launchers/launcher.hpp"

namespace lf {

// The host's scene cache, by the same rule as this machine's (local_cache_dir), in the host's own environment.
inline constexpr const char* kCacheDir = "d=\"${LIGHTFARM_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/lightfarm}/scenes\"; ";

struct Captured {
  bool ran = false;  // false: it could not even start (output says why)
  int status = -1;   // as from waitpid; -1: timed out (the child was killed)
  std::string output;
};
// Runs argv with stdout and stderr captured, `input` on its stdin (else /dev/null), for at most `seconds`.
Captured run_captured(const std::vector<std::string>& argv, double seconds, const std::string* input = nullptr);
std::string last_line(std::string text);
// `text` quoted for a POSIX shell.
std::string shell_quote(const std::string& text);

std::string cache_check_script(const std::string& hash, size_t size);
std::string cache_write_script(const std::string& hash);
// Ships `bytes` with `prefix` + a shell script as the remote command (the script is the last argument).
Result<Launcher::Shipped> ship_through(const std::vector<std::string>& prefix, const std::string& who,
                                       const std::string& bytes, const std::string& hash);

}  // namespace lf
