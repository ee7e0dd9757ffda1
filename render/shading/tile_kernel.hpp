#pragma once
// The renderer's per-tile kernel, apart from the host program that moves tiles around (Embree tutorials' split):
// trace the camera rays of a tile into shading points, then fold the radiance the lighting network returns into
// pixels. The renderer actor and the bare single-process benchmark both call exactly this.
#include <cstdint>
#include <span>
#include <vector>

#include "core/specs.hpp"
#include "render/shading/emitter_edges.hpp"
#include "render/tracing/camera.hpp"
#include "render/lightops/lightop.hpp"

namespace lf {

struct TileRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // half-open
  // A time-limited frame's pass (ImageSpec::time_limit): each pixel's samples are its sequence's from this index on.
  uint32_t first_sample = 0;
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  int pixel_count() const { return width() * height(); }
};

// The image's sampler (CONFIG image.sampler: "sobol", else independent).
inline SamplerKind sampler_of(const ImageSpec& image) {
  return image.sampler == "sobol" ? SamplerKind::sobol : SamplerKind::independent;
}

// Tiles covering the image, row by row.
std::vector<TileRect> make_tiles(int width, int height, int tile_size);

struct TileWork {
  TileRect rect;
  int spp = 1;
  int shaded = 0;  // of each pixel's spp samples, the first `shaded` are points (ImageSpec::shade_spp; 0: all)
  ShadingPoints points;                 // one per shaded camera sample that hit a surface
  std::vector<uint32_t> sample_of_point;  // which sample (pixel-major, then sample index) each point is
  std::vector<float> distance;          // per point: how far along its camera ray from `eye` it lies
  Vec3 eye{};                           // where every camera ray starts (a pinhole's; through a lens, `distance` is empty)
  std::vector<RGB> emitted;             // per sample: emission the camera sees directly (none in an adaptive
                                        // second round's tile: its pixels' emission is the first round's)
  // Set by trace_tile: every point is exactly what a lean input rebuilds from the scene and the tile (position by
  // point_on_ray from eye and distance, key by tile_sample_key, normal by surface_at, material by material_of), so
  // a request need not check it point by point (actors/codecs/shade_codec.hpp). Keys are rebuildable only with the
  // sampler and image width trace_tile used, kept here. Whoever changes a point clears it.
  bool rebuildable = false;
  SamplerKind sampler = SamplerKind::independent;
  int64_t image_width = 0;
};

// A camera ray's hit: the point `t` along the ray from `origin` whose direction is -wo. Out of line, so that the
// renderer and a LightOp rebuilding its points from a lean request (actors/codecs/shade_codec.hpp) compute it with
// the same instructions, bit for bit.
Vec3 point_on_ray(Vec3 origin, Vec3 wo, float t);
// The sample key of a tile's `sample`-th camera sample (pixel-major, then sample index), as trace_tile gives it: its
// pixel's sample rect.first_sample + sample % spp.
uint64_t tile_sample_key(SamplerKind kind, int64_t image_width, const TileRect& rect, int spp, uint32_t sample);

// No pixel on a light's outline: tiles traced without extra seen samples.
const EmitterEdges& no_edges();
// A tile's camera rays, one per sample (pixel-major, then sample index), and their sample keys; then, without keys,
// the extra seen samples of the tile's pixels on a light's outline (edges.samples - spp each, pixel by pixel).
void tile_camera_rays(const Camera& camera, const ImageSpec& image, const TileRect& rect, std::vector<Ray>& rays,
                      std::vector<uint64_t>& keys, const EmitterEdges& edges = no_edges());
// The tile's shading points from its camera rays' hits (rays, hits and keys as tile_camera_rays gave them, with
// the same edges): an outline pixel's emission is the mean over all its seen samples, in each of its samples.
void tile_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                 std::span<const Ray> rays, std::span<const Hit> hits, std::span<const uint64_t> keys, TileWork& work,
                 const EmitterEdges& edges = no_edges());
// As above without the outline's extra samples (rays, hits and keys: one a sample of the tile).
void first_round_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                        std::span<const Ray> rays, std::span<const Hit> hits, std::span<const uint64_t> keys,
                        TileWork& work);
