#pragma once
// The director (Session + NetManager, DESIGN §1): validates a FarmSpec, launches its actors, waits for every HELLO,
// configures them with their peers' endpoints, drives the phases launch -> hello -> configure -> setup -> render
// -> finish, hosts the render master and the film, collects stats, and shuts everything down. Whatever happens
// (an actor crash, a bad HELLO, Ctrl-C), it returns only after every actor process is gone.
#include <string>

#include "core/farm_spec.hpp"

namespace lf {

struct RunOptions {
  bool progress_on_terminal = false;  // a live bar on stderr; otherwise plain lines
  std::string stats_json;             // write figures here as JSON, if set
  bool quiet = false;                 // no tables (benchmarks)
};

// Returns the process exit status: 0 on success, 1 if the farm failed, 128+signal if interrupted.
int run_farm(const FarmSpec& spec, const RunOptions& options);

}  // namespace lf
