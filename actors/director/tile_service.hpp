#pragma once
// The tile service: the render master and the film (Kipfer's MasterRenderer), its checkpoint beside the output
// and, once every tile is in, the image. Serves
//   tile       {count?}                    -> {tile: {id, x0, y0, x1, y1}} ({tiles: [...]} asked with a count), or
//                                             {} once every tile is done
//   tile_done  {id, pixels: f32[3 w h]}    -> {}; ERROR refused unless the sender holds the tile (and only once);
//              or {tiles: [...]}              ERROR bad_request for a body without id and pixels
// A request with a count gets up to that many while every renderer could still take as many; the frame's last
// tiles go one to a request, so no renderer holds two while another waits with none.
// A tile request waits while no tile is free but some are out with others (a lost renderer's tiles come back),
// and before the render phase. A lost renderer's tiles go back in line.
// A time-limited frame (image.time_limit) renders passes: once every tile of a pass is in, the pass joins the
// frame's sum and, if another pass of the last one's length still fits in the time, the tiles go out again with
// the next pass's first sample (tile.first). Past the time a pass is given up: no tile goes out, its tiles still
// out are taken and dropped, and the frame is the mean of the passes completed (at least one).
// A job's frames in flight: the next frame may begin while the last one's tiles are still out (begin_frame with
// in_flight). Its tiles then go out, the last frame's still land in its own film (tile ids of the two frames
// differ), and a tile the last frame gets back from a lost renderer goes out before the next frame's. Each tile
// says its frame (tile.frame).
#include <deque>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "actors/director/film_checkpoint.hpp"
#include "actors/director/progress.hpp"
#include "actors/director/render_master.hpp"
#include "actors/director/service.hpp"
#include "core/specs.hpp"
#include "render/images/image.hpp"

namespace lf {

// Where a frame's partial image goes: STEM.preview.EXT beside OUTPUT.
std::string preview_path(const std::string& output);

class TileService final : public Service {
 public:
  // `renderers`: the actors that ask for tiles (a loss of any other actor is not this service's concern).
  TileService(const ImageSpec& image, std::vector<std::string> renderers, bool terminal, bool quiet);
  std::vector<wire::Op> ops() const override { return {wire::Op::tile, wire::Op::tile_done}; }
  Status on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) override;
  Status on_phase(wire::Phase phase, Outbox& out) override;
  Status on_lost(const std::string& actor, const std::string& why, Outbox& out) override;

