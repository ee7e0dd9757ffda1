#include "actors/director/tile_service.hpp"

#include "actors/codecs/control_codec.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/log.hpp"
#include "render/images/image.hpp"

namespace lf {

using Clock = std::chrono::steady_clock;

TileService::TileService(const ImageSpec& image, std::vector<std::string> renderers, bool terminal, bool quiet)
    : image_(image),
      quiet_(quiet),
      renderers_(std::move(renderers)),
      master_(image.width, image.height, image.tile),
      progress_(terminal, quiet, master_.total(), static_cast<uint64_t>(image.tile) * image.tile * image.spp) {}

double TileService::render_seconds() const {
  return rendering_ ? std::chrono::duration<double>(Clock::now() - render_start_).count() : 0.0;
}

Status TileService::on_phase(wire::Phase phase, Outbox& out) {
  if (phase != wire::Phase::render) return Ok{};
  rendering_ = true;
  render_start_ = last_progress_ = pass_start_ = Clock::now();
  serve_waiting(out);
  return Ok{};
}

double TileService::seconds_since_progress() const {
  return rendering_ ? std::chrono::duration<double>(Clock::now() - last_progress_).count() : 0.0;
}

std::string TileService::stall_report(const std::string& in_flight) const {
  return "no tile has landed for " + seconds_text(std::round(seconds_since_progress())) + " (" +
         std::to_string(tiles_done()) + " of " + std::to_string(tiles_total()) + " done): " + holders() +
         "; requests " + (in_flight.empty() ? std::string("none in flight") : in_flight);
}

std::string TileService::holders() const {
  std::string text;
  for (const auto& [worker, tiles] : master_.held()) {
    text += (text.empty() ? "" : "; ") + worker + " holds tile" + (tiles.size() == 1 ? "" : "s");
    for (size_t i = 0; i < tiles.size(); ++i) text += (i ? ", " : " ") + std::to_string(tiles[i]);
  }
  if (earlier_)
    for (const auto& [worker, tiles] : earlier_->master.held())
      text += (text.empty() ? "" : "; ") + worker + " holds " + std::to_string(tiles.size()) + " of the frame before's tiles";
  if (text.empty()) text = "no renderer holds a tile";
  return text + "; " + std::to_string(waiting_.size()) + " tile request" + (waiting_.size() == 1 ? "" : "s") +
         " waiting";
}

void TileService::finish_progress() {
  progress_.update(image_.time_limit > 0 ? master_.total() : master_.done(), render_seconds(), true);
}

size_t TileService::progress_done() const {
  if (image_.time_limit <= 0) return master_.done();
  // A time-limited frame's bar is its time: the tiles' share of it spent.
  const double spent = std::min(1.0, render_seconds() / image_.time_limit);
  return std::min(master_.total() - 1, static_cast<size_t>(spent * static_cast<double>(master_.total())));
}

Status TileService::write_frame() {
  // What made the image, in the file: its samples a pixel, and a time-limited frame's passes.
  ImageNotes notes{{"lightfarm:samples", std::to_string(std::max(1, passes_) * image_.spp)}};
  if (image_.time_limit > 0) notes.emplace_back("lightfarm:passes", std::to_string(passes_));
  if (auto st = write(film(), image_.output, notes); !st) return st;
  if (image_.time_limit > 0 && !quiet_)
    log_info(image_.output + ": " + std::to_string(passes_) + " pass" + (passes_ == 1 ? "" : "es") + " of " +
             std::to_string(image_.spp) + " samples a pixel (" + std::to_string(passes_ * image_.spp) + ") in " +
             seconds_text(render_seconds()) + " of rendering (time_limit " + seconds_text(image_.time_limit) + ")");
  written_ = true;
  if (checkpoint_) checkpoint_->remove();
  if (preview_every_ > 0) {
    std::error_code ec;
    std::filesystem::remove(preview_path(image_.output), ec);
  }
  return Ok{};
}

Status TileService::write_earlier() {
  if (!earlier_) return Ok{};
  Earlier frame = std::move(*earlier_);
  earlier_.reset();
  if (auto st = write(frame.master.film(), frame.output, {{"lightfarm:samples", std::to_string(image_.spp)}}); !st) return st;
  if (frame.checkpoint) frame.checkpoint->remove();
  return Ok{};
}

Status TileService::write(const Image& film, const std::string& output, const ImageNotes& notes) {
  if (auto st = write_image(film, output, display(), notes); !st) return st;
  if (all_black(film))
    log_warn(output + ": every pixel is 0, nothing the camera sees is lit: it may look at the back of the "
             "scene's surfaces from outside or past them (`lightfarm scene FILE.obj` suggests a camera that frames "
             "the scene), or the lights may face away from what it sees");
  return Ok{};
}

std::string preview_path(const std::string& output) {
  const size_t slash = output.find_last_of('/');
  const size_t dot = output.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return output + ".preview";
  return output.substr(0, dot) + ".preview" + output.substr(dot);
}

void TileService::write_preview() {
  if (preview_every_ <= 0 || written_) return;
  const auto now = Clock::now();
  if (std::chrono::duration<double>(now - last_preview_).count() < preview_every_) return;
  last_preview_ = now;
  if (auto st = write_image(film(), preview_path(image_.output), display()); !st)
    log_warn("cannot write the preview: " + st.error().message + "; no more previews of this frame"), preview_every_ = 0;
}

void TileService::begin_frame(const std::string& output, const std::string& key, double interval, bool restart,
                              double preview_every, std::optional<int> frame, bool in_flight) {
  if (in_flight) {
    earlier_.emplace(Earlier{std::move(master_), image_.output, frame_, base_, std::move(checkpoint_)});
    base_ = base_ == 0 ? earlier_->master.total() : 0;
  } else {
    earlier_.reset();
    base_ = 0;
  }
  frame_ = frame;
  next_frame_coming_ = false;
  image_.output = output;
  preview_every_ = preview_every;
  last_preview_ = Clock::now();
  master_ = RenderMaster(image_.width, image_.height, image_.tile);
  progress_.restart();
  if (!in_flight) {
    rendering_ = false;
    waiting_.clear();  // none: every renderer said the last frame had no tile left
  }  // else still rendering: the waiting requests get this frame's tiles (serve)
  written_ = false;
  checkpoint_.reset();
  resumed_ = 0;
  passes_ = 0;
  sum_.clear();
  passes_finished_ = giving_up_ = false;
  // A time-limited frame's passes are not checkpointed: which it completes depends on the time anyway.
  if (interval <= 0 || image_.time_limit > 0) return;
  checkpoint_.emplace(output + ".lfresume", key, image_.width, image_.height, image_.tile, interval);
  if (restart) checkpoint_->remove();
  std::string note;
  resumed_ = checkpoint_->restore(master_, note);
  if (note.empty()) return;
  if (resumed_ > 0) log_info(note, LogKind::recovery);
  else log_warn(note);
}

Status TileService::on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) {
  if (op == wire::Op::tile) {
    auto count = control::decode_tile_count(body);
    if (!count) {
      out.refuse(actor, id, count.error().code, count.error().message);
      return Ok{};
    }
    waiting_.push_back({actor, id, *count});
    serve_waiting(out);
    return Ok{};
  }
  auto done = control::decode_tile_done(body);
  if (!done) {
    out.refuse(actor, id, done.error().code, done.error().message);
    return Ok{};
  }
  // Each tile of a batch counts on its own: one refused (a tile given to another after this renderer seemed lost)
  // does not lose the others' pixels.
  std::string refused;
  size_t accepted = 0;
  for (const control::FinishedTile& tile : done->tiles) {
    // Of the frame in flight before the latest, by its ids, or of the latest.
    const bool earlier = earlier_ && tile.id >= earlier_->base && tile.id - earlier_->base < earlier_->master.total();
    const auto outcome = earlier ? earlier_->master.complete(actor, tile.id - earlier_->base, tile.rgb)
                                 : master_.complete(actor, tile.id - base_, tile.rgb);
    if (earlier && earlier_->checkpoint && outcome == RenderMaster::Outcome::accepted) earlier_->checkpoint->save(earlier_->master);
    if (outcome == RenderMaster::Outcome::accepted) {
      ++accepted;
      continue;
    }
    log_warn("refused tile " + std::to_string(tile.id) + " from '" + actor + "': " + RenderMaster::describe(outcome));
    refused += (refused.empty() ? "" : "; ") +
               (done->tiles.size() == 1 ? std::string() : "tile " + std::to_string(tile.id) + ": ") +
               RenderMaster::describe(outcome);
  }
  if (!refused.empty()) {
    out.refuse(actor, id, ErrorCode::refused, refused);
    if (accepted == 0) return Ok{};
  } else if (done->next) {
    // Asked for the renderer's next tiles too: the reply is a tile request's, answered like one (it may wait).
    waiting_.push_back({actor, id, done->count});
  } else {
    out.reply(actor, id, Value::Map{});
  }
  if (giving_up_) {
    // A tile of the pass given up: dropped, unless it completes the pass after all. The frame is done once none is out.
    if (master_.finished()) add_pass();
    if (master_.held().empty()) passes_finished_ = true;
    serve_waiting(out);
    return Ok{};
  }
  if (image_.time_limit > 0 && master_.finished()) {
    pass_completed();
    serve_waiting(out);
  }
  if (checkpoint_) checkpoint_->save(master_);
  if (!master_.finished()) write_preview();
  last_progress_ = Clock::now();
  // The farm's first tile (a job's later frames keep the first frame's figure).
  if (first_tile_seconds_ == 0 && master_.done() >= resumed_ + 1) first_tile_seconds_ = render_seconds();
  progress_.update(progress_done(), render_seconds());
  if (master_.finished() || done->next) serve_waiting(out);
  return Ok{};
}

