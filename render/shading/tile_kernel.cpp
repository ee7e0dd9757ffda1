#include "render/shading/tile_kernel.hpp"

#include <algorithm>
#include <cmath>

#include "render/shading/sampler.hpp"
#include "render/scene/surface.hpp"

namespace lf {

std::vector<TileRect> make_tiles(int width, int height, int tile_size) {
  std::vector<TileRect> tiles;
  for (int y = 0; y < height; y += tile_size)
    for (int x = 0; x < width; x += tile_size)
      tiles.push_back({x, y, std::min(x + tile_size, width), std::min(y + tile_size, height)});
  return tiles;
}

const EmitterEdges& no_edges() {
  static const EmitterEdges none;
  return none;
}

namespace {

// The camera ray through pixel (x, y) of the sample with this key, drawn from `stream`.
Ray sample_ray(const Camera& camera, SamplerKind kind, uint64_t key, uint64_t stream, int x, int y) {
  Sampler sampler(kind, key, stream);
  const Uniform2 jitter = sampler.uniform2();
  const float px = static_cast<float>(x) + jitter.u, py = static_cast<float>(y) + jitter.v;
  if (!camera.has_lens()) return camera.ray(px, py);
  const Uniform2 lens = sampler.uniform2();  // drawn only with a lens: pinhole images keep their numbers
  return camera.ray(px, py, lens.u, lens.v);
}

}  // namespace

void tile_camera_rays(const Camera& camera, const ImageSpec& image, const TileRect& rect, std::vector<Ray>& rays,
                      std::vector<uint64_t>& keys, const EmitterEdges& edges) {
  const size_t samples = static_cast<size_t>(rect.pixel_count()) * image.spp;
  rays.resize(samples);
  keys.resize(samples);
  const SamplerKind kind = sampler_of(image);
  size_t s = 0;
  for (int y = rect.y0; y < rect.y1; ++y)
    for (int x = rect.x0; x < rect.x1; ++x)
      for (int k = 0; k < image.spp; ++k, ++s) {
        keys[s] = tile_sample_key(kind, image.width, rect, image.spp, static_cast<uint32_t>(s));
        rays[s] = sample_ray(camera, kind, keys[s], streams::camera, x, y);
      }
  if (edges.samples <= image.spp) return;
  // The outline's pixels' seen samples, after all the others: their own stream, numbered on from pass to pass of a
  // time-limited frame, so that no two passes repeat one.
  const uint32_t extra = static_cast<uint32_t>(edges.samples - image.spp);
  const uint32_t first = rect.first_sample / static_cast<uint32_t>(image.spp) * extra;
  for (int y = rect.y0; y < rect.y1; ++y)
    for (int x = rect.x0; x < rect.x1; ++x) {
      if (!edges.at(x, y)) continue;
      const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(image.width) + static_cast<uint64_t>(x);
      for (uint32_t j = 0; j < extra; ++j)
        rays.push_back(sample_ray(camera, kind, pixel_sample_key(kind, pixel, first + j), streams::outline, x, y));
    }
}

namespace {

// What the camera sees directly along a ray that hit nothing or a surface: the environment, or an emitter's front.
RGB seen_along(const Scene& scene, const Ray& ray, const Hit& hit) {
  if (!hit.valid()) return scene.environment() ? scene.background(ray.direction) : RGB{};
  const uint32_t tri = hit.triangle;
  const Vec3 wo = -ray.direction;
  if (!scene.material(scene.material_of(tri)).emissive() || dot(scene.normal(tri), wo) <= 0) return RGB{};
  return scene.emission_at(tri, point_on_ray(ray.origin, wo, hit.t));
}

}  // namespace

void tile_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                 std::span<const Ray> rays, std::span<const Hit> hits, std::span<const uint64_t> keys, TileWork& work,
                 const EmitterEdges& edges) {
  const size_t samples = keys.size();
  first_round_points(scene, camera, image, rect, rays.first(samples), hits.first(samples), keys, work);
  if (rays.size() == samples) return;
  // Each outline pixel's emission is the mean over all its seen samples, written to each of its spp samples so that
  // whatever averages a pixel's samples' emission averages them all.
  const size_t spp = static_cast<size_t>(image.spp), extra = static_cast<size_t>(edges.samples - image.spp);
  const float inv = 1.0f / static_cast<float>(edges.samples);
  size_t r = samples, p = 0;
  for (int y = rect.y0; y < rect.y1; ++y)
    for (int x = rect.x0; x < rect.x1; ++x, ++p) {
      if (!edges.at(x, y)) continue;
      RGB seen{};
      for (size_t k = p * spp; k < (p + 1) * spp; ++k) seen += work.emitted[k];
      for (size_t j = 0; j < extra; ++j, ++r) seen += seen_along(scene, rays[r], hits[r]);
      for (size_t k = p * spp; k < (p + 1) * spp; ++k) work.emitted[k] = seen * inv;
    }
}

