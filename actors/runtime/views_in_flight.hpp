#pragma once
// A job's frames in flight, as an actor that runs op code sees them: the last frame's requests are still answered
// while the next frame's view is set up and asked. Ops read the view through one Camera (SceneContext::camera)
// the actor owns. It holds the view of whichever request's or setup's code runs: set when that code starts, and
// again whenever it resumes after waiting (GatherState::before_resume), since one thread runs all of it and
// another view's code may have run meanwhile. Views are named by their frame's number, as requests name them.
#include <functional>
#include <optional>

#include "render/tracing/camera.hpp"

namespace lf {

class ViewsInFlight {
 public:
  // `active` shows CONFIG's view, that of `frame` (a job's first; none outside a job).
  ViewsInFlight(Camera& active, std::optional<int> frame) : active_(active), latest_(active), earlier_(active),
                                                            latest_frame_(frame) {}

  // PHASE frame: `frame`, seen by `camera`, is the latest view. `in_flight`: the view it follows, that frame's,
  // stays as the earlier view for the requests that name it; otherwise no earlier view remains.
  void take(int frame, const Camera& camera, std::optional<int> in_flight) {
    if (in_flight) earlier_ = latest_;
    earlier_frame_ = in_flight;
    latest_ = camera;
    latest_frame_ = frame;
    enter(frame);
  }
  // Whether a request that names `view` is for the earlier view (its frame still rendering).
  bool is_earlier(std::optional<int> view) const { return view && earlier_frame_ && *view == *earlier_frame_; }
  // The code about to run (or resume) is for `view`'s frame: the earlier view's, else the latest.
  void enter(std::optional<int> view) {
    earlier_active_ = is_earlier(view);
    active_ = earlier_active_ ? earlier_ : latest_;
  }
  void enter_latest() { enter(latest_frame_); }
  // For a coroutine about to wait: what gives it its view back before it resumes.
  std::function<void()> restorer() {
    return [this, view = active_frame()] { enter(view); };
  }
  // The frame whose view the running code is for, which the requests it sends name (none outside a job).
  std::optional<int> active_frame() const { return earlier_active_ ? earlier_frame_ : latest_frame_; }

 private:
  Camera& active_;
  Camera latest_, earlier_;
  std::optional<int> latest_frame_, earlier_frame_;
  bool earlier_active_ = false;
};

}  // namespace lf
