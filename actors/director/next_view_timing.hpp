#pragma once
// When a frame in flight sends the next frame's view. The switch (PHASE frame, setup, render: each awaited) keeps
// the ops busy with the next view's setup, while the renderers have only this frame's tiles still out to work on;
// sent once the last tile is out, its waits left cores idle at every frame of a job (Lost Empire's walk: 0.2-0.35 of
// two cores for about half a second at each of 23 switches). So the view goes out while this frame still has as
// many tiles to hand out as the renderers take in the time the last switch took, at the rate they have taken this
// frame's: the farm's own figures, nothing tuned on a scene. The job's first switch has none to go by and waits for
// the last tile to be out. The images are the same either way: tiles and requests name their frame.
#include <cstddef>

namespace lf {

class NextViewTiming {
 public:
  // `left`: this frame's tiles not yet handed out; `handed_out`: those that were, over `seconds` since its tiles
  // began to go out.
  bool due(size_t left, size_t handed_out, double seconds) const {
    if (left == 0) return true;
    if (last_switch_seconds_ <= 0 || handed_out == 0 || seconds <= 0) return false;
    return static_cast<double>(left) <= static_cast<double>(handed_out) / seconds * last_switch_seconds_;
  }
  void switched(double seconds) { last_switch_seconds_ = seconds; }

 private:
  double last_switch_seconds_ = 0;
};

}  // namespace lf