namespace {

// A tile's points start empty, with what says how to read them.
void start_points(const Camera& camera, const ImageSpec& image, const TileRect& rect, size_t samples, TileWork& work) {
  work.rect = rect;
  work.spp = image.spp;
  work.shaded = image.shade_spp;
  work.points.clear();
  work.sample_of_point.clear();
  work.distance.clear();
  work.eye = camera.eye();
  work.emitted.assign(samples, RGB{});
  work.rebuildable = true;  // every point is pushed as surface_at, point_on_ray and tile_sample_key give it
  work.sampler = sampler_of(image);
  work.image_width = image.width;
}

// Sample `sample`'s shading point, where its camera ray hit; returns the emission the camera sees there.
RGB push_point(const Scene& scene, const Camera& camera, const Ray& ray, const Hit& hit, uint64_t key, uint32_t sample,
               TileWork& work) {
  const uint32_t tri = hit.triangle;
  const Vec3 wo = -ray.direction;
  const Vec3 p = point_on_ray(ray.origin, wo, hit.t);
  const SurfacePoint sp = surface_at(scene, tri, p, wo);
  work.points.push_back(p, sp.ns, wo, scene.material_of(tri), key, tri);
  work.sample_of_point.push_back(sample);
  // Rays through a lens leave from points other than the eye: their points travel as positions, not as
  // distances from the eye (actors/runtime/lean_points.cpp rebuilds a point only from the eye).
  if (!camera.has_lens()) work.distance.push_back(hit.t);
  return sp.front && scene.material(scene.material_of(tri)).emissive() ? scene.emission_at(tri, p) : RGB{};
}

}  // namespace

void first_round_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                        std::span<const Ray> rays, std::span<const Hit> hits, std::span<const uint64_t> keys,
                        TileWork& work) {
  const size_t samples = rays.size();
  start_points(camera, image, rect, samples, work);
  work.points.reserve(samples);
  const size_t per_pixel = static_cast<size_t>(image.spp), shaded = static_cast<size_t>(image.shaded_per_pixel());
  for (size_t i = 0; i < samples; ++i) {
    if (!hits[i].valid()) {
      // What the camera sees beyond the scene: the environment, if it shows it.
      if (scene.environment()) work.emitted[i] = scene.background(rays[i].direction);
      continue;
    }
    if (i % per_pixel >= shaded) {  // seen, not shaded: only its emission counts (surface_at's front)
      const uint32_t tri = hits[i].triangle;
      const Vec3 wo = -rays[i].direction;
      if (scene.material(scene.material_of(tri)).emissive() && dot(scene.normal(tri), wo) > 0)
        work.emitted[i] = scene.emission_at(tri, point_on_ray(rays[i].origin, wo, hits[i].t));
      continue;
    }
    work.emitted[i] = push_point(scene, camera, rays[i], hits[i], keys[i], static_cast<uint32_t>(i), work);
  }
}

