#pragma once
// Folders a process keeps for itself in /tmp (ssh control sockets, an actor's IPC socket): mode 0700, named
// /tmp/lightfarm-KIND-PID-XXXXXX after their owner, so that folders left by a process that was SIGKILLed (and
// could not remove its own) are recognised and swept by the next lightfarm process on that host.
#include <string>
#include <string_view>

namespace lf {

// Makes /tmp/lightfarm-KIND-<this pid>-XXXXXX (0700); "" when it cannot.
std::string make_private_dir(const std::string& kind);
// Removes this user's /tmp/lightfarm-KIND-PID-* folders whose PID no longer runs; returns how many went.
int sweep_stale_private_dirs(const std::string& kind);
// Whether `pid` (decimal digits, as in a file name made with the writer's PID) names a process that no longer runs.
// False for anything else, and for a live or reused PID: what it names is then kept.
bool owner_is_gone(std::string_view pid);

}  // namespace lf
