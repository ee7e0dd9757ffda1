#include "actors/render_master.hpp"

namespace lf {

RenderMaster::RenderMaster(int width, int height, int tile_size)
    : tiles_(make_tiles(width, height, tile_size)), done_(tiles_.size(), false), film_(width, height) {
  for (size_t i = tiles_.size(); i-- > 0;) unassigned_.push_back(i);
}

std::optional<RenderMaster::Assignment> RenderMaster::next(const std::string& worker) {
  while (!unassigned_.empty()) {
    uint64_t id = unassigned_.back();
    unassigned_.pop_back();
    if (done_[id]) continue;
    holder_[id] = worker;
    return Assignment{id, tiles_[id]};
  }
  return std::nullopt;
}

RenderMaster::Outcome RenderMaster::complete(const std::string& worker, uint64_t id, std::span<const float> rgb) {
  if (id >= tiles_.size()) return Outcome::unknown_tile;
  if (done_[id]) return Outcome::already_done;
  auto it = holder_.find(id);
  if (it == holder_.end() || it->second != worker) return Outcome::not_holder;
  const TileRect& r = tiles_[id];
  if (rgb.size() != static_cast<size_t>(3 * r.pixel_count())) return Outcome::wrong_size;
  size_t i = 0;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x, i += 3) film_.at(x, y) = {rgb[i], rgb[i + 1], rgb[i + 2]};
  done_[id] = true;
  holder_.erase(it);
  ++done_count_;
  return Outcome::accepted;
}

size_t RenderMaster::release(const std::string& worker) {
  size_t n = 0;
  for (auto it = holder_.begin(); it != holder_.end();) {
    if (it->second == worker) {
      unassigned_.push_back(it->first);
      it = holder_.erase(it);
      ++n;
    } else {
      ++it;
    }
  }
  return n;
}

const char* RenderMaster::describe(Outcome o) {
  switch (o) {
    case Outcome::accepted: return "accepted";
    case Outcome::not_holder: return "the tile is not assigned to this renderer";
    case Outcome::already_done: return "the tile is already done";
    case Outcome::unknown_tile: return "no such tile";
    case Outcome::wrong_size: return "the pixel count does not match the tile";
  }
  return "?";
}

}  // namespace lf