void trace_tile(const Scene& scene, const RayTracer& tracer, const Camera& camera, const ImageSpec& image,
                const TileRect& rect, TileWork& work, const EmitterEdges& edges) {
  thread_local std::vector<Ray> rays;
  thread_local std::vector<Hit> hits;
  thread_local std::vector<uint64_t> keys;
  tile_camera_rays(camera, image, rect, rays, keys, edges);
  hits.resize(rays.size());
  // One coherent stream (SIMD packets), the same batch on any layout; a ray's hit is the same as traced alone
  // (partition.test: CameraRaysInPacketsHitWhatTheyHitOneByOne), which camera rays through a partitioned scene are.
  tracer.intersect(rays, hits, /*coherent=*/true);
  tile_points(scene, camera, image, rect, rays, hits, keys, work, edges);
}

MoreSamples more_sample_rays(const Camera& camera, const ImageSpec& image, const TileRect& rect,
                             std::span<const uint32_t> shaded_of_pixel) {
  // Up to adaptive_spp samples a pixel: past spp they go on along each pixel's sequence (lit, not seen: the
  // pixel's emission stays the first round's). Only the wanted samples' rays are made (a tile of 256 a pixel has
  // 262,144 others).
  const SamplerKind kind = sampler_of(image);
  const uint32_t per_pixel = static_cast<uint32_t>(std::max(image.spp, image.adaptive_spp));
  const uint32_t shaded = static_cast<uint32_t>(image.shaded_per_pixel());
  MoreSamples more;
  uint32_t p = 0;
  for (int y = rect.y0; y < rect.y1; ++y)
    for (int x = rect.x0; x < rect.x1; ++x, ++p)
      for (uint32_t k = shaded; k < shaded_of_pixel[p]; ++k) {
        const uint32_t i = p * per_pixel + k;
        const uint64_t key = tile_sample_key(kind, image.width, rect, static_cast<int>(per_pixel), i);
        more.rays.push_back(sample_ray(camera, kind, key, streams::camera, x, y));
        more.keys.push_back(key);
        more.sample.push_back(i);
      }
  return more;
}

void more_sample_points(const Scene& scene, const Camera& camera, const ImageSpec& image, const TileRect& rect,
                        const MoreSamples& more, std::span<const Hit> hits, TileWork& work) {
  // The second round's tile counts max(spp, adaptive_spp) samples a pixel, so that each point's sample index (and
  // the key a lean input rebuilds from it) is its place in the pixel's sequence. Only the wanted samples are
  // held; the tile has no emission, which is the first round's.
  ImageSpec wide = image;
  wide.spp = std::max(image.spp, image.adaptive_spp);
  wide.shade_spp = image.shaded_per_pixel();
  start_points(camera, wide, rect, 0, work);
  work.points.reserve(more.sample.size());
  for (size_t j = 0; j < more.sample.size(); ++j)
    if (hits[j].valid()) push_point(scene, camera, more.rays[j], hits[j], more.keys[j], more.sample[j], work);
}

void trace_more_samples(const Scene& scene, const RayTracer& tracer, const Camera& camera, const ImageSpec& image,
                        const TileRect& rect, std::span<const uint32_t> shaded_of_pixel, TileWork& work) {
  const MoreSamples more = more_sample_rays(camera, image, rect, shaded_of_pixel);
  std::vector<Hit> hits(more.rays.size());
  tracer.intersect(more.rays, hits, /*coherent=*/true);
  more_sample_points(scene, camera, image, rect, more, hits, work);
}

