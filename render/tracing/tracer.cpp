#include "render/tracing/tracer.hpp"

#include "render/tracing/tied_hits.hpp"

#include <algorithm>
#include <embree3/rtcore.h>
#include <malloc.h>

#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace lf {

namespace {

// Which scene triangle each of a geometry's Embree primitives is, and the scene its alpha filter asks.
struct Primitives {
  const Scene* scene = nullptr;
  std::span<const uint32_t> subset;  // Embree's primitive i is scene triangle subset[i]; empty: the whole scene
  uint32_t triangle_of(unsigned prim) const { return subset.empty() ? prim : subset[prim]; }
};

void skip_cut_out(const RTCFilterFunctionNArguments* args) {
  const auto* prims = static_cast<const Primitives*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
    if (!prims->scene->opaque(prims->triangle_of(RTCHitN_primID(args->hit, args->N, i)), {1 - u - v, u, v}))
      args->valid[i] = 0;
  }
}

// A geometry of `triangles` (scene numbering; empty: the whole scene) over the vertices `vertices` names
// (renumbered: Embree's vertex i is scene vertex vertices[i]; empty: the scene's); each corner in its scene order, so
// a triangle's hit is the same arithmetic whichever geometry holds it. `corners`, when given, are the triangles'
// corners already laid out (the scene image's), read in place.
RTCGeometry triangle_geometry(RTCDevice device, const Scene& scene, std::span<const uint32_t> triangles,
                              std::span<const std::array<uint32_t, 3>> corners, const std::vector<uint32_t>& vertices,
                              const std::vector<uint32_t>& renumbered) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (vertices.empty() && scene.shares_storage()) {
    // The scene image is mapped by every actor of this host; Embree reads it in place (padded for its loads).
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, scene.vertices().data(), 0,
                               sizeof(Vec3), scene.vertices().size());
  } else {
    const size_t count = vertices.empty() ? scene.vertices().size() : vertices.size();
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), count));
    for (size_t i = 0; i < count; ++i) {
      const Vec3 v = scene.vertices()[vertices.empty() ? i : vertices[i]];
      vb[3 * i] = v.x;
      vb[3 * i + 1] = v.y;
      vb[3 * i + 2] = v.z;
    }
  }
  if (triangles.empty() && scene.shares_storage()) corners = scene.triangles();
  if (!corners.empty()) {
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, corners.data(), 0,
                               3 * sizeof(unsigned), corners.size());
    return geom;
  }
  const size_t count = triangles.empty() ? scene.triangles().size() : triangles.size();
  auto* ib = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), count));
  for (size_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = scene.triangles()[triangles.empty() ? i : triangles[i]][c];
      ib[3 * i + c] = vertices.empty() ? v : renumbered[v];
    }
  return geom;
}

}  // namespace

struct RayTracer::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  // Per Embree geometry (its geomID): the triangles that may be cut out by an alpha map are a geometry of their
  // own with the alpha filter; the rest, most of a scene, need no call back into the filter for each candidate hit.
  std::vector<Primitives> geometries;
  std::vector<uint32_t> order;  // the geometries' triangles, opaque first, when the scene image holds no such order
  std::unique_ptr<TiedHits> ties;  // the whole scene's; a part's tracer leaves ties to its caller
  uint32_t triangle_of(unsigned geom, unsigned prim) const { return geometries[geom].triangle_of(prim); }
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RayTracer::RayTracer(const Scene& scene) : RayTracer(scene, std::vector<uint32_t>{}) {}

