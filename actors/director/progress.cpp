#include "actors/director/progress.hpp"

#include <cstdio>
#include <string>

#include "core/log.hpp"

namespace lf {

Progress::Progress(bool terminal, bool quiet, size_t total_tiles, uint64_t samples_per_tile)
    : terminal_(terminal && !quiet), quiet_(quiet), total_(total_tiles), per_tile_(samples_per_tile) {}

void Progress::update(size_t done, double elapsed, bool force) {
  if (terminal_) {
    const auto now = std::chrono::steady_clock::now();
    if (!force && std::chrono::duration<double>(now - last_).count() < 0.1) return;
    if (finished_) return;
    last_ = now;
    const int width = 30;
    int filled = total_ ? static_cast<int>(width * done / total_) : width;
    double rate = elapsed > 0 ? done * per_tile_ / elapsed : 0;
    double eta = done > 0 ? elapsed * (static_cast<double>(total_) - done) / done : 0;
    std::fprintf(stderr, "\r[%s%s] %zu/%zu tiles  %.2f M samples/s  ETA %.0f s   ",
                 std::string(static_cast<size_t>(filled), '#').c_str(),
                 std::string(static_cast<size_t>(width - filled), '.').c_str(), done, total_, rate / 1e6, eta);
    if (done == total_) {
      std::fprintf(stderr, "\n");
      finished_ = true;
    }
  } else if (!quiet_) {
    size_t tenth = total_ ? 10 * done / total_ : 10;
    if (tenth > last_tenth_ || (force && done == total_ && last_tenth_ < 10)) {
      last_tenth_ = tenth;
      log_info("render " + std::to_string(tenth * 10) + "% (" + std::to_string(done) + "/" + std::to_string(total_) +
               " tiles)");
    }
  }
}

void StepProgress::report(const std::string& actor, const std::string& what, uint64_t done, uint64_t total,
                          bool bar_drawing) {
  if (quiet_ || total == 0) return;
  const int quarter = static_cast<int>(4 * done / total);
  const auto now = std::chrono::steady_clock::now();
  auto [step, fresh] = shown_.try_emplace(actor + "\n" + what, Shown{now, 0});
  if (quarter <= step->second.quarter || now - step->second.first < std::chrono::seconds(1)) return;
  step->second.quarter = quarter;
  if (bar_drawing) std::fprintf(stderr, "\n");
  log_info(actor + ": " + what + " " + std::to_string(25 * quarter) + "% (" + std::to_string(done) + " of " +
           std::to_string(total) + ")");
}

}  // namespace lf
