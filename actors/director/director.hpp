#pragma once
// The director (the Session and NetManager of Kipfer, "Distributed Lighting Networks", 1999): a phase sequencer. It runs the stages
//   prepare -> launch -> hello -> configure -> setup -> render -> finish
// over the parts around it: the Supervisor (actor table, heartbeats, exits, losses; launchers per host) and the
// services registered by operation (TileService: render master and film; ExchangeService: all-gather and fetch;
// RingService: the radiosity ring). It owns the control socket and routes each REQUEST to the service that
// serves its operation. Whatever happens (an actor crash, a bad HELLO, Ctrl-C), it returns only after every actor
// process is gone.
#include <string>

#include "farm/farm_spec.hpp"

namespace lf {

struct RunOptions {
  bool progress_on_terminal = false;  // a live bar on stderr; otherwise plain lines
  std::string stats_json;             // write figures here as JSON, if set
  bool quiet = false;                 // no tables (benchmarks)
  std::string monitor;                // "[ADDR:]PORT": serve the live monitor there (actors/monitor/monitor.hpp)
  double monitor_hold = 0;            // seconds the monitor stays up after the frame
  // The frame's finished tiles go to OUTPUT.lfresume at most this often (actors/director/film_checkpoint.hpp); a
  // later run of the same frame resumes from them. 0: no checkpoint.
  double checkpoint_every = 30;
  bool restart = false;               // ignore (and replace) OUTPUT.lfresume and a job's record
  // The frame's partial image (unfinished tiles black) to OUTPUT's STEM.preview.EXT at most this often while it
  // renders, removed once the frame is written. 0: none.
  double preview_every = 0;
};

// Returns the process exit status: 0 on success, 1 if the farm failed, 2 for a fault of the script or command line
// found before anything started, 128+signal if interrupted.
int run_farm(const FarmSpec& spec, const RunOptions& options);
// The same over launchers the caller holds (a test's fakes: director.test.cpp).
class Launchers;
int run_farm(const FarmSpec& spec, const RunOptions& options, Launchers& launchers);

}  // namespace lf
