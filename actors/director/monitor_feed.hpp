#pragma once
// What the live monitor shows (docs/monitor.md), built on the director's thread from the actor table, the tile
// service, the ring service and the farm's timeline, and handed to the Monitor as a copy: the state at least once a
// second, the preview when tiles have landed, the log as typed lines (LogKind), setup steps' progress.
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "actors/monitor/monitor.hpp"
#include "actors/director/ring_service.hpp"
#include "actors/director/supervisor.hpp"
#include "actors/director/tile_service.hpp"
#include "core/log.hpp"

namespace lf {

class FrameLoop;

// The farm's stages as they pass: when it began, each finished stage's seconds, and whether the image is written.
struct FarmTimeline {
  Clock::time_point start = Clock::now();
  std::vector<std::pair<std::string, double>> stage_seconds;  // in order
  std::vector<double> stage_cpu_seconds;  // the director's CPU (all its threads) in each, same order
  bool image_written = false;
  double seconds() const { return std::chrono::duration<double>(Clock::now() - start).count(); }
};

class MonitorFeed {
 public:
  // Serves the monitor at `address` ("[ADDR:]PORT") and keeps the director's log lines for it until destroyed.
  static Result<std::unique_ptr<MonitorFeed>> start(const std::string& address, const FarmSpec& spec,
                                                    const Supervisor& supervisor, const TileService& tiles,
                                                    const RingService& ring, const FarmTimeline& timeline,
                                                    const FrameLoop& frames);
  ~MonitorFeed();
  std::string url() const { return monitor_->url(); }

  // A setup step's progress (photons, a cache's pre-pass) as an actor reports it.
  void on_progress(const std::string& actor, const std::string& what, uint64_t done, uint64_t total);
  // From the director's loop: notes when tiles land and publishes at most once a second (`now`: at once, as when a
  // stage begins).
  void update(bool now);
  // After the frame: the final figures, kept up for `seconds` (Ctrl-C ends the wait).
  void hold(double seconds, bool quiet, int status);

 private:
  MonitorFeed(std::unique_ptr<Monitor> monitor, const FarmSpec& spec, const Supervisor& supervisor,
              const TileService& tiles, const RingService& ring, const FarmTimeline& timeline, const FrameLoop& frames);
  void keep_log_line(const std::string& level, const std::string& text, LogKind kind);
  std::string actor_state(const ActorRecord& a) const;
  Value actor_entry(const ActorSpec& spec, const Value::Array& parts);
  Value state();
  void publish(bool now);
  void publish_preview(bool notify = true);

  std::unique_ptr<Monitor> monitor_;
  const FarmSpec& spec_;
  const Supervisor& supervisor_;
  const TileService& tiles_;
  const RingService& ring_;
  const FarmTimeline& timeline_;
  const FrameLoop& frames_;
  std::map<std::string, Value> progress_;  // actor + step -> {actor, what, done, total}
  std::map<std::string, std::tuple<Value, Clock::time_point, Value>> live_before_;  // figures, when, rates
  std::mutex log_mutex_;  // lines may be logged on other threads (hosts connecting)
  std::deque<Value::Map> log_lines_;
  Clock::time_point published_{};
  size_t preview_tiles_ = SIZE_MAX, tiles_seen_ = 0;
  int64_t tile_landed_ms_ = 0;     // Unix time of the latest tile's arrival
  int64_t oldest_unshown_ms_ = 0;  // of the first tile that landed since the last preview (0: none)
};

}  // namespace lf
