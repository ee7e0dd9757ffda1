#include "actors/director/monitor_feed.hpp"

#include "actors/director/frame_loop.hpp"

#include <algorithm>
#include <cmath>
#include <thread>

#include "actors/runtime/process.hpp"
#include "farm/builders.hpp"
#include "render/images/image.hpp"

namespace lf {

Result<std::unique_ptr<MonitorFeed>> MonitorFeed::start(const std::string& address, const FarmSpec& spec,
                                                        const Supervisor& supervisor, const TileService& tiles,
                                                        const RingService& ring, const FarmTimeline& timeline,
                                                        const FrameLoop& frames) {
  auto m = Monitor::start(address);
  if (!m) return m.error();
  std::unique_ptr<MonitorFeed> feed(new MonitorFeed(std::move(*m), spec, supervisor, tiles, ring, timeline, frames));
  set_log_observer([f = feed.get()](const std::string& level, const std::string& text, LogKind kind) {
    f->keep_log_line(level, text, kind);
  });
  log_info("monitor: " + feed->url());
  feed->update(true);
  return feed;
}

MonitorFeed::MonitorFeed(std::unique_ptr<Monitor> monitor, const FarmSpec& spec, const Supervisor& supervisor,
                         const TileService& tiles, const RingService& ring, const FarmTimeline& timeline,
                         const FrameLoop& frames)
    : monitor_(std::move(monitor)), spec_(spec), supervisor_(supervisor), tiles_(tiles), ring_(ring), timeline_(timeline),
      frames_(frames) {}

MonitorFeed::~MonitorFeed() { set_log_observer({}); }

// The page colours a line by its kind: its level (info, warning, error), or what the line is about where the code
// that logged it said so (loss, recovery).
void MonitorFeed::keep_log_line(const std::string& level, const std::string& text, LogKind kind) {
  std::string shown = level.empty() ? "info" : level.substr(0, level.find(':'));
  if (kind != LogKind::plain) shown = log_kind_name(kind);
  Value::Map line;
  line["kind"] = std::move(shown);
  line["text"] = text;
  line["seconds"] = timeline_.seconds();
  std::lock_guard<std::mutex> lock(log_mutex_);
  log_lines_.push_back(std::move(line));
  if (log_lines_.size() > 300) log_lines_.pop_front();
}

void MonitorFeed::on_progress(const std::string& actor, const std::string& what, uint64_t done, uint64_t total) {
  progress_[actor + "\n" + what] = Value::Map{{"actor", actor}, {"what", what}, {"done", static_cast<int64_t>(done)},
                                              {"total", static_cast<int64_t>(total)}};
}

std::string MonitorFeed::actor_state(const ActorRecord& a) const {
  if (!a.spec->has_process()) return "pool";  // dispatched by its clients: nothing runs under its name
  if (a.lost) return "lost";
  if (a.rejoining) return "restarting";
  if (a.exited || a.said_bye) return "done";
  if (!a.said_hello) return "launching";
  const Stage st = supervisor_.stage();
  if (st <= Stage::configure) return a.ready == wire::Phase::configure ? "ready" : "configuring";
  if (st == Stage::setup) return a.ready == wire::Phase::setup ? "ready" : "setup";
  if (st == Stage::render) return "rendering";
  return "finishing";
}

Value MonitorFeed::actor_entry(const ActorSpec& spec, const Value::Array& parts) {
  const ActorRecord& a = supervisor_.at(spec.name);
  Value::Array inputs;
  for (int i : spec.inputs) inputs.push_back(spec_.actors[static_cast<size_t>(i)].name);
  if (spec.is_renderer() && spec.inputs.empty() && spec_.lighting >= 0)
    inputs.push_back(spec_.actors[static_cast<size_t>(spec_.lighting)].name);
  Value::Map m{{"name", spec.name}, {"kind", spec.kind}, {"host", spec.host}, {"state", actor_state(a)},
               {"inputs", std::move(inputs)}, {"restarts", static_cast<int64_t>(a.restarts)}};
  if (!parts.empty() && traces_through_parts(spec)) m["rays_from"] = parts;
  if (const pid_t pid = supervisor_.host_pid(a); pid > 0) m["pid"] = static_cast<int64_t>(pid);
  if (!a.loss.empty()) m["loss"] = a.loss;
  if (a.live.is_map()) {
    m["live"] = a.live;
    // Rates over the time since the figures before these (heartbeats come about once a second).
    // Plain references, not a structured binding: clang 14 cannot capture one in the lambda below.
    auto& entry = live_before_[spec.name];
    Value& before = std::get<0>(entry);
    Clock::time_point& before_at = std::get<1>(entry);
    Value& rates = std::get<2>(entry);
    if (a.live_at != before_at) {
      if (before.is_map() && before_at != Clock::time_point{}) {
        const double dt = std::chrono::duration<double>(a.live_at - before_at).count();
        auto delta = [&](const char* k) {
          const Value *x = a.live.find(k), *y = before.find(k);
          const double xv = x && x->is_number() ? (x->is_int() ? static_cast<double>(x->as_int()) : x->as_double()) : 0;
          const double yv = y && y->is_number() ? (y->is_int() ? static_cast<double>(y->as_int()) : y->as_double()) : 0;
          return dt > 0 ? (xv - yv) / dt : 0.0;
        };
        rates = Value::Map{{"requests_per_second", delta("requests")},
                           {"points_per_second", delta("points")},
                           {"busy_share", std::min(1.0, delta("busy_seconds"))}};
      }
      before = a.live;
      before_at = a.live_at;
    }
    if (rates.is_map() && !a.stats.is_map() && !a.lost) m["rates"] = rates;  // a finished actor does nothing
  }
  if (a.stats.is_map()) {
    // Its final figures: the counters end at what the end-of-run table prints, not at the last heartbeat.
    m["stats"] = a.stats;
    Value::Map final_live;
    for (const char* k : {"requests", "points", "tiles", "busy_seconds", "bytes_in", "bytes_out"})
      if (const Value* v = a.stats.find(k)) final_live[k] = *v;
    final_live["queue"] = int64_t{0};
    m["live"] = std::move(final_live);
  }
  return m;
}

Value MonitorFeed::state() {
  const double now = timeline_.seconds();
  Value::Array actors, parts;  // parts: a partitioned scene's geometry actors
  for (const ActorSpec& g : spec_.actors)
    if (g.is_geometry()) parts.push_back(g.name);
  for (const ActorSpec& spec : spec_.actors) actors.push_back(actor_entry(spec, parts));
  Value::Array stages;
  double stages_done = 0;
  for (const auto& [name, secs] : timeline_.stage_seconds) {
    stages.push_back(Value::Map{{"name", name}, {"seconds", secs}});
    stages_done += secs;
  }
  if (!timeline_.image_written)
    stages.push_back(Value::Map{{"name", std::string(stage_name(supervisor_.stage())) + " (now)"},
                                {"seconds", now - stages_done}});
  Value::Array progress;
  for (const auto& [key, p] : progress_) progress.push_back(p);
  Value::Array log;
  {
    std::lock_guard<std::mutex> lock(log_mutex_);
    for (const Value::Map& l : log_lines_) log.push_back(l);
  }
  Value::Map farm{{"script", spec_.script},
                  {"output", tiles_.output()},
                  {"width", static_cast<int64_t>(spec_.image.width)},
                  {"height", static_cast<int64_t>(spec_.image.height)},
                  {"stage", timeline_.image_written ? std::string("done") : std::string(stage_name(supervisor_.stage()))},
                  {"elapsed_seconds", now},
                  {"tiles_done", static_cast<int64_t>(tiles_.tiles_done())},
                  {"tiles_total", static_cast<int64_t>(tiles_.tiles_total())}};
  Value::Map state{{"farm", std::move(farm)}, {"actors", std::move(actors)}, {"stages", std::move(stages)},
                   {"progress", std::move(progress)}, {"log", std::move(log)}};
  if (Value job = frames_.status(static_cast<double>(tiles_.tiles_done()) / std::max<size_t>(1, tiles_.tiles_total()));
      !job.is_nil())
    state["job"] = std::move(job);
  if (ring_.active()) {
    // The last 200 iterations' unshot power (older ones thinned out): what a progressive solution shows.
    const auto& unshot = ring_.unshot_fraction();
    Value::Array tail;
    const size_t step = std::max<size_t>(1, unshot.size() / 200);
    for (size_t i = 0; i < unshot.size(); i += step) tail.push_back(unshot[i]);
    if (!unshot.empty() && (unshot.size() - 1) % step != 0) tail.push_back(unshot.back());
    state["radiosity"] =
        Value::Map{{"iterations", static_cast<int64_t>(unshot.size())}, {"unshot_fraction", std::move(tail)}};
  }
  return state;
}

void MonitorFeed::update(bool now) {
  if (tiles_.tiles_done() != tiles_seen_) {  // when tiles landed, for the page's latency
    tiles_seen_ = tiles_.tiles_done();
    tile_landed_ms_ = std::chrono::duration_cast<std::chrono::milliseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
    if (oldest_unshown_ms_ == 0) oldest_unshown_ms_ = tile_landed_ms_;
  }
  publish(now);
}

// Once a second (and at every call with `now`): the state, and the preview when tiles have landed, as one update,
// so that a watching page wakes, lays out and paints once a second. A headless Chromium watching on the farm's
// machine took 0.082 of a core with the state twice a second and the preview apart, 0.063 so (bench/monitor_bench).
void MonitorFeed::publish(bool now) {
  const auto t = Clock::now();
  if (!now && t - published_ < std::chrono::milliseconds(1000)) return;
  published_ = t;
  if (const size_t done = tiles_.tiles_done(); done != preview_tiles_) {
    preview_tiles_ = done;
    publish_preview(/*notify=*/false);  // the state below tells the readers about both
  }
  monitor_->publish_state(state());
}

// The film so far as the output will look (exposure, tone map, sRGB), at most 400 pixels wide (a page that decodes
// and draws it once a second costs its machine CPU by the pixel).
void MonitorFeed::publish_preview(bool notify) {
  const Image& film = tiles_.film();
  const int step = std::max(1, (film.width + 399) / 400);
  const int w = std::max(1, film.width / step), h = std::max(1, film.height / step);
  const Display display{static_cast<float>(spec_.image.exposure), spec_.image.tonemap};
  std::string rgb(static_cast<size_t>(w) * h * 3, '\0');
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const RGB& p = film.at(x * step, y * step);
      for (int c = 0; c < 3; ++c)
        rgb[(static_cast<size_t>(y) * w + x) * 3 + c] =
            static_cast<char>(static_cast<unsigned char>(std::lround(255.0f * display_srgb(p[c], display))));
    }
  monitor_->publish_preview(w, h, std::move(rgb), tiles_.tiles_done(),
                            oldest_unshown_ms_ ? oldest_unshown_ms_ : tile_landed_ms_, tile_landed_ms_, notify);
  oldest_unshown_ms_ = 0;
}

void MonitorFeed::hold(double seconds, bool quiet, int status) {
  publish(true);
  publish_preview();
  if (seconds <= 0) return;
  if (!quiet)
    log_info("monitor: holding " + monitor_->url() + " for " + seconds_text(seconds) +
             (status == 0 ? "" : " (the farm failed)"));
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < until && !stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    monitor_->publish_state(state());
  }
}

}  // namespace lf