// Both, with the rays traced by `tracer`.
void trace_tile(const Scene& scene, const RayTracer& tracer, const Camera& camera, const ImageSpec& image,
                const TileRect& rect, TileWork& work, const EmitterEdges& edges = no_edges());

// Adaptive sampling (ImageSpec::adaptive_spp). After a tile's first round, each pixel's count of shaded samples:
// shade_spp where the standard error its lighting's mean would have (from the spread of the shaded samples of its
// neighbours in the tile, not its own, so that its mean stays unbiased) is within adaptive_threshold / 2^exposure
// (that share of display white), else shade_spp doubled until it would be (as estimated), at most adaptive_spp.
// A function of the tile's samples only (tiles are the image's), so the image does not depend on the farm's layout.
// `radiance` is one value a point of `work` (the first round's: shaded_per_pixel() samples a pixel lit).
std::vector<uint32_t> adaptive_shaded_counts(const ImageSpec& image, const TileWork& work, std::span<const RGB> radiance);
// The second round's points: pixel p's samples from shaded_per_pixel() up to shaded_of_pixel[p], traced again
// (below spp their camera rays are the first round's, so their hits are too; past it, the next of the pixel's
// sequence). `work` is a tile of max(spp, adaptive_spp) samples a pixel.
void trace_more_samples(const Scene& scene, const RayTracer& tracer, const Camera& camera, const ImageSpec& image,
                        const TileRect& rect, std::span<const uint32_t> shaded_of_pixel, TileWork& work);
// The same in two steps, for rays traced elsewhere (a partitioned scene's parts): the wanted samples' camera rays,
// each with its key and its sample's index in the second round's tile; then the points from those rays' hits.
struct MoreSamples {
  std::vector<Ray> rays;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> sample;
};
MoreSamples more_sample_rays(const Camera& camera, const ImageSpec& image, const TileRect& rect,
                             std::span<const uint32_t> shaded_of_pixel);
void more_sample_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                        const MoreSamples& more, std::span<const Hit> hits, TileWork& work);
// pixels[p] = mean of emission over all spp samples + the lighting of both rounds' points over shaded_of_pixel[p].
void resolve_adaptive_tile(const TileWork& first, std::span<const RGB> first_radiance, const TileWork& more,
                           std::span<const RGB> more_radiance, std::span<const uint32_t> shaded_of_pixel,
                           std::vector<RGB>& pixels);

// `work` with its points (and their samples and distances) in the order `order` gives (indices into work's points):
// the same tile, sent in another order (a partitioned farm's renderer groups its points by part). Still rebuildable.
void reorder_points(const TileWork& work, std::span<const uint32_t> order, TileWork& out);

// The radiance of points in one pixel, summed: one sum per run of consecutive points whose samples (pixel-major
// sample indices of a tile with `spp` samples per pixel) lie in one pixel, added in point order from zero. The
// renderer folds a tile's radiance this way, and a LightOp asked for a folded reply (docs/PROTOCOL.md) folds its
// points the same way, so the two give the same bits. Appends to `sums`.
void fold_by_pixel(std::span<const RGB> radiance, std::span<const uint32_t> samples, int spp, std::vector<RGB>& sums);
// How many sums fold_by_pixel gives for these samples.
size_t pixel_runs(std::span<const uint32_t> samples, int spp);

// pixels[p] = mean over samples of (emitted + radiance of its point); sums run in sample order.
void resolve_tile(const TileWork& work, std::span<const RGB> radiance, std::vector<RGB>& pixels);
// Whether any sample of the tile's pixel p sees an emitter (work.emitted non-zero).
bool pixel_sees_emitter(const TileWork& work, size_t pixel);
// As resolve_tile, where a pixel marked in `folded` takes its points' radiance as their sum (`pixel_radiance[p]`,
// from fold_by_pixel) and `radiance` is read for the other pixels only. The same bits as resolve_tile for a pixel
// whose samples see no emitter (0 + r is r): fold only those.
void resolve_tile(const TileWork& work, std::span<const RGB> radiance, std::span<const RGB> pixel_radiance,
                  std::span<const uint8_t> folded, std::vector<RGB>& pixels);

}  // namespace lf
