#pragma once
// RenderMaster: hands out tiles on demand and takes results back. It remembers who holds each tile and accepts
// a result only from that holder and only once (a tile handed out again after a loss may come back twice), so a
// late or repeated answer cannot overwrite or double-count. Pure logic: the director feeds it requests; tests feed it without processes.
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "render/images/image.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {

class RenderMaster {
 public:
  RenderMaster(int width, int height, int tile_size);

  struct Assignment {
    uint64_t id;
    TileRect rect;
  };
  // The next unassigned tile for `worker`, or nullopt when every tile is assigned or done.
  std::optional<Assignment> next(const std::string& worker);

  enum class Outcome { accepted, not_holder, already_done, unknown_tile, wrong_size };
  Outcome complete(const std::string& worker, uint64_t id, std::span<const float> rgb);
  // Puts every tile `worker` holds back in line (its process is gone). Returns how many.
  size_t release(const std::string& worker);
  // A tile finished by an earlier run of the same frame (FilmCheckpoint): done, with its pixels, held by nobody.
  // False for an unknown id, a tile already done or a wrong pixel count.
  bool restore(uint64_t id, std::span<const float> rgb);
  bool is_done(uint64_t id) const { return id < done_.size() && done_[static_cast<size_t>(id)]; }
  const TileRect& rect(uint64_t id) const { return tiles_[static_cast<size_t>(id)]; }

  size_t total() const { return tiles_.size(); }
  size_t unassigned() const { return unassigned_.size(); }
  size_t done() const { return done_count_; }
  // The tiles each worker holds and has not finished, by worker.
  std::map<std::string, std::vector<uint64_t>> held() const {
    std::map<std::string, std::vector<uint64_t>> out;
    for (const auto& [id, worker] : holder_)
      if (!done_[static_cast<size_t>(id)]) out[worker].push_back(id);
    return out;
  }
  bool finished() const { return done_count_ == tiles_.size(); }
  const Image& film() const { return film_; }
  static const char* describe(Outcome o);

 private:
  void place(uint64_t id, std::span<const float> rgb);  // its pixels into the film; done
  std::vector<TileRect> tiles_;
  std::vector<bool> done_;
  std::map<uint64_t, std::string> holder_;
  std::vector<uint64_t> unassigned_;  // a stack, popped from the back; filled so tile 0 goes first
  size_t done_count_ = 0;
  Image film_;
};

}  // namespace lf
