#pragma once
// The render's progress: a live bar on a terminal (tiles, samples per second, ETA), plain lines at every tenth
// otherwise (logs, CI), nothing when quiet.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

namespace lf {

class Progress {
 public:
  Progress(bool terminal, bool quiet, size_t total_tiles, uint64_t samples_per_tile);
  void update(size_t done, double elapsed_seconds, bool force = false);
  // True while the bar owns the terminal's current line (an error message then starts on a new one).
  bool drawing() const { return terminal_ && !finished_; }
  // The next frame of a job: from none done.
  void restart() { *this = Progress(terminal_, quiet_, total_, per_tile_); }

 private:
  bool terminal_;
  bool quiet_;
  size_t total_;
  uint64_t per_tile_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  size_t last_tenth_ = 0;
  bool finished_ = false;
};

// A long setup step (photons, a cache's pre-pass) as it goes: a line at each quarter, per actor and step, once the
// step has taken a second (short ones say nothing).
class StepProgress {
 public:
  explicit StepProgress(bool quiet) : quiet_(quiet) {}
  // Logs the line when one is due; `bar_drawing`: the render's bar holds the terminal's line (a new one first).
  void report(const std::string& actor, const std::string& what, uint64_t done, uint64_t total, bool bar_drawing);

 private:
  struct Shown {
    std::chrono::steady_clock::time_point first;  // the step's first report
    int quarter = 0;                              // the last quarter shown
  };
  bool quiet_;
  std::map<std::string, Shown> shown_;  // actor + step
};

}  // namespace lf
