#pragma once
// Progressive refinement radiosity (Stürzlinger et al. §1): the patch with the most unshot power shoots; every
// receiving element's sample points see M sub-areas of the shooter through rays (an M-bit visibility vector per sample)
// and take the analytic form factor of the visible ones; elements whose samples disagree too much are split and
// re-sampled for the same shooter (adaptive subdivision).
//
// Part holds the elements of some patches and does everything but casting rays: it says which samples need
// which rays, and takes the visibility vectors back. The serial solver (below) and the ring nodes
// (radiosity/ring.hpp) drive the same Part, so both compute the same numbers in the same order.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "core/result.hpp"
#include "radiosity/mesh.hpp"

namespace lf::radiosity {

struct SolverSettings {
  int shooter_samples = 16;    // M: sub-areas of the shooter (a square number, at most 64)
  float subdivide = 0;         // split an element when its samples' received radiosity differs by more than
                               // this multiple of the scene's mean radiosity (emitted power / total area);
                               // 0: no adaptive subdivision
  int max_depth = 2;           // how many times an element may be split
  double converge = 0.01;      // stop when unshot power / emitted power falls below this
  int max_iterations = 10000;  // and after this many shooters in any case
};

struct Shooter {
  uint32_t patch = 0;
  uint32_t surface = 0;
  Polygon polygon;
  RGB unshot;                  // the radiosity it shoots
  std::vector<Polygon> parts;  // the M sub-areas
  std::vector<Vec3> targets;   // their centroids, where visibility rays end
};
Shooter make_shooter(const Mesh& mesh, uint32_t patch, RGB unshot, int samples);

// The segment whose being blocked hides sub-area m of the shooter from a sample point: both ends lifted off
// their surfaces by the mesh's epsilon. Serial solver and ring nodes cast exactly this segment.
struct Segment {
  Vec3 from, to;
};
Segment visibility_segment(Vec3 point, Vec3 normal, const Shooter& shooter, int m, float epsilon);

struct Candidate {
  uint32_t patch = UINT32_MAX;  // none
  double power = 0;             // area * average(unshot)
  RGB unshot;
  // The better shooter: more power, ties to the lower patch number (so every layout picks the same one).
  bool beats(const Candidate& o) const { return power > o.power || (power == o.power && patch < o.patch); }
};

struct Element {
  Polygon polygon;
  uint32_t patch = 0;
  int depth = 0;
  bool leaf = true;
  RGB radiosity;  // B, emission included
  RGB unshot;
};

struct ShotTotals {
  double power_arrived = 0;   // sum over receiving elements of area * average(irradiance from this shot)
  uint64_t elements_split = 0;
  uint64_t samples = 0;       // samples that needed rays
  uint64_t rays_requested = 0;
};

class Part {
 public:
  Part(const Mesh& mesh, std::vector<uint32_t> patches, SolverSettings settings);

  Candidate best() const;
  double unshot_power() const;  // over the patches held here
  // The shooter's own unshot power leaves it (if it is held here); then the first round of samples is ready.
  void begin_shot(const Shooter& shooter);
  bool round_ready() const { return !round_.empty(); }
  // The samples of this round: point, normal, and the sub-areas worth a ray (form factor > 0) as initial bits.
  size_t sample_count() const { return sample_point_.size(); }
  Vec3 sample_point(size_t i) const { return sample_point_[i]; }
  Vec3 sample_normal(size_t i) const { return sample_normal_[i]; }
  uint64_t sample_mask(size_t i) const { return sample_mask_[i]; }
  // visible[i]: sample i's initial bits ANDed with every blocker found. Applies the shot, or splits elements and
  // prepares another round for their children.
  void finish_round(std::span<const uint64_t> visible);
  const ShotTotals& shot() const { return shot_; }

  const std::vector<uint32_t>& patches() const { return patches_; }
  const std::vector<Element>& elements() const { return elements_; }
  size_t leaf_count() const;

  // Back to the state before the first shot.
  void reset();
  // Back to a checkpoint: the leaf elements this part had after some shot, in their order then (what
  // elements() gave, split parents left out: nothing reads them again, and leaves keep their relative order, so every
  // later sum adds the same numbers in the same order). An error, and no change, for elements of patches held
  // elsewhere.
  Status restore(std::vector<Element> leaves);

 private:
  void prepare_round(std::vector<uint32_t> elements);

  const Mesh& mesh_;
  std::vector<uint32_t> patches_;
  SolverSettings settings_;
  float split_threshold_ = 0;
  std::vector<Element> elements_;
  std::vector<std::vector<uint32_t>> patch_elements_;  // per held patch (index into patches_), all its elements
  std::vector<int32_t> local_of_patch_;                // mesh patch -> index in patches_, or -1
  const Shooter* shooter_ = nullptr;
  std::vector<uint32_t> round_;                        // elements sampled this round
  std::vector<uint32_t> round_first_sample_;           // per round element, its first sample (+ one end marker)
  std::vector<Vec3> sample_point_, sample_normal_;
  std::vector<uint64_t> sample_mask_;
  std::vector<double> sample_factor_;                  // per sample and sub-area: the unoccluded form factor
  ShotTotals shot_;
};

struct IterationRecord {
  uint32_t shooter = 0;
  double power_shot = 0;      // area * average(unshot) of the shooter
  double power_arrived = 0;   // as ShotTotals
  double unshot_fraction = 0; // after the shot, of the emitted power
  uint64_t elements_split = 0;
};

// Casts segments: occluded[i] = 1 when something blocks segments[i].
using SegmentTracer = std::function<void(std::span<const Segment>, std::span<uint8_t>)>;

// The reference: one Part holding every patch, rays against the whole scene.
struct SerialResult {
  std::vector<Element> elements;
  std::vector<IterationRecord> iterations;
  double unshot_fraction = 0;
};
SerialResult solve_serial(const Mesh& mesh, const SolverSettings& settings, const SegmentTracer& trace);

// Whole-scene visibility through Embree, for the serial solver and tests.
class SceneVisibility {
 public:
  explicit SceneVisibility(const Mesh& mesh);  // every surface
  SceneVisibility(const Mesh& mesh, std::span<const uint32_t> surfaces);  // just these
  ~SceneVisibility();
  void operator()(std::span<const Segment> segments, std::span<uint8_t> occluded) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Applies `trace` to every requested ray of the part's current round and returns the visibility vectors.
std::vector<uint64_t> trace_round(const Part& part, const Shooter& shooter, float epsilon, const SegmentTracer& trace);

}  // namespace lf::radiosity
