#pragma once
// The scene an actor holds over a job's frames: the shipped one, or, for a frame that changes materials
// (frames { materials }), a copy with that frame's changes (Scene::with_material_changes). Each frame's changes are
// whole (over the shipped scene, not over the frame before), so any frame's scene is the same whichever frames this
// actor took before it. The shipped scene stays alive: what was built over it (the BVH, remote tracing) still
// serves the changed one, whose geometry it shares.
#include <memory>
#include <string>
#include <utility>

#include "core/result.hpp"
#include "core/value.hpp"
#include "render/scene/scene.hpp"

namespace lf {

class FrameScene {
 public:
  FrameScene() = default;
  explicit FrameScene(std::shared_ptr<const Scene> shipped) : shipped_(shipped), current_(std::move(shipped)) {}
  // Takes a frame's material changes: true when the scene differs from the one held before (whatever was set up
  // over it must be set up anew), false when they are the ones it holds. An error names `what` (the frame) and the
  // change the scene refuses, or a frame left without light.
  Result<bool> take(const Value::Array& materials, const std::string& what) {
    if (materials == applied_) return false;
    if (materials.empty()) {
      current_ = shipped_;
    } else {
      auto changed = shipped_->with_material_changes(materials, what);
      if (!changed) return changed.error();
      current_ = std::move(*changed);
    }
    applied_ = materials;
    return true;
  }
  const std::shared_ptr<const Scene>& scene() const { return current_; }
  // The scene as shipped, alive as long as this: what is built over its geometry (inputs' lean requests, remote
  // tracing) binds to it, never to a frame's copy, which a later frame drops.
  const Scene& shipped() const { return *shipped_; }

 private:
  std::shared_ptr<const Scene> shipped_;
  std::shared_ptr<const Scene> current_;
  Value::Array applied_;
};

}  // namespace lf
