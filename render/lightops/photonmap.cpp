// photonmap: caustics by a caustic photon map (Jensen). No inputs.
//
// Setup: photons leave the lights (emitter chosen by power, uniform point, cosine direction), each carrying an
// equal share of the total emitted flux. They follow mirrors and glass (Fresnel picks reflection or refraction)
// and are stored where they first land on a non-specular surface after at least one specular bounce — the
// light paths L S+ D that make caustics. Photon j draws its random numbers from its own index, so replicas of a
// pool shoot disjoint, contiguous shares (replica r of n shoots [N r / n, N (r + 1) / n)) and merge them in
// replica order: every replica then holds the same map, photon for photon, as a single op would.
// Shade: at a non-specular point, the k nearest photons within max_radius (a kd-tree, nanoflann) estimate the
// reflected radiance, sum f(wo, wi) * flux * w / (pi r^2), with a cone filter w = 1 - d / (k_cone r) normalised
// by 1 - 2 / (3 k_cone) (or an Epanechnikov filter, or none). Points on mirrors and glass get nothing.
// With `precompute = m` (Christensen 1999), setup estimates the irradiance at every m-th photon once; a diffuse
// point then takes the estimate of the nearest such photon on a surface facing its way (one neighbour instead of
// k), other points and points with no such neighbour the full estimate.
#include <nanoflann.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "render/shading/bsdf.hpp"
#include "render/scene/surface.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"

