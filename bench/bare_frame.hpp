#pragma once
// One frame of the bare single-thread loop, shared by the benchmarks that measure the path kernel without the farm:
// trace a tile, shade its points with `pathtrace` (depth 12), resolve; every tile in turn.
#include <chrono>
#include <cstdint>
#include <vector>

#include "core/value.hpp"
#include "render/tracing/camera.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/tile_kernel.hpp"

namespace bench {

struct BareFrame {
  double seconds = 0;
  uint64_t hash = 0;  // FNV-1a of every tile's pixels in tile order: equal hashes, equal images
};

inline uint64_t fnv1a(uint64_t h, const void* data, size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

inline BareFrame bare_pathtrace_frame(const lf::Scene& scene, const lf::RayTracer& tracer, const lf::CameraSpec& cam,
                                      const char* sampler, int size, int spp) {
  lf::ImageSpec image;
  image.width = image.height = size;
  image.spp = spp;
  image.sampler = sampler;
  image.edge_spp = lf::ImageSpec::default_edge_spp(spp);  // as a farm's image { } has it
  lf::Camera camera(cam, size, size);
  const lf::EmitterEdges edges = lf::emitter_edges(scene, camera, image);
  auto op = lf::create_lightop(*lf::find_lightop_kind("pathtrace"),
                               lf::ParamTable(lf::Value::Map{{"max_depth", 12}}, "pathtrace"));
  lf::LocalInputs none;
  lf::SceneContext ctx{&scene, &tracer};
  ctx.sampler = lf::sampler_of(image);
  lf::run_to_completion(op->setup(ctx, none));
  lf::TileWork work;
  std::vector<lf::RGB> radiance, pixels;
  BareFrame f;
  f.hash = 0xcbf29ce484222325ull;
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& tile : lf::make_tiles(size, size, image.tile)) {
    lf::trace_tile(scene, tracer, camera, image, tile, work, edges);
    radiance.assign(work.points.size(), {});
    lf::run_to_completion(op->shade(work.points, radiance, none));
    lf::resolve_tile(work, radiance, pixels);
    f.hash = fnv1a(f.hash, pixels.data(), pixels.size() * sizeof(lf::RGB));
  }
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

// The camera the empty Cornell box (CornellBox-Empty-RG) is rendered with in the peer comparison (bench/peer).
inline lf::CameraSpec empty_cornell_camera() {
  lf::CameraSpec cam;
  cam.eye = {0, 1, 3.4};
  cam.at = {0, 1, 0};
  cam.fov = 40;
  return cam;
}

}  // namespace bench
