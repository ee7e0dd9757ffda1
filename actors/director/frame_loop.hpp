#pragma once
// The director's render stage as a sequence of frames: the farm's one frame, or a job's frames in turn over the
// one farm (launched, shipped and set up once, seen from the job's first frame). Before each other frame it sends
// PHASE frame {frame, camera}: each actor takes the new view and redoes only the setup that depends on it
// (LightOp::setup_sees_camera: a new op for the view, or the op's setup extended to it, LightOp::carries_views);
// the rest is kept. So frame k's image is a pure function of the job and k: the same on any layout, and whether
// the job ran in one go or resumed: where an op carries its setup over the views, the views of frames a run skips
// (done, or not chosen by --frames) are replayed (PHASE frame and setup, no render) so that it holds what the
// uninterrupted job's held. Where nothing is carried and no kept setup asked an op that sees the camera (a photon
// map, an area-placed cache over ops that do not learn from the view) it is also what a farm of frame k alone
// renders. Each frame is written as soon as it is complete and recorded in the job's record (JobRecord),
// which a later run of the same job reads to skip the frames done; the frame in progress resumes from its film
// checkpoint (FilmCheckpoint).
// Frames in flight: while frame k's last tiles are out (NextViewTiming), frame k+1's view goes out (PHASE frame
// with in_flight = k, and setup) and its tiles follow k's, while k's last tiles still render; k is written when its
// last tile lands. The actors answer k's requests as before meanwhile (each request names its frame), so the images
// are those of one frame at a time. Where the farm cannot (see flies()), the frames go one at a time.
#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "actors/director/carried_setups.hpp"
#include "actors/director/director.hpp"
#include "actors/director/exchange_service.hpp"
#include "actors/director/job_record.hpp"
#include "actors/director/next_view_timing.hpp"
#include "actors/director/report.hpp"
#include "actors/director/tile_service.hpp"
#include "farm/farm_spec.hpp"
#include "transport/protocol.hpp"

namespace lf {

// What the frame loop asks of the director.
struct FrameStages {
  // PHASE to every actor. Frame and setup then wait for every READY; render does not (render_until does).
  std::function<void(wire::Phase, Value::Map)> run_phase;
  // Turns the farm's loop while it renders, until `done` (a render that makes no progress says so now and then).
  std::function<void(const std::function<bool()>&)> render_until;
  // Waits for every renderer's READY render: no tile is left.
  std::function<void()> end_render;
};

class FrameLoop {
 public:
  // `exchange` and `out`: where a resumed job's kept setups are published for the actors that restore them.
  FrameLoop(FarmSpec& spec, TileService& tiles, ExchangeService& exchange, Outbox& out, const RunOptions& options);
  // The service that keeps a job's carried setups (REQUEST keep_setup), for the director to route to.
  Service& carried_setups() { return carried_; }

  // With the scene's content hash known: which frames are left (a job skips those its record says are done and
  // whose files are unchanged), the first of them begun in the tile service, and its camera made the farm's
  // (spec.camera, what every actor's CONFIG says).
  void prepare(const std::string& scene_hash);
  bool nothing_left() const { return left_.empty(); }

  // Renders every frame left; throws FarmFailure when a frame cannot be finished or written.
  void run(const FrameStages& stages);
  // A job's progress for the monitor: {frames_total, frames_done, frame (the oldest not written), frames_in_flight
  // (rendering: 1, or 2 while the next began beside it), frame_seconds (the mean of the frames after the first, else
  // the first's; a frame's time runs from the image before it), eta_seconds}, given how much of the current frame is done (0..1); nil for
  // a farm of one frame.
  Value status(double current_done) const;

  // A job's figures in the run's report: each frame rendered (PHASE frame, or the render's start, to its image
  // written; replays included), the frames the record had done, the seconds spent replaying the views of frames
  // not rendered; the render's seconds are every frame's.
  void add_figures(RunFigures& f) const;

 private:
  struct Left {
    FrameSpec frame;
    size_t index = 0;  // in spec.frames
    std::string key;
  };
  // PHASE frame and PHASE setup: the farm takes frame `f`'s view (`replay`: to extend carried setups, no render;
  // `new_materials`: the job's materials change at `f`, and every actor sets up anew).
  void switch_view(const FrameSpec& f, bool replay, const std::function<void(wire::Phase, Value::Map)>& run_phase,
                   bool new_materials = false, std::optional<int> in_flight = std::nullopt);
  // The newest frame (index in spec.frames) at or before `index` where the job's materials change (0: none).
  size_t materials_change(size_t index) const;
  // Before frame spec.frames[before] when the farm holds spec.frames[holds]'s view: the newest frame after `holds`,
  // up to `before` itself, whose carried setups are all kept is restored (PHASE frame with restore, and setup), and
  // the views after it replayed. True: `before`'s own view was restored (the farm holds it, set up).
  bool catch_up(size_t holds, size_t before, const std::function<void(wire::Phase, Value::Map)>& run_phase);
  // Whether left_[i + 1] may begin while left_[i] renders: the job's next frame with the same materials, on a farm
  // whose every actor answers two views at once (flyable_), with no preview or time limit.
  bool flies(size_t i) const;
  // A frame's image is complete and written: its figures, its line, the job's record.
  void written(const Left& f, double seconds);
  bool flyable_ = false;
  NextViewTiming next_view_;
  bool two_in_flight_ = false;  // the next frame began beside the one not yet written
  size_t begun_in_flight_ = 0;  // frames that began beside the one before
  // The number each tile and request names a job's frame by (none for a farm of one frame).
  std::optional<int> frame_number(const Left& f) const { return record_ ? std::optional(f.frame.number) : std::nullopt; }
  std::optional<std::chrono::steady_clock::time_point> last_written_;
  FarmSpec& spec_;
  TileService& tiles_;
  ExchangeService& exchange_;
  Outbox& out_;
  CarriedSetups carried_;
  std::vector<std::string> carrying_;  // the actors (processes) whose setups are carried over the views (a job's only)
  // An op carries its setup over the views: frames skipped are restored or replayed, views kept.
  bool any_carried() const { return !carrying_.empty(); }
  const RunOptions& options_;
  std::optional<JobRecord> record_;  // a job's (frames { }); none for a farm of one frame
  std::vector<Left> left_;
  size_t skipped_ = 0, written_ = 0;
  double replay_seconds_ = 0, restore_seconds_ = 0;
  std::vector<std::string> asked_by_carried_;  // the actors a carried setup may ask: they set up for a replayed view too
  struct FrameFigures {
    int number = 0;
    double seconds = 0;
    std::string output;
    int samples = 0;  // a pixel's: spp, or a time-limited frame's passes times spp
  };
  std::vector<FrameFigures> figures_;
};

}  // namespace lf