  // A frame begins (the farm's one, or each of a job's in turn): every tile to do, its image to go to `output`, and
  // its checkpoint beside it (OUTPUT.lfresume, FilmCheckpoint; `interval` <= 0: none): the tiles an earlier run of
  // the same frame (`key`, frame_key) finished are done now, said in the log, and it is written as tiles land.
  // `restart`: it is dropped first. `preview_every` > 0: the partial image goes to preview_path(output) at most
  // that often while tiles land (removed once the frame is written).
  // `frame`: the job's frame number, which each tile names. `in_flight`: the frame under way is not done; it goes on
  // beside this one (no preview or time limit then; each keeps its own checkpoint) until earlier_finished().
  void begin_frame(const std::string& output, const std::string& key, double interval, bool restart,
                   double preview_every = 0, std::optional<int> frame = std::nullopt, bool in_flight = false);
  // A job's next frame will begin in flight: a tile request this frame cannot serve waits for it, even once every
  // tile is done (renderers are not told that no tile is left).
  void expect_next_frame(bool coming) { next_frame_coming_ = coming; }
  // The frame that went on beside the latest (begin_frame in_flight): whether every tile is in, and its image
  // written (then it is gone).
  bool earlier_finished() const { return !earlier_ || earlier_->master.finished(); }
  Status write_earlier();
  // Tile requests that waited for a frame begun in flight get its tiles.
  void serve(Outbox& out) { serve_waiting(out); }
  // The farm stops early: what is done goes to the checkpoint now (nothing once the image is written).
  void save_checkpoint() {
    if (checkpoint_ && !written_) checkpoint_->save(master_, true);
    if (earlier_ && earlier_->checkpoint) earlier_->checkpoint->save(earlier_->master, true);
  }
  // Writes the finished frame to the image's output (with its exposure and tone map); the checkpoint has served
  // then. A frame whose every pixel is 0 is written with a warning naming the likely causes.
  Status write_frame();
  const std::string& output() const { return image_.output; }  // the frame's
  bool finished() const { return image_.time_limit > 0 ? passes_finished_ : master_.finished(); }
  // The frame's image: the pass being rendered, or a time-limited frame's mean of its completed passes.
  const Image& film() const { return passes_ > 0 ? mean_ : master_.film(); }
  // A time-limited frame's completed passes (0 for any other frame).
  int passes() const { return passes_; }
  size_t tiles_done() const { return master_.done(); }
  size_t tiles_total() const { return master_.total(); }
  size_t tiles_unassigned() const { return master_.unassigned(); }
  // Seconds from the render phase's start to the first finished tile, and to now.
  double first_tile_seconds() const { return first_tile_seconds_; }
  double render_seconds() const;
  // Seconds since the last tile landed (or the frame began), and who holds which unfinished tiles and how many
  // tile requests wait: what a farm that makes no progress is waiting on.
  double seconds_since_progress() const;
  std::string holders() const;
  // The warning for a frame that made no progress: how long, who holds what, and `in_flight` (the actors' requests).
  std::string stall_report(const std::string& in_flight) const;
  // Final progress line; the bar's end.
  void finish_progress();
  bool drawing_progress() const { return progress_.drawing(); }

 private:
  void serve_waiting(Outbox& out);
  // What the progress bar shows done: tiles, or a time-limited frame's share of its time (in tiles).
  size_t progress_done() const;
  // A time-limited frame's pass is complete: it joins the mean (add_pass), and the next begins if it fits in the time.
  void pass_completed();
  void add_pass();
  // Past a time-limited frame's time with a pass complete: the pass under way is given up.
  bool out_of_time() const;

  // The image (its film, with the exposure and tone map) to `output`, with `notes`.
  Status write(const Image& film, const std::string& output, const ImageNotes& notes);
  // Tile ids: the latest frame's are its master's plus base_, those of the frame in flight beside it another base.
  struct Earlier {
    RenderMaster master;
    std::string output;
    std::optional<int> frame;
    uint64_t base = 0;
    std::optional<FilmCheckpoint> checkpoint;
  };
  std::optional<Earlier> earlier_;
  uint64_t base_ = 0;
  std::optional<int> frame_;
  bool next_frame_coming_ = false;

  ImageSpec image_;  // output: the frame's
  bool quiet_ = false;
  std::vector<std::string> renderers_;
  RenderMaster master_;
  Progress progress_;
  bool rendering_ = false;
  std::chrono::steady_clock::time_point render_start_;
  double first_tile_seconds_ = 0;
  std::chrono::steady_clock::time_point last_progress_;
  // Tile requests not yet answered, oldest first, answered from the front (thousands may wait at once).
  struct Waiting {
    std::string actor;
    uint64_t id;
    int count;  // 0: the one-tile form
  };
  std::deque<Waiting> waiting_;
  bool written_ = false;
  std::optional<FilmCheckpoint> checkpoint_;
  double preview_every_ = 0;
  std::chrono::steady_clock::time_point last_preview_;
  size_t resumed_ = 0;
  // A time-limited frame: passes completed, their sum and mean, when the pass under way began, and whether the
  // frame has every pass it will get (the last given up, or none more fits).
  int passes_ = 0;
  std::vector<RGB> sum_;
  Image mean_;
  std::chrono::steady_clock::time_point pass_start_;
  bool passes_finished_ = false, giving_up_ = false;
  // The partial frame to preview_path(output), if `preview_every_` has passed since the last.
  void write_preview();
  Display display() const { return {static_cast<float>(image_.exposure), image_.tonemap}; }
};

}  // namespace lf