RayTracer::RayTracer(const Scene& scene, std::vector<uint32_t> triangles)
    : impl_(std::make_unique<Impl>()), scene_(scene) {
  const bool whole = triangles.empty();
  // One thread per actor: parallelism comes from processes (and Embree's own pool would fight them for cores).
  impl_->device = rtcNewDevice("threads=1");
  if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
  impl_->scene = rtcNewScene(impl_->device);
  // A part keeps its triangles' own vertices only (renumbered); the whole scene keeps the scene's.
  std::vector<uint32_t> vertices, renumbered;
  if (!whole) {
    renumbered.assign(scene.vertices().size(), UINT32_MAX);
    for (uint32_t t : triangles)
      for (uint32_t v : scene.triangles()[t])
        if (renumbered[v] == UINT32_MAX) {
          renumbered[v] = static_cast<uint32_t>(vertices.size());
          vertices.push_back(v);
        }
  }
  impl_->geometries.reserve(2);  // the filters hold pointers into it
  // A geometry of the triangles `part` lists (empty: the whole scene); `corners`: theirs as the scene image lays them
  // out, else none. With the alpha filter where they may be cut out.
  auto add = [&](std::span<const uint32_t> part, std::span<const std::array<uint32_t, 3>> corners, bool filtered) {
    Primitives& prims = impl_->geometries.emplace_back(Primitives{&scene, part});
    RTCGeometry geom = triangle_geometry(impl_->device, scene, part, corners, vertices, renumbered);
    if (filtered) {
      // Alpha cut-outs: a hit where the alpha map says the surface is not there is no hit, for every kind of ray.
      rtcSetGeometryUserData(geom, &prims);
      rtcSetGeometryIntersectFilterFunction(geom, &skip_cut_out);
      rtcSetGeometryOccludedFilterFunction(geom, &skip_cut_out);
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(impl_->scene, geom, static_cast<unsigned>(impl_->geometries.size() - 1));
    rtcReleaseGeometry(geom);
  };
  // The triangles that are opaque everywhere, then those that may be cut out: each group a geometry. A mapped
  // scene's image holds that order for the whole scene (every actor of this host reads the same copy); else this
  // tracer makes it.
  const bool cutouts = scene.has_cutouts();
  std::span<const uint32_t> order = scene.opaque_first().triangles;
  std::span<const std::array<uint32_t, 3>> corners = scene.opaque_first().corners;
  size_t opaque = scene.opaque_first().opaque;
  if (!whole || (cutouts && order.empty())) {
    impl_->order = std::move(triangles);
    if (whole) {
      impl_->order.resize(scene.triangle_count());
      std::iota(impl_->order.begin(), impl_->order.end(), 0u);
    }
    opaque = scene.put_opaque_first(impl_->order);
    order = impl_->order;
    corners = {};
  }
  if (whole && (!cutouts || opaque == order.size())) {
    impl_->order = {};
    add({}, {}, false);  // nothing cut out: the scene's own triangles, in place
  } else {
    const auto corners_of = [&](size_t at, size_t n) { return corners.empty() ? corners : corners.subspan(at, n); };
    if (opaque > 0) add(order.first(opaque), corners_of(0, opaque), false);
    if (opaque < order.size()) add(order.subspan(opaque), corners_of(opaque, order.size() - opaque), true);
  }
  rtcCommitScene(impl_->scene);
  if (rtcGetDeviceError(impl_->device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the scene");
  if (whole) impl_->ties = std::make_unique<TiedHits>(scene);
  // The build's temporaries (half again the BVH's size) stay in the heap after they are freed; give them back,
  // since every actor of a host holds its own BVH.
  ::malloc_trim(0);
}

RayTracer::~RayTracer() = default;

static void fill(RTCRay& r, const Ray& ray) {
  r.org_x = ray.origin.x;
  r.org_y = ray.origin.y;
  r.org_z = ray.origin.z;
  r.dir_x = ray.direction.x;
  r.dir_y = ray.direction.y;
  r.dir_z = ray.direction.z;
  r.tnear = ray.tnear;
  r.tfar = ray.tfar;
  r.time = 0;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
}

// Rays given to Embree in one stream call at most.
constexpr size_t kStreamPiece = size_t{1} << 20;

// The rays and Embree's answers of this thread's last intersect_unsettled (settling reads its barycentrics).
static std::vector<RTCRayHit>& rayhit_buffer() {
  thread_local std::vector<RTCRayHit> buffer;
  return buffer;
}

void RayTracer::intersect(std::span<const Ray> rays, std::span<Hit> hits, bool coherent) const {
  intersect_unsettled(rays, hits, coherent);
  if (!impl_->ties) return;
  const std::vector<RTCRayHit>& answers = rayhit_buffer();
  for (size_t i = 0; i < rays.size(); ++i) hits[i] = impl_->ties->settle(rays[i], hits[i], answers[i].hit.u, answers[i].hit.v);
}

void RayTracer::intersect_unsettled(std::span<const Ray> rays, std::span<Hit> hits, bool coherent) const {
  std::vector<RTCRayHit>& buffer = rayhit_buffer();
  buffer.resize(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    fill(buffer[i].ray, rays[i]);
    buffer[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
    buffer[i].hit.primID = RTC_INVALID_GEOMETRY_ID;
    buffer[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  // In pieces: one stream of 40 M rays (3.2 GB of RTCRayHit: an eight-cache network's own values in one process)
  // crashed inside rtcIntersect1M.
  for (size_t first = 0; first < rays.size(); first += kStreamPiece)
    rtcIntersect1M(impl_->scene, &context, buffer.data() + first,
                   static_cast<unsigned>(std::min(kStreamPiece, rays.size() - first)), sizeof(RTCRayHit));
  for (size_t i = 0; i < rays.size(); ++i) {
    if (buffer[i].hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      hits[i] = Hit{};
    } else {
      hits[i] = Hit{impl_->triangle_of(buffer[i].hit.geomID, buffer[i].hit.primID), buffer[i].ray.tfar};
    }
  }
}

void RayTracer::occluded(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
  thread_local std::vector<RTCRay> buffer;
  buffer.resize(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) fill(buffer[i], rays[i]);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t first = 0; first < rays.size(); first += kStreamPiece)
    rtcOccluded1M(impl_->scene, &context, buffer.data() + first,
                  static_cast<unsigned>(std::min(kStreamPiece, rays.size() - first)), sizeof(RTCRay));
  // Embree marks an occluded ray by setting tfar to -inf.
  for (size_t i = 0; i < rays.size(); ++i) occluded[i] = buffer[i].tfar < 0 ? 1 : 0;
}

}  // namespace lf