std::vector<uint32_t> adaptive_shaded_counts(const ImageSpec& image, const TileWork& work, std::span<const RGB> radiance) {
  const size_t spp = static_cast<size_t>(work.spp), pixels = work.emitted.size() / spp;
  const int shaded = image.shaded_per_pixel();
  std::vector<double> sum(pixels, 0.0), sum_sq(pixels, 0.0);
  for (size_t j = 0; j < work.sample_of_point.size(); ++j) {
    const double v = average(radiance[j]);
    const size_t p = work.sample_of_point[j] / spp;
    sum[p] += v;
    sum_sq[p] += v * v;
  }
  const double n = shaded;
  // Each pixel's sample variance of its lighting (samples that hit nothing are zeros).
  std::vector<double> variance(pixels);
  for (size_t p = 0; p < pixels; ++p) {
    const double mean = sum[p] / n;
    variance[p] = std::max(0.0, (sum_sq[p] - n * mean * mean) / (n - 1));
  }
  std::vector<uint32_t> counts(pixels, static_cast<uint32_t>(shaded));
  // The noise allowed, in radiance: adaptive_threshold of display white at the image's exposure.
  const double allowed = image.adaptive_threshold / std::exp2(image.exposure);
  const int width = work.rect.width(), height = work.rect.height();
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      // The standard error a pixel's mean would have, from the spread of its neighbours' samples in the tile, never
      // its own: its samples are then independent of whether it gets more, and its mean stays unbiased. A pixel
      // that decided on its own samples got more when they happened to spread (a bright sample among its first)
      // and kept its low mean when they did not: darker on average where light is rare and bright (the test).
      // Noise gathers in regions (around a light, in a caustic), so the neighbours see what the pixel would.
      double pooled = 0;
      int neighbours = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, v = y + dy;
          if ((dx == 0 && dy == 0) || u < 0 || v < 0 || u >= width || v >= height) continue;
          pooled += variance[static_cast<size_t>(v) * static_cast<size_t>(width) + static_cast<size_t>(u)];
          ++neighbours;
        }
      if (neighbours == 0) continue;
      const double error = std::sqrt(pooled / neighbours / n);
      if (!(error > allowed)) continue;
      // Enough samples to bring the error to the threshold, as a doubling of shade_spp (a prefix of the pixel's
      // samples whose length is a power of two times shade_spp stays stratified), at most adaptive_spp.
      const double wanted = allowed > 0 ? n * (error / allowed) * (error / allowed) : 1e30;
      int count = shaded;
      while (count < image.adaptive_spp && count < wanted) count *= 2;
      counts[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)] =
          static_cast<uint32_t>(std::min(count, image.adaptive_spp));
    }
  return counts;
}

void resolve_adaptive_tile(const TileWork& first, std::span<const RGB> first_radiance, const TileWork& more,
                           std::span<const RGB> more_radiance, std::span<const uint32_t> shaded_of_pixel,
                           std::vector<RGB>& pixels) {
  const size_t spp = static_cast<size_t>(first.spp), count = first.emitted.size() / spp;
  pixels.assign(count, RGB{});
  std::vector<RGB> lit(count);
  for (size_t j = 0; j < first.sample_of_point.size(); ++j) lit[first.sample_of_point[j] / spp] += first_radiance[j];
  const size_t more_spp = static_cast<size_t>(more.spp);  // the second round's tile may count more a pixel
  for (size_t j = 0; j < more.sample_of_point.size(); ++j) lit[more.sample_of_point[j] / more_spp] += more_radiance[j];
  const float inv = 1.0f / static_cast<float>(spp);
  for (size_t p = 0; p < count; ++p) {
    RGB seen{};
    for (size_t k = 0; k < spp; ++k) seen += first.emitted[p * spp + k];
    pixels[p] = seen * inv + lit[p] * (1.0f / static_cast<float>(shaded_of_pixel[p]));
  }
}

void reorder_points(const TileWork& work, std::span<const uint32_t> order, TileWork& out) {
  out = TileWork{};
  out.rect = work.rect;
  out.spp = work.spp;
  out.shaded = work.shaded;
  out.eye = work.eye;
  out.emitted = work.emitted;
  out.rebuildable = work.rebuildable;
  out.sampler = work.sampler;
  out.image_width = work.image_width;
  out.points.reserve(order.size());
  const ShadingPoints& w = work.points;
  for (uint32_t i : order) {
    if (w.triangle.empty()) out.points.push_back(w.position[i], w.normal[i], w.wo[i], w.material[i], w.key[i]);
    else out.points.push_back(w.position[i], w.normal[i], w.wo[i], w.material[i], w.key[i], w.triangle[i]);
    out.sample_of_point.push_back(work.sample_of_point[i]);
    if (!work.distance.empty()) out.distance.push_back(work.distance[i]);
  }
}

