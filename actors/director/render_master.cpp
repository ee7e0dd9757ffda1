#include "actors/director/render_master.hpp"

#include <algorithm>

namespace lf {

// Interleaves the bits of x and y: tiles close in Morton order are close on screen, so consecutive tiles share
// geometry and lighting data (Jansen & Reinhard's access coherence).
static uint64_t morton(uint32_t x, uint32_t y) {
  uint64_t code = 0;
  for (int b = 0; b < 16; ++b) code |= (uint64_t{(x >> b) & 1u} << (2 * b)) | (uint64_t{(y >> b) & 1u} << (2 * b + 1));
  return code;
}

RenderMaster::RenderMaster(int width, int height, int tile_size)
    : tiles_(make_tiles(width, height, tile_size)), done_(tiles_.size(), false), film_(width, height) {
  std::vector<uint64_t> order(tiles_.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](uint64_t i) {
    return morton(static_cast<uint32_t>(tiles_[i].x0 / tile_size), static_cast<uint32_t>(tiles_[i].y0 / tile_size));
  };
  std::sort(order.begin(), order.end(), [&](uint64_t a, uint64_t b) { return key(a) < key(b); });
  // unassigned_ is a stack: push in reverse so the first in Morton order is handed out first.
  unassigned_.assign(order.rbegin(), order.rend());
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
  if (rgb.size() != static_cast<size_t>(3 * tiles_[id].pixel_count())) return Outcome::wrong_size;
  place(id, rgb);
  holder_.erase(it);
  return Outcome::accepted;
}

bool RenderMaster::restore(uint64_t id, std::span<const float> rgb) {
  if (id >= tiles_.size() || done_[id] || rgb.size() != static_cast<size_t>(3 * tiles_[id].pixel_count())) return false;
  place(id, rgb);
  return true;
}

void RenderMaster::place(uint64_t id, std::span<const float> rgb) {
  const TileRect& r = tiles_[id];
  size_t i = 0;
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x, i += 3) film_.at(x, y) = {rgb[i], rgb[i + 1], rgb[i + 2]};
  done_[id] = true;
  ++done_count_;
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
