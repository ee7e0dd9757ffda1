#include "actors/kinds/tile_plan.hpp"

#include <algorithm>

namespace lf {
namespace {

// The points regrouped by part: plan.order, each group's end (in sending order) and part, and per pixel whether
// its points lie in more than one part.
void group_by_part(const TileWork& work, std::span<const uint32_t> sample_part, size_t parts, TilePlan& plan,
                   std::vector<size_t>& group_end, std::vector<int64_t>& group_part, std::vector<uint8_t>& split_pixel) {
  const size_t n = work.points.size();
  std::vector<uint32_t> part(n);
  std::vector<size_t> count(parts + 1, 0);
  for (size_t i = 0; i < n; ++i) {
    part[i] = std::min<uint32_t>(sample_part[work.sample_of_point[i]], static_cast<uint32_t>(parts));
    ++count[part[i]];
  }
  std::vector<size_t> next(parts + 1, 0);
  group_end.clear();
  group_part.clear();
  for (size_t k = 0, at = 0; k <= parts; ++k) {
    next[k] = at;
    at += count[k];
    if (count[k] == 0) continue;
    group_end.push_back(at);
    group_part.push_back(k < parts ? static_cast<int64_t>(k) : -1);
  }
  plan.order.resize(n);
  for (size_t i = 0; i < n; ++i) plan.order[next[part[i]]++] = static_cast<uint32_t>(i);
  // A pixel's points are consecutive in point order; in another part's group they may come back later.
  const uint32_t spp = static_cast<uint32_t>(work.spp);
  std::vector<int64_t> seen_in(plan.pixel_count, -1);
  split_pixel.assign(plan.pixel_count, 0);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t px = work.sample_of_point[i] / spp;
    if (seen_in[px] >= 0 && seen_in[px] != part[i]) split_pixel[px] = 1;
    seen_in[px] = part[i];
  }
}

}  // namespace

TilePlan plan_batches(const TileWork& work, std::span<const uint32_t> sample_part, const BatchOptions& options) {
  TilePlan plan;
  const size_t n = work.points.size();
  plan.point_count = n;
  plan.pixel_count = static_cast<size_t>(work.rect.pixel_count());
  plan.folding = options.fold;
  std::vector<size_t> group_end{n};
  std::vector<int64_t> group_part{-1};
  std::vector<uint8_t> split_pixel;
  if (options.parts > 0 && n > 0) group_by_part(work, sample_part, options.parts, plan, group_end, group_part, split_pixel);
  if (n == 0) return plan;
  const size_t batch = std::max<size_t>(options.batch, 1);
  std::vector<uint8_t> unfoldable;
  if (options.fold) {
    const uint32_t spp = static_cast<uint32_t>(work.spp);
    plan.pixel.resize(n);
    for (size_t j = 0; j < n; ++j)
      plan.pixel[j] = work.sample_of_point[plan.order.empty() ? j : plan.order[j]] / spp;
    unfoldable.resize(plan.pixel_count);
    for (size_t p = 0; p < unfoldable.size(); ++p)
      unfoldable[p] = pixel_sees_emitter(work, p) || (!split_pixel.empty() && split_pixel[p]);
  }
  const std::vector<uint32_t>& pixel = plan.pixel;
  for (size_t g = 0, begin = 0; g < group_end.size(); ++g) {
    for (size_t end = begin; begin < group_end[g]; begin = end) {
      end = std::min(begin + batch, group_end[g]);
      while (options.fold && end < group_end[g] && pixel[end] == pixel[end - 1]) ++end;
      Batch b{.begin = begin, .end = end, .part = group_part[g], .foldable = options.fold};
      for (size_t j = begin; options.fold && j < end; ++j)
        if (j == begin || pixel[j] != pixel[j - 1]) {
          ++b.pixels;
          b.foldable = b.foldable && !unfoldable[pixel[j]];
        }
      plan.batches.push_back(b);
    }
  }
  return plan;
}

TileRadiance::TileRadiance(const TilePlan& plan)
    : point(plan.point_count), pixel(plan.folding ? plan.pixel_count : 0), folded(plan.folding ? plan.pixel_count : 0) {}

void scatter_reply(const TilePlan& plan, const Batch& b, bool folded, std::span<const RGB> reply, TileRadiance& out) {
  if (!folded) {
    for (size_t j = b.begin; j < b.end; ++j) out.point[plan.order.empty() ? j : plan.order[j]] = reply[j - b.begin];
    return;
  }
  const auto& pixel = plan.pixel;
  for (size_t j = b.begin, run = 0; j < b.end; ++j)
    if (j == b.begin || pixel[j] != pixel[j - 1]) {
      out.pixel[pixel[j]] = reply[run++];
      out.folded[pixel[j]] = 1;
    }
}

}  // namespace lf
