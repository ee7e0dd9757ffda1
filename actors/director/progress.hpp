#pragma once
// The render's progress: a live bar on a terminal (tiles, samples per second, ETA), plain lines at every tenth
// otherwise (logs, CI), nothing when quiet.
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace lf {

class Progress {
 public:
  Progress(bool terminal, bool quiet, size_t total_tiles, uint64_t samples_per_tile);
  void update(size_t done, double elapsed_seconds, bool force = false);
  // True while the bar owns the terminal's current line (an error message then starts on a new one).
  bool drawing() const { return terminal_ && !finished_; }

 private:
  bool terminal_;
  bool quiet_;
  size_t total_;
  uint64_t per_tile_;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  size_t last_tenth_ = 0;
  bool finished_ = false;
};

}  // namespace lf
