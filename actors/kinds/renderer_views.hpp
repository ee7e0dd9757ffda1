#pragma once
// A renderer's views of a job's frames: the latest PHASE frame's (CONFIG's before any) and, while frames are in
// flight, the last frame's too, for its tiles still to come (one a lost renderer gave back). A tile keeps the view
// it began with, so a PHASE frame never changes a tile under way.
#include <memory>
#include <optional>

#include "core/specs.hpp"
#include "render/scene/scene.hpp"
#include "render/shading/emitter_edges.hpp"
#include "render/tracing/camera.hpp"

namespace lf {

// A frame's view: its camera, its pixels on a light's outline, and its frame's number (none outside a job).
struct RendererView {
  Camera camera;
  EmitterEdges edges;
  std::optional<int> frame;
};

class RendererViews {
 public:
  // `frame`'s view (none: CONFIG's, outside a job) becomes the latest; `in_flight`: the one it follows stays for
  // the tiles that name its frame.
  void take(const Scene& scene, const CameraSpec& spec, const ImageSpec& image, std::optional<int> frame, bool in_flight) {
    earlier_ = in_flight ? latest_ : nullptr;
    const Camera camera(spec, image.width, image.height);
    latest_ = std::make_shared<const RendererView>(RendererView{camera, emitter_edges(scene, camera, image), frame});
  }
  // The view of a tile that names `frame` (the frame before, in flight), else the latest.
  std::shared_ptr<const RendererView> for_tile(std::optional<int> frame) const {
    return earlier_ && frame && earlier_->frame == frame ? earlier_ : latest_;
  }

 private:
  std::shared_ptr<const RendererView> latest_, earlier_;
};

}  // namespace lf
