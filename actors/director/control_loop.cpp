#include "actors/director/control_loop.hpp"

#include <cmath>
#include <csignal>

#include "actors/director/farm_failure.hpp"
#include "actors/runtime/process.hpp"
#include "core/log.hpp"

namespace lf {
namespace {
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

void ControlLoop::turn(long timeout_ms) {
  if (stop_requested())
    throw FarmFailure{"interrupted by signal " + std::to_string(stop_signal()) + "; stopping the farm",
                      128 + stop_signal()};
  if (take_suspend_request()) suspend_farm();
  notice_outside_stop();
  wire::Poller poller;
  poller.add(control_.socket());
  const long wait_ms = std::min<long>(timeout_ms, static_cast<long>(spec_.heartbeat_timeout * 250));
  const auto waiting_since = Clock::now();
  poller.wait(wait_ms);
  // The stop may have come during the wait: before reading what it left behind.
  notice_outside_stop(seconds_since(waiting_since) > wait_ms / 1000.0 + spec_.heartbeat_timeout);
  read_messages();
  while (auto exit = launchers_.reap_one()) {
    // A stop that landed while messages were read would otherwise make the actors that left during it look like
    // the fault: judge this director's own absence first.
    notice_outside_stop();
    // Its last words (an ERROR with the reason, or BYE) may still be in flight: read them before judging. (Not for
    // an actor that has said BYE: at the end of every farm that waited 50 ms per actor, 0.6 s for 12.)
    wire::Poller last;
    last.add(control_.socket());
    for (int i = 0; i < 5 && supervisor_.may_still_speak(exit->pid) && !last.wait(10)[0]; ++i) {
    }
    read_messages();
    judged(supervisor_.on_exit(*exit));
  }
  judged(supervisor_.check_heartbeats(Clock::now()));
  supervisor_.send_heartbeats(Clock::now());
}

void ControlLoop::read_messages() {
  while (auto in = control_.socket().receive()) judged(supervisor_.on_message(in->peer, in->message));
}

void ControlLoop::judged(const Status& st) {
  check(st);
  for (SupervisorEvent& e : supervisor_.take_events()) route_(e);
}

void ControlLoop::notice_outside_stop(bool slept_through) {
  if (take_resumed() || slept_through) {
    const double away = seconds_since(last_awake_);
    if (away > spec_.heartbeat_timeout)
      throw FarmFailure{"this director was stopped for " + seconds_text(std::round(away)) +
                        ", longer than heartbeat_timeout (" + seconds_text(spec_.heartbeat_timeout) +
                        "): its actors took it for dead"};
    supervisor_.forgive_silence(Clock::now());
  }
  last_awake_ = Clock::now();
}

// Ctrl-Z. Remote actors cannot be stopped: a pause longer than heartbeat_timeout loses them (pools recover;
// docs/lua-api.md).
void ControlLoop::suspend_farm() {
  const auto stopped_at = Clock::now();
  launchers_.pause_all(true);
  // SIGSTOP, not SIGTSTP re-raised: the kernel discards a default-action SIGTSTP in an orphaned process group (a
  // farm started from a script or a service), which would leave the actors stopped and the director running.
  ::raise(SIGSTOP);  // stops here until SIGCONT
  launchers_.pause_all(false);
  take_resumed();  // that SIGCONT was this pause's
  const double paused = seconds_since(stopped_at);
  if (paused > spec_.heartbeat_timeout && launchers_.any_remote())
    log_warn("the farm was suspended for " + seconds_text(std::round(paused)) +
             "; actors on other hosts cannot be, and may have taken the director for dead");
  supervisor_.forgive_silence(Clock::now());
}

}  // namespace lf