Status TileService::on_lost(const std::string& actor, const std::string& why, Outbox& out) {
  if (std::find(renderers_.begin(), renderers_.end(), actor) == renderers_.end()) return Ok{};
  std::erase_if(waiting_, [&](const Waiting& w) { return w.actor == actor; });
  const size_t tiles = master_.release(actor) + (earlier_ ? earlier_->master.release(actor) : 0);
  log_warn("renderer '" + actor + "' " + why + "; its " + std::to_string(tiles) + " tiles go to the others", LogKind::loss);
  serve_waiting(out);
  return Ok{};
}

void TileService::add_pass() {
  const Image& pass = master_.film();
  if (sum_.empty()) sum_.assign(pass.pixels.size(), RGB{});
  for (size_t i = 0; i < sum_.size(); ++i) sum_[i] += pass.pixels[i];
  ++passes_;
  mean_ = Image(pass.width, pass.height);
  const float inv = 1.0f / static_cast<float>(passes_);
  for (size_t i = 0; i < sum_.size(); ++i) mean_.pixels[i] = sum_[i] * inv;
}

void TileService::pass_completed() {
  add_pass();
  const auto now = Clock::now();
  const double pass_seconds = std::chrono::duration<double>(now - pass_start_).count();
  if (render_seconds() + pass_seconds > image_.time_limit) {
    passes_finished_ = true;  // another pass would not fit
    return;
  }
  master_ = RenderMaster(image_.width, image_.height, image_.tile);
  pass_start_ = now;
}