Vec3 point_on_ray(Vec3 origin, Vec3 wo, float t) { return origin + (-wo) * t; }

uint64_t tile_sample_key(SamplerKind kind, int64_t image_width, const TileRect& rect, int spp, uint32_t sample) {
  const uint64_t per_pixel = static_cast<uint64_t>(spp), local = sample / per_pixel;
  const uint64_t w = static_cast<uint64_t>(rect.width());
  const uint64_t x = static_cast<uint64_t>(rect.x0) + local % w, y = static_cast<uint64_t>(rect.y0) + local / w;
  return pixel_sample_key(kind, y * static_cast<uint64_t>(image_width) + x, rect.first_sample + sample % per_pixel);
}

void fold_by_pixel(std::span<const RGB> radiance, std::span<const uint32_t> samples, int spp, std::vector<RGB>& sums) {
  const uint32_t per_pixel = static_cast<uint32_t>(spp);
  for (size_t j = 0; j < samples.size();) {
    const uint32_t pixel = samples[j] / per_pixel;
    RGB sum{};
    for (; j < samples.size() && samples[j] / per_pixel == pixel; ++j) sum += radiance[j];
    sums.push_back(sum);
  }
}

size_t pixel_runs(std::span<const uint32_t> samples, int spp) {
  const uint32_t per_pixel = static_cast<uint32_t>(spp);
  size_t runs = 0;
  for (size_t j = 0; j < samples.size(); ++j) runs += j == 0 || samples[j] / per_pixel != samples[j - 1] / per_pixel;
  return runs;
}

void resolve_tile(const TileWork& work, std::span<const RGB> radiance, std::vector<RGB>& pixels) {
  resolve_tile(work, radiance, {}, {}, pixels);
}

bool pixel_sees_emitter(const TileWork& work, size_t pixel) {
  const size_t spp = static_cast<size_t>(work.spp);
  for (size_t k = pixel * spp; k < (pixel + 1) * spp; ++k)
    if (work.emitted[k].x != 0 || work.emitted[k].y != 0 || work.emitted[k].z != 0) return true;
  return false;
}

void resolve_tile(const TileWork& work, std::span<const RGB> radiance, std::span<const RGB> pixel_radiance,
                  std::span<const uint8_t> folded, std::vector<RGB>& pixels) {
  const size_t samples = work.emitted.size();
  const size_t spp = static_cast<size_t>(work.spp);
  pixels.assign(samples / spp, RGB{});
  const float inv = 1.0f / static_cast<float>(spp);
  if (work.shaded > 0 && work.shaded < work.spp) {
    // Emission over all samples, lighting over the shaded ones (ImageSpec::shade_spp).
    const float inv_shaded = 1.0f / static_cast<float>(work.shaded);
    std::vector<RGB> lit(pixels.size());
    for (size_t j = 0; j < work.sample_of_point.size(); ++j)
      if (folded.empty() || !folded[work.sample_of_point[j] / static_cast<uint32_t>(work.spp)])
        lit[work.sample_of_point[j] / spp] += radiance[j];
    for (size_t p = 0; p < pixels.size(); ++p) {
      RGB seen{};
      for (size_t k = 0; k < spp; ++k) seen += work.emitted[p * spp + k];
      pixels[p] = seen * inv + (!folded.empty() && folded[p] ? pixel_radiance[p] : lit[p]) * inv_shaded;
    }
    return;
  }
  std::vector<RGB> per_sample(work.emitted);
  for (size_t j = 0; j < work.sample_of_point.size(); ++j)
    if (folded.empty() || !folded[work.sample_of_point[j] / static_cast<uint32_t>(work.spp)])
      per_sample[work.sample_of_point[j]] += radiance[j];
  for (size_t p = 0; p < pixels.size(); ++p) {
    if (!folded.empty() && folded[p]) {
      pixels[p] = pixel_radiance[p] * inv;
      continue;
    }
    RGB sum{};
    for (size_t k = 0; k < spp; ++k) sum += per_sample[p * spp + k];
    pixels[p] = sum * inv;
  }
}

}  // namespace lf
