#pragma once
// One turn of the director's loop: wait for control messages (at most a quarter of the heartbeat timeout), hand
// them and the processes that ended to the supervisor, check and send heartbeats. It also watches for the director
// itself being paused: by Ctrl-Z (it stops this machine's actors, then itself, and continues them on `fg`), or from
// outside (SIGSTOP, a debugger), which it learns of only when it runs again. The time spent stopped must not count
// as the actors' silence; a stop from outside longer than the heartbeat timeout ends the farm saying so, since the
// actors took the director for dead and are going.
#include <functional>

#include "actors/director/control_channel.hpp"
#include "actors/launchers/launcher.hpp"
#include "actors/director/supervisor.hpp"

namespace lf {

class ControlLoop {
 public:
  using Route = std::function<void(SupervisorEvent&)>;
  // `route`: where the supervisor's events go, each as soon as the supervisor has judged what produced it.
  ControlLoop(const FarmSpec& spec, ControlChannel& control, Supervisor& supervisor, Launchers& launchers, Route route)
      : spec_(spec), control_(control), supervisor_(supervisor), launchers_(launchers), route_(std::move(route)) {}
  // Waits up to `timeout_ms` and handles what came. Throws FarmFailure (a signal, an actor's failure, a long stop).
  void turn(long timeout_ms);

 private:
  void read_messages();
  void judged(const Status& st);  // check(st), then route what the supervisor said
  void suspend_farm();
  // `slept_through`: a wait just returned far later than its timeout (the SIGCONT handler may run on another
  // thread and set its flag a moment after this one looked; the overrun says the same without that race).
  void notice_outside_stop(bool slept_through = false);

  const FarmSpec& spec_;
  ControlChannel& control_;
  Supervisor& supervisor_;
  Launchers& launchers_;
  Route route_;
  Clock::time_point last_awake_ = Clock::now();  // the last time notice_outside_stop() ran
};

}  // namespace lf
