#pragma once
// Which light paths a LightOp's answer counts, in Heckbert's notation ("Adaptive radiosity textures for
// bidirectional ray tracing", SIGGRAPH 1990): a path is written from the light to the point being shaded, one letter
// per scattering event, the last one at the shaded point itself. L D G is light reflected by a diffuse surface and
// then by the shaded point's glossy lobe; L S+ D is a caustic; a lone L is the point's own emission.
//
// A LightPaths holds, for every path of up to kMaxEvents events over the lobes D (diffuse), G (glossy) and S (mirror
// and glass), how many times an answer counts it: 1 where the op computes that light, 0 where it leaves it out, 2
// where two of its parts both add it. An op states its set from its inputs' (LightOp::paths); the farm composes the
// sets along the network and checks what reaches the camera (farm/light_path_check.hpp). Paths longer than
// kMaxEvents are not tracked: their light is a product of that many reflectances.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lf {

enum class Lobe : uint8_t { diffuse, glossy, specular };
inline constexpr int kLobeCount = 3;
inline constexpr char kLobeLetters[kLobeCount + 1] = "DGS";

// A set of lobes, e.g. the lobes a scene's materials have.
struct Lobes {
  bool has[kLobeCount] = {false, false, false};
  static Lobes all() { return Lobes{{true, true, true}}; }
  static Lobes of(std::initializer_list<Lobe> lobes) {
    Lobes l;
    for (Lobe x : lobes) l.has[static_cast<int>(x)] = true;
    return l;
  }
  bool contains(Lobe x) const { return has[static_cast<int>(x)]; }
};

class Scene;
struct Material;

// The lobes a material has: D (a Lambert lobe, or a metal_rough material's base and multiply scattered light),
// G (a Phong lobe, a metal_rough material's specular lobe and rough glass), S (mirror, glass, a mirror term).
Lobes material_lobes(const Material& m);

// Where an op's answer can be other than zero: at a point whose material has one of `lobes` (the last events of the
// paths it counts), and, with `emission`, at a point that emits (the lone L). The runtime asks an input only about
// the points its answer reaches (CONFIG inputs[i].answers_at, docs/PROTOCOL.md).
struct AnswerEnds {
  Lobes lobes;
  bool emission = false;
  bool reaches(const Material& m) const;
  // "L" for emission, then the lobes' letters in DGS order: "LD", "G", "" (nowhere).
  std::string letters() const;
  // nullopt for a letter that is not one of L, D, G, S.
  static std::optional<AnswerEnds> parse(std::string_view letters);
};

// The lobes the scene's materials have where at least one triangle uses them, and whether anything emits.
struct SceneLobes {
  Lobes lobes;
  bool emits = false;
  std::vector<std::string> materials[kLobeCount];  // names of the materials with each lobe, in material order
  // Of the materials with a D lobe, those whose D is a metal_rough material's (its base and its conductor's
  // multiply scattered light, which weigh light by its elevation): `irradiance` and path tracing light it; the
  // radiosity solution and the directional cache, which hold Lambert light only, do not.
  std::vector<std::string> elevation_weighted;
};
// `materials`: the scene's materials as a job's frame changes them (the same list, in the same order).
SceneLobes scene_lobes(const Scene& scene, const std::vector<Material>* materials = nullptr);

class LightPaths {
 public:
  static constexpr int kMaxEvents = 6;
  // Number of paths of 0..kMaxEvents events: (3^(kMaxEvents+1) - 1) / 2.
  static constexpr size_t kPathCount = 1093;

  // Counts nothing.
  LightPaths() : counts_(kPathCount, 0.0f) {}
  // The point's own emission: L.
  static LightPaths emission();
  // Every path of `min_events`..`max_events` events whose letters are all in `lobes` (max beyond kMaxEvents: all up
  // to it), counted once.
  static LightPaths every(int min_events, int max_events, Lobes lobes = Lobes::all());

  // Each path w becomes w X: light these paths bring to a point, scattered once more at a point with lobe X.
  LightPaths then(Lobe x) const;
  // Each path w becomes w X^k for k in min..max.
  LightPaths then_repeated(Lobe x, int min, int max) const;
  // Where an answer that counts these paths can be other than zero.
  AnswerEnds ends() const;
  // Only the paths whose last event is in `lobes` (and the lone L where `with_emission`): what an answer holds at a
  // point that has those lobes.
  LightPaths ending_in(Lobes lobes, bool with_emission) const;

  LightPaths& operator+=(const LightPaths& o);
  LightPaths operator+(const LightPaths& o) const { return LightPaths(*this) += o; }
  LightPaths operator*(float weight) const;

  // How many times `path` ("L", "LDG", ...) is counted; 0 for one longer than kMaxEvents.
  float count(std::string_view path) const;
  // Every path (as "L...") whose count is not zero, shortest first, in letter order.
  std::vector<std::string> counted() const;
  bool empty() const;

  // Iteration over every path index: its events and count.
  static std::string path_of(size_t index);
  float count_at(size_t index) const { return counts_[index]; }
  // Whether every letter of path `index` is in `lobes`.
  static bool made_of(size_t index, Lobes lobes);

  // A short description for a diagram's arrow: per number of events, "L(D|G|S){1,5}D" where every path of that
  // shape is there, else the paths themselves (or how many there are).
  std::string summary() const;

 private:
  static size_t index_of(std::string_view events);  // letters after the L
  std::vector<float> counts_;
};

}  // namespace lf
