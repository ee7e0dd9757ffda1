#pragma once
// What an actor process (and the director's) knows of itself, apart from the farm: the signals that stop, pause
// and continue it, the farm's keys on its standard input, and its own figures (start time, memory, CPU).
#include <sys/types.h>

#include <cstdint>

#include "core/result.hpp"
#include "transport/security.hpp"

namespace lf {

// Installs SIGINT/SIGTERM handlers that make poll loops stop; returns true once a signal has arrived.
void install_stop_signals();
// The director's Ctrl-Z: SIGTSTP only sets a flag (take_suspend_request), so that it pauses its actors first.
void install_suspend_signal();
// True once after a SIGCONT: this process was stopped, and time passed that nobody could account for.
bool take_resumed();
bool take_suspend_request();
bool stop_requested();
int stop_signal();

// The farm's keys, from the first line of standard input (--curve): never on the command line or in the
// environment, where other users of the host could read them.
Result<wire::FarmKeys> read_farm_keys_from_stdin();

// An actor forked by a host agent counts its start-up from the `lightfarm actor` process that asked for it (its
// stub), as if it had loaded everything itself.
void count_start_from(pid_t pid);
// Seconds since this process (or the one count_start_from named) was started; 0 where unknown.
double seconds_since_process_start();
// This process's proportional set size (shared pages by their share); 0 where unknown.
uint64_t proportional_set_bytes();
// CPU time of this whole process, every thread, user and system.
double process_cpu_seconds();

}  // namespace lf