bool TileService::out_of_time() const {
  return image_.time_limit > 0 && passes_ > 0 && !passes_finished_ && render_seconds() > image_.time_limit;
}

// Answers waiting tile requests: tiles while tiles are free; "none left" once every tile is done.
void TileService::serve_waiting(Outbox& out) {
  if (!rendering_) return;
  if (out_of_time()) giving_up_ = true;
  if (giving_up_ && master_.held().empty()) passes_finished_ = true;
  while (!waiting_.empty()) {
    const Waiting w = waiting_.front();
    std::vector<control::Tile> tiles;
    if (!giving_up_ && !passes_finished_) {
      // Several only while every renderer could take as many of the tiles still free.
      const size_t share = std::max<size_t>(1, master_.unassigned() / std::max<size_t>(1, renderers_.size()));
      const size_t give = std::min<size_t>(static_cast<size_t>(std::max(1, w.count)), share);
      // The frame in flight before the latest first: a lost renderer's tiles of it came back.
      while (earlier_ && tiles.size() < give) {
        auto t = earlier_->master.next(w.actor);
        if (!t) break;
        tiles.push_back(control::Tile{t->id + earlier_->base, t->rect, 0, earlier_->frame});
      }
      while (tiles.size() < give) {
        auto t = master_.next(w.actor);
        if (!t) break;
        tiles.push_back(control::Tile{t->id + base_, t->rect, static_cast<uint32_t>(passes_) * static_cast<uint32_t>(image_.spp),
                                      frame_});
      }
      // Keep waiting while a tile may come back, or the next frame's tiles are to come.
      if (tiles.empty() && (!master_.finished() || next_frame_coming_ || !earlier_finished())) return;
    }
    waiting_.pop_front();
    if (w.count > 0) out.reply(w.actor, w.id, control::encode_tiles_reply(tiles));
    else out.reply(w.actor, w.id, control::encode_tile_reply(tiles.empty() ? std::nullopt : std::optional(tiles[0])));
  }
}

}  // namespace lf
