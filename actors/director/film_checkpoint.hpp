#pragma once
// FilmCheckpoint: a long frame's finished tiles on disk beside its output (OUTPUT.lfresume), so that `lightfarm
// run` again after a crash, Ctrl-C, a killed director or a reboot renders only the rest and writes the same image
// bit for bit: every tile is a pure function of its pixels, samples and seeds, whichever renderer made it and
// whenever. The file carries a key naming what the frame's pixels depend on (the scene's content, camera, image,
// lighting network; not the hosts or the number of renderers); a file with another key is another frame's and
// is left alone with a message. It is written whole to a temporary and renamed (a crash mid-write leaves the last
// one), at most once per `interval` while tiles land, and removed once the image is written.
//
// Form (native byte order): "LFRESUME1", u32 key length, key, u32 width, height, tile, u32 count, then per tile
// u64 id and its f32 RGB pixels, row by row.
#include <chrono>
#include <string>

#include "actors/director/render_master.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

class FilmCheckpoint {
 public:
  // interval_seconds <= 0: never written (nor read).
  FilmCheckpoint(std::string path, std::string key, int width, int height, int tile, double interval_seconds);

  // Marks the tiles a matching file holds done in `master`, with their pixels; returns how many. `note` says what
  // was found: nothing, another frame's file (left in place), a damaged one, or the tiles taken.
  size_t restore(RenderMaster& master, std::string& note) const;
  // Writes the finished tiles if `interval` has passed since the last write (or `now_anyway`). A failure to write is
  // a warning, once: the frame goes on.
  void save(const RenderMaster& master, bool now_anyway = false);
  // The frame's image is written: the file has served.
  void remove() const;
  const std::string& path() const { return path_; }
  bool enabled() const { return interval_ > 0; }

 private:
  std::string path_, key_;
  int width_, height_, tile_;
  double interval_;
  std::chrono::steady_clock::time_point last_save_;
  size_t saved_tiles_ = 0;
  bool warned_ = false;
};

// The key of a frame seen by `camera`: a content hash of what its pixels depend on (`scene_hash`: a file scene's
// shipped content, textures and environment map included; empty for a built-in one; `materials`: the frame's
// changes over it, FrameSpec::materials).
std::string frame_key(const FarmSpec& spec, const std::string& scene_hash, const CameraSpec& camera,
                      const Value::Array& materials = {});

}  // namespace lf
