#pragma once
// How a renderer cuts a tile's shading points into shade requests, and puts the replies back: a pure plan, apart
// from the actor that sends it. Three things shape it:
// - batches of at most `batch` points (a request's size);
// - folding: a lean input may sum a pixel's radiance itself and reply one value a pixel (fold_by_pixel), so a
//   batch then ends between pixels, and a batch with a pixel that must not be folded (it sees an emitter, whose
//   emission is summed with its samples, or its points lie in two parts and come back in two replies) is not;
// - parts: a pool whose replicas hold scene parts gets each part's points apart, grouped by the part their camera
//   ray's hit was found in (in point order within a part), so the points are sent in another order.
// The scatter puts each reply's values back in point order (or a folded pixel's sum by pixel), so the pixels sum
// exactly what they would have unsent: the image is the same whatever the plan.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "render/shading/tile_kernel.hpp"

namespace lf {

struct BatchOptions {
  size_t batch = 1;    // points a request, at most (a folding batch runs on to its last pixel's end)
  bool fold = false;   // batches may be folded: end them between pixels
  size_t parts = 0;    // when > 0: group the points by part (`sample_part`, one entry a camera sample)
};

struct Batch {
  size_t begin = 0, end = 0;  // points [begin, end) in sending order
  int64_t part = -1;          // the scene part a replica answering it must hold; -1: any replica
  bool foldable = false;      // whole pixels, none of which must be left unfolded
  size_t pixels = 0;          // runs of one pixel's points in it: the values a folded reply holds (when folding)
};

struct TilePlan {
  std::vector<uint32_t> order;  // each sent point's index in the tile's points; empty: sent in point order
  std::vector<uint32_t> pixel;  // when folding: each sent point's pixel in the tile
  std::vector<Batch> batches;
  size_t point_count = 0, pixel_count = 0;
  bool folding = false;
  // The values a batch's reply holds: one a pixel when it was sent folded, else one a point.
  size_t reply_size(const Batch& b, bool folded) const { return folded ? b.pixels : b.end - b.begin; }
};

// `sample_part`: with options.parts > 0, the part each camera sample's hit was found in (>= parts: none, grouped
// last, sent to any replica).
TilePlan plan_batches(const TileWork& work, std::span<const uint32_t> sample_part, const BatchOptions& options);

// A tile's radiance as its replies come in: one value a point in point order, and the sum of a pixel's points
// where it came folded.
struct TileRadiance {
  std::vector<RGB> point;
  std::vector<RGB> pixel;
  std::vector<uint8_t> folded;
  explicit TileRadiance(const TilePlan& plan = {});
};

// Puts batch `b`'s reply (`folded`: sent asking for one value a pixel) where it belongs.
void scatter_reply(const TilePlan& plan, const Batch& b, bool folded, std::span<const RGB> reply, TileRadiance& out);

}  // namespace lf
