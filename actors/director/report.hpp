#pragma once
// The end-of-run report: phase timings and the per-actor table on stderr, the "wrote" line on stdout, and the same
// figures as JSON for --stats-json.
#include <string>
#include <utility>
#include <vector>

#include "actors/director/supervisor.hpp"
#include "core/result.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

struct RunFigures {
  std::vector<std::pair<std::string, double>> stage_seconds;  // in order
  std::vector<double> stage_cpu_seconds;                        // the director's, in the same order
  double total_seconds = 0;
  double render_seconds = 0;       // a job's: every frame's, PHASE frame to image written
  double first_tile_seconds = 0;  // from the director's start
  size_t frames_rendered = 1;
  // Samples a pixel, summed over the frames rendered: each frame's spp, a time-limited frame's passes times spp
  // (0: spp times frames_rendered).
  uint64_t pixel_samples = 0;
  Value frames;                   // a job's: {frames: [{frame, seconds, output}], skipped, record}; nil for one frame
  Value radiosity;                // the ring's report, or nil
  Value scene;                    // a shipped scene: {hash, bytes, bytes_shipped: {host: bytes}}, or nil
};

void print_report(const FarmSpec& spec, const Supervisor& supervisor, const RunFigures& figures);
Status write_stats_json(const FarmSpec& spec, const Supervisor& supervisor, const RunFigures& figures,
                        const std::string& path);

}  // namespace lf