namespace lf {
namespace {

struct Photon {
  Vec3 position;
  Vec3 incoming;  // unit direction back towards where the photon came from
  RGB flux;
  Vec3 normal;    // of the surface it landed on, on the side it arrived from
};
static_assert(sizeof(Photon) == 12 * sizeof(float), "photons travel between replicas as packed floats");

// Irradiance estimated once at a photon (precompute).
struct IrradiancePoint {
  Vec3 position;
  Vec3 normal;
  RGB irradiance;
};

struct IrradianceCloud {
  std::vector<IrradiancePoint> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return points[i].position[static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

struct PhotonCloud {
  std::vector<Photon> photons;
  size_t kdtree_get_point_count() const { return photons.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return photons[i].position[static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PhotonCloud>, PhotonCloud, 3,
                                                   uint32_t>;
using IrradianceTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, IrradianceCloud>,
                                                           IrradianceCloud, 3, uint32_t>;

enum class Filter { cone, epanechnikov, none };

Filter filter_of(const std::string& name) {
  return name == "cone" ? Filter::cone : name == "epanechnikov" ? Filter::epanechnikov : Filter::none;
}

class PhotonMap final : public LightOp {
 public:
  explicit PhotonMap(const ParamTable& p)
      : photons_(static_cast<uint64_t>(p.get_int("photons", 500000, 1, int64_t{1} << 32))),
        k_(static_cast<size_t>(p.get_int("k", 64, 1, 10000))),
        max_radius_(static_cast<float>(p.get_float("max_radius", 0, 0, 1e30))),
        filter_(filter_of(p.get_string("filter", "cone", {"cone", "epanechnikov", "none"}))),
        cone_k_(static_cast<float>(p.get_float("cone_k", 1.1, 1.0, 100))),
        max_depth_(static_cast<int>(p.get_int("max_depth", 16, 1, 256))),
        precompute_(static_cast<uint32_t>(p.get_int("precompute", 0, 0, 1000))),
        seed_(static_cast<uint64_t>(p.get_int("seed", 0, 0, INT32_MAX))) {}

  Task setup(SceneContext ctx, Inputs&) override {
    ctx_ = ctx;
    const Scene& scene = *ctx.scene;
    if (max_radius_ <= 0) max_radius_ = 1000 * scene.epsilon();  // 10 % of the scene's diagonal
    const uint64_t begin = photons_ * static_cast<uint64_t>(ctx.replica_index) / static_cast<uint64_t>(ctx.replica_count);
    const uint64_t end = photons_ * static_cast<uint64_t>(ctx.replica_index + 1) / static_cast<uint64_t>(ctx.replica_count);
    using Clock = std::chrono::steady_clock;
    auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    auto phase_start = Clock::now();
    std::vector<Photon> mine = shoot(scene, *ctx.tracer, begin, end, ctx);
    ctx.report("shooting photons", end - begin, end - begin);
    shoot_seconds_ = seconds_since(phase_start);
    phase_start = Clock::now();

    std::string part(mine.size() * sizeof(Photon), '\0');
    if (!mine.empty()) std::memcpy(part.data(), mine.data(), part.size());
    SoloExchange solo;
    Exchange& exchange = ctx.exchange ? *ctx.exchange : solo;
    std::vector<std::string> parts;
    co_await exchange.all_gather(std::move(part), &parts);
    cloud_.photons.clear();
    for (const auto& p : parts) {
      if (p.size() % sizeof(Photon) != 0) throw LightOpError("photonmap: a replica's share is malformed");
      const size_t n = p.size() / sizeof(Photon);
      const size_t at = cloud_.photons.size();
      cloud_.photons.resize(at + n);
      if (n) std::memcpy(cloud_.photons.data() + at, p.data(), p.size());
    }
    exchange_seconds_ = seconds_since(phase_start);
    phase_start = Clock::now();
    tree_ = std::make_unique<KdTree>(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree_->buildIndex();
    kd_depth_ = depth_of(tree_->root_node);
    build_seconds_ = seconds_since(phase_start);
    if (precompute_ > 0) {
      irradiance_.points.clear();
      for (size_t j = 0; j < cloud_.photons.size(); j += precompute_) {
        const Photon& ph = cloud_.photons[j];
        irradiance_.points.push_back({ph.position, ph.normal, estimate_irradiance(ph.position, ph.normal)});
      }
      irradiance_tree_ = std::make_unique<IrradianceTree>(3, irradiance_, nanoflann::KDTreeSingleIndexAdaptorParams(16));
      irradiance_tree_->buildIndex();
    }
    precompute_seconds_ = seconds_since(phase_start) - build_seconds_;
  }

  Task shade(const ShadingPoints& points, std::span<RGB> radiance, Inputs&) override {
    const Scene& scene = *ctx_.scene;
    const float max_r2 = max_radius_ * max_radius_;
    for (size_t i = 0; i < points.size(); ++i) {
      radiance[i] = RGB{};
      const Material& m = scene.material(points.material[i]);
      if (m.specular() || cloud_.photons.empty()) continue;
      ++lookups_;
      if (irradiance_tree_ && m.type == Material::Type::diffuse) {
        // The nearest precomputed estimate, if it lies on a surface facing the same way.
        const float q[3] = {points.position[i].x, points.position[i].y, points.position[i].z};
        uint32_t nearest = 0;
        float d2 = max_r2;
        nanoflann::KNNResultSet<float, uint32_t> one(1);
        one.init(&nearest, &d2);
        irradiance_tree_->findNeighbors(one, q, nanoflann::SearchParams());
        if (one.size() == 0) continue;  // no caustic photon within max_radius
        const IrradiancePoint& e = irradiance_.points[nearest];
        if (dot(e.normal, points.normal[i]) > 0.9f) {
          ++served_precomputed_;
          radiance[i] = points.albedo(i, scene, ctx_.pixel_footprint(points.position[i])) * e.irradiance * (1.0f / kPi);
          continue;
        }
      }
      const float footprint = ctx_.pixel_footprint(points.position[i]);
      float metallic, roughness;
      points.metal_rough(i, scene, footprint, metallic, roughness);
      const Bsdf bsdf(m, points.albedo(i, scene, footprint), metallic, roughness, points.outside(i, scene));
      radiance[i] = estimate(points.position[i], points.normal[i],
                             [&](Vec3 wi) { return bsdf.eval(points.normal[i], points.wo[i], wi); }, bsdf.transmits());
    }
    co_return;
  }

 public:
  // The photons leave the lights, wherever the camera is.
  bool setup_sees_camera() const override { return false; }

  // Light that reached a diffuse or glossy point through mirrors and glass alone: L S+ (D|G).
  std::optional<LightPaths> paths(std::span<const LightPaths>) const override {
    const LightPaths chains = LightPaths::emission().then_repeated(Lobe::specular, 1, max_depth_);
    LightPaths landed = chains.then(Lobe::diffuse);
    landed += chains.then(Lobe::glossy);
    return landed;
  }

  // photons_shot: by the whole pool; photons_stored: in this map (caustic photons only); lookups: non-specular
  // points asked for; served_precomputed: answered by the nearest precomputed irradiance (`precompute`), the rest
  // by a k-nearest estimate. Setup's time: shooting this replica's share, the exchange of shares (waiting for the
  // slowest replica included), the kd-tree over the whole map, the precomputed irradiance.
  Value stats() const override {
    return Value::Map{{"photons_shot", static_cast<int64_t>(photons_)},
                      {"photons_stored", static_cast<int64_t>(cloud_.photons.size())},
                      {"lookups", static_cast<int64_t>(lookups_)},
                      {"served_precomputed", static_cast<int64_t>(served_precomputed_)},
                      {"kd_depth", kd_depth_},
                      {"estimates", static_cast<int64_t>(estimates_)},
                      {"mean_radius", estimates_ ? radius_sum_ / static_cast<double>(estimates_) : 0.0},
                      {"shoot_seconds", shoot_seconds_},
                      {"exchange_seconds", exchange_seconds_},
                      {"build_seconds", build_seconds_},
                      {"precompute_seconds", precompute_seconds_}};
  }

 private:
  // Levels of the kd-tree, leaves included (buckets of at most 16 photons).
  template <class Node>
  static int depth_of(const Node* node) {
    if (!node) return 0;
    return 1 + std::max(depth_of(node->child1), depth_of(node->child2));
  }
  int kd_depth_ = 0;
  double shoot_seconds_ = 0, exchange_seconds_ = 0, build_seconds_ = 0, precompute_seconds_ = 0;
  mutable uint64_t estimates_ = 0;  // density estimates made (lookups and precomputed ones) that found photons
  mutable double radius_sum_ = 0;   // and the sum of their gather radii
  uint64_t lookups_ = 0, served_precomputed_ = 0;
  // sum f(wi) * flux * w / (pi r^2 norm) over the k nearest photons within max_radius that arrived on n's side
  // (`both_sides`: on either side, for rough glass, which transmits them as f says).
  template <class Brdf>
  RGB estimate(Vec3 x, Vec3 n, Brdf&& f, bool both_sides = false) const {
    std::vector<uint32_t>& index = scratch_index_;
    std::vector<float>& dist2 = scratch_dist2_;
    index.resize(k_);
    dist2.resize(k_);
    const float max_r2 = max_radius_ * max_radius_;
    const float q[3] = {x.x, x.y, x.z};
    // k nearest, but none beyond max_radius: seeding the result set's worst distance with the radius prunes the
    // search, so points far from any caustic cost almost nothing.
    nanoflann::KNNResultSet<float, uint32_t> result(k_);
    result.init(index.data(), dist2.data());
    dist2[k_ - 1] = max_r2;
    tree_->findNeighbors(result, q, nanoflann::SearchParams());
    const size_t found = result.size();
    if (found == 0) return {};
    const float r2 = dist2[found - 1] > 0 ? dist2[found - 1] : max_r2;
    const float r = std::sqrt(r2);
    ++estimates_;
    radius_sum_ += r;
    RGB sum{};
    for (size_t j = 0; j < found; ++j) {
      const Photon& ph = cloud_.photons[index[j]];
      if (!both_sides && dot(ph.incoming, n) <= 0) continue;  // arrived on the other side
      float w = 1.0f;
      const float d = std::sqrt(dist2[j]);
      if (filter_ == Filter::cone) w = 1.0f - d / (cone_k_ * r);
      else if (filter_ == Filter::epanechnikov) w = 2.0f * (1.0f - dist2[j] / r2);  // normalised over the disc
      sum += f(ph.incoming) * ph.flux * w;
    }
    const float norm = filter_ == Filter::cone ? 1.0f - 2.0f / (3.0f * cone_k_) : 1.0f;
    return sum * (1.0f / (kPi * r2 * norm));
  }

  // Irradiance: the estimate with f = 1.
  RGB estimate_irradiance(Vec3 x, Vec3 n) const {
    return estimate(x, n, [](Vec3) { return RGB{1, 1, 1}; });
  }

  std::vector<Photon> shoot(const Scene& scene, const RayTracer& tracer, uint64_t begin, uint64_t end,
                            const SceneContext& ctx) const {
    const float count = static_cast<float>(photons_);
    std::vector<Photon> stored;
    struct Flight {
      Ray ray;
      RGB flux;
      Rng rng;
      int specular_bounces = 0;
    };
    const uint64_t batch = 4096;
    for (uint64_t first = begin; first < end; first += batch) {
      ctx.report("shooting photons", first - begin, end - begin);
      std::vector<Flight> flights;
      for (uint64_t j = first; j < std::min(end, first + batch); ++j) {
        Rng rng(splitmix64(j), streams::photons ^ (seed_ << 8));
        const LightSample ls = sample_light(scene, rng);
        const float u = rng.uniform(), v = rng.uniform();
        if (is_black(ls.radiance)) continue;  // a cut-out part of an emitter
        if (ls.at_infinity) {
          // From the environment: parallel rays through a disc across the scene's bounding sphere, facing the
          // direction the light comes from; flux Le pi R^2 / p(direction) for a disc of radius R.
          const Bounds& b = scene.bounds();
          const Vec3 centre = (b.lo + b.hi) * 0.5f;
          const float radius = 0.5f * length(b.hi - b.lo) + scene.epsilon();
          Vec3 t, s2;
          basis(ls.direction, t, s2);
          const float r = radius * std::sqrt(u), phi = 2.0f * kPi * v;
          const Vec3 origin = centre + ls.direction * radius + t * (r * std::cos(phi)) + s2 * (r * std::sin(phi));
          const RGB flux = ls.radiance * (kPi * radius * radius / (ls.pdf_area * count));
          flights.push_back(Flight{Ray{origin, -ls.direction}, flux, rng});
          continue;
        }
        if (ls.point_light && ls.point_light->spot()) {
          // A spot: uniform over its outer cone, flux I(dir) times the cone's solid angle over P(light).
          const PointLight& spot = *ls.point_light;
          const float one_minus = 1 - spot.cos_outer, cos_t = 1 - u * one_minus;
          const float sin_t = std::sqrt(std::max(0.0f, 1 - cos_t * cos_t)), phi = 2.0f * kPi * v;
          Vec3 t, b;
          basis(spot.axis, t, b);
          const Vec3 dir = normalize(t * (sin_t * std::cos(phi)) + b * (sin_t * std::sin(phi)) + spot.axis * cos_t);
          const RGB flux = spot.intensity_towards(dir) * (2.0f * kPi * one_minus / (ls.pdf_area * count));
          if (!is_black(flux)) flights.push_back(Flight{Ray{ls.point, dir}, flux, rng});
          continue;
        }
        Vec3 dir;
        if (ls.is_point) {  // uniform over the sphere
          const float z = 1.0f - 2.0f * u, r = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = 2.0f * kPi * v;
          dir = {r * std::cos(phi), r * std::sin(phi), z};
        } else {
          dir = cosine_hemisphere(ls.normal, u, v);
        }
        // Flux over the density of the photon's origin and direction: pi Le / p(point) on an area light (cosine
        // directions), 4 pi I / P(light) for a point light. Lights picked by power make it the same share of the
        // total for every photon.
        const RGB flux = ls.radiance * ((ls.is_point ? 4.0f * kPi : kPi) / (ls.pdf_area * count));
        const Vec3 origin = ls.is_point ? ls.point : scene.ray_origin(ls.triangle, ls.point, ls.normal);
        flights.push_back(Flight{Ray{origin, dir}, flux, rng});
      }
      std::vector<Ray> rays;
      std::vector<Hit> hits;
      for (int depth = 0; depth < max_depth_ && !flights.empty(); ++depth) {
        rays.clear();
        for (const auto& f : flights) rays.push_back(f.ray);
        hits.resize(rays.size());
        tracer.intersect(rays, hits);
        std::vector<Flight> next;
        for (size_t i = 0; i < flights.size(); ++i) {
          if (!hits[i].valid()) continue;
          Flight f = flights[i];
          const uint32_t tri = hits[i].triangle;
          const Material& m = scene.material(scene.material_of(tri));
          const Vec3 wo = -f.ray.direction;
          const Vec3 ng = scene.normal(tri);
          const bool front = dot(ng, wo) > 0;
          const Vec3 x = f.ray.origin + f.ray.direction * hits[i].t;
          if (!m.specular()) {
            if (f.specular_bounces > 0) stored.push_back(Photon{x, wo, f.flux, front ? ng : -ng});
            // A caustic map keeps only L S+ D paths and stops at the first diffuse surface, unless that surface
            // also reflects like a mirror: then on through its mirror term, kept in proportion to kr.
            if (!m.has_mirror_term()) continue;
          }
          const Vec3 n = front ? ng : -ng;  // offsets; the smooth normal ns reflects and refracts
          const Vec3 ns = surface_at(scene, tri, x, wo).ns;
          std::optional<Bsdf::Sample> s;
          if (m.specular()) {
            s = Bsdf(m).sample(ns, wo, front, f.rng.uniform(), 0.5f, 0.5f);
          } else if (const float keep = std::min(1.0f, std::max({m.kr.x, m.kr.y, m.kr.z})); f.rng.uniform() < keep) {
            s = Bsdf(m).sample_mirror_term(ns, wo);
            if (s) s->weight = s->weight * (1.0f / keep);
          }
          if (!s) continue;
          f.flux = f.flux * s->weight;
          const Vec3 side = dot(s->wi, n) > 0 ? n : -n;
          f.ray = Ray{scene.ray_origin(tri, x, side), s->wi};
          ++f.specular_bounces;
          next.push_back(f);
        }
        flights = std::move(next);
      }
    }
    return stored;
  }

  uint64_t photons_;
  size_t k_;
  float max_radius_;
  Filter filter_;
  float cone_k_;
  int max_depth_;
  uint32_t precompute_;
  uint64_t seed_;
  SceneContext ctx_;
  PhotonCloud cloud_;
  std::unique_ptr<KdTree> tree_;
  IrradianceCloud irradiance_;
  std::unique_ptr<IrradianceTree> irradiance_tree_;
  mutable std::vector<uint32_t> scratch_index_;
  mutable std::vector<float> scratch_dist2_;
};

}  // namespace

extern const LightOpKind photonmap_kind{
    .name = "photonmap",
    .summary = "caustics from a caustic photon map (k nearest photons, cone filter)",
    .min_inputs = 0,
    .max_inputs = 0,
    .create = [](const ParamTable& p) -> std::unique_ptr<LightOp> { return std::make_unique<PhotonMap>(p); },
    .shares_setup = true};

}  // namespace lf
