#include "render/shading/light_paths.hpp"

#include "render/scene/scene.hpp"

#include <algorithm>
#include <bitset>
#include <optional>

namespace lf {

Lobes material_lobes(const Material& m) {
  return Lobes{{
      m.type == Material::Type::metal_rough ? m.has_diffuse_lobe()
                                            : (m.type == Material::Type::diffuse || m.type == Material::Type::glossy) &&
                                                  (!is_black(m.kd) || m.kd_map >= 0),
      (m.type == Material::Type::glossy && !is_black(m.ks)) || m.type == Material::Type::metal_rough,
      m.type == Material::Type::glass || (m.type == Material::Type::mirror && !is_black(m.ks)) || m.has_mirror_term(),
  }};
}

bool AnswerEnds::reaches(const Material& m) const {
  if (emission && m.emissive()) return true;
  const Lobes has = material_lobes(m);
  for (int l = 0; l < kLobeCount; ++l)
    if (lobes.has[l] && has.has[l]) return true;
  return false;
}

std::string AnswerEnds::letters() const {
  std::string s = emission ? "L" : "";
  for (int l = 0; l < kLobeCount; ++l)
    if (lobes.has[l]) s += kLobeLetters[l];
  return s;
}

SceneLobes scene_lobes(const Scene& scene, const std::vector<Material>* materials) {
  std::vector<bool> used(scene.materials().size(), false);
  for (uint32_t t = 0; t < scene.triangle_count(); ++t) used[scene.material_of(t)] = true;
  SceneLobes out;
  out.emits = !scene.point_lights().empty() || (scene.environment() && scene.environment()->emits());
  for (size_t id = 0; id < used.size(); ++id) {
    if (!used[id]) continue;
    const Material& m = materials ? (*materials)[id] : scene.material(static_cast<uint32_t>(id));
    out.emits = out.emits || m.emissive();
    const Lobes has = material_lobes(m);
    for (int l = 0; l < kLobeCount; ++l)
      if (has.has[l]) {
        out.lobes.has[l] = true;
        out.materials[l].push_back(m.name);
      }
    if (has.contains(Lobe::diffuse) && m.type == Material::Type::metal_rough) out.elevation_weighted.push_back(m.name);

  }
  return out;
}

// Paths are numbered in bijective base 3: the lone L is 0 and w X is 3 w + X + 1, so a path's last event is
// (index - 1) mod 3, the path before it (index - 1) / 3, and the paths of k events follow those of k - 1.
namespace {

constexpr size_t first_of(int events) {  // the index of the first path of that many events
  size_t first = 0;
  for (int k = 0; k < events; ++k) first = 3 * first + 1;
  return first;
}
static_assert(first_of(LightPaths::kMaxEvents + 1) == LightPaths::kPathCount);

int lobe_of(char c) {
  for (int i = 0; i < kLobeCount; ++i)
    if (kLobeLetters[i] == c) return i;
  return -1;
}

// Index of path w followed by lobe x, or none past the longest paths tracked.
std::optional<size_t> appended(size_t index, int x) {
  const size_t next = 3 * index + static_cast<size_t>(x) + 1;
  return next < LightPaths::kPathCount ? std::optional<size_t>(next) : std::nullopt;
}

int last_lobe(size_t index) { return static_cast<int>((index - 1) % 3); }

}  // namespace

std::optional<AnswerEnds> AnswerEnds::parse(std::string_view letters) {
  AnswerEnds e;
  for (char c : letters) {
    if (c == 'L') {
      e.emission = true;
      continue;
    }
    const int l = lobe_of(c);
    if (l < 0) return std::nullopt;
    e.lobes.has[l] = true;
  }
  return e;
}

AnswerEnds LightPaths::ends() const {
  AnswerEnds e;
  e.emission = counts_[0] != 0;
  for (size_t i = 1; i < kPathCount; ++i)
    if (counts_[i] != 0) e.lobes.has[last_lobe(i)] = true;
  return e;
}

std::string LightPaths::path_of(size_t index) {
  std::string events;
  for (; index > 0; index = (index - 1) / 3) events.insert(events.begin(), kLobeLetters[last_lobe(index)]);
  return "L" + events;
}

bool LightPaths::made_of(size_t index, Lobes lobes) {
  for (; index > 0; index = (index - 1) / 3)
    if (!lobes.has[last_lobe(index)]) return false;
  return true;
}

size_t LightPaths::index_of(std::string_view events) {
  size_t index = 0;
  for (char c : events) index = 3 * index + static_cast<size_t>(lobe_of(c)) + 1;
  return index;
}

LightPaths LightPaths::emission() {
  LightPaths p;
  p.counts_[0] = 1;
  return p;
}

LightPaths LightPaths::every(int min_events, int max_events, Lobes lobes) {
  LightPaths p;
  for (size_t i = first_of(std::max(0, min_events)); i < first_of(std::min(max_events, kMaxEvents) + 1); ++i)
    if (made_of(i, lobes)) p.counts_[i] = 1;
  return p;
}

LightPaths LightPaths::then(Lobe x) const {
  LightPaths p;
  for (size_t i = 0; i < kPathCount; ++i)
    if (auto next = appended(i, static_cast<int>(x))) p.counts_[*next] = counts_[i];
  return p;
}

LightPaths LightPaths::then_repeated(Lobe x, int min, int max) const {
  LightPaths sum, step = *this;
  for (int k = 0; k <= std::min(max, kMaxEvents); ++k) {
    if (k >= min) sum += step;
    step = step.then(x);
  }
  return sum;
}

LightPaths LightPaths::ending_in(Lobes lobes, bool with_emission) const {
  LightPaths p;
  p.counts_[0] = with_emission ? counts_[0] : 0.0f;
  for (size_t i = 1; i < kPathCount; ++i)
    if (lobes.has[last_lobe(i)]) p.counts_[i] = counts_[i];
  return p;
}

LightPaths& LightPaths::operator+=(const LightPaths& o) {
  for (size_t i = 0; i < kPathCount; ++i) counts_[i] += o.counts_[i];
  return *this;
}

LightPaths LightPaths::operator*(float weight) const {
  LightPaths p = *this;
  for (float& c : p.counts_) c *= weight;
  return p;
}

float LightPaths::count(std::string_view path) const {
  if (path.empty() || path[0] != 'L' || path.size() > static_cast<size_t>(kMaxEvents) + 1) return 0;
  for (char c : path.substr(1))
    if (lobe_of(c) < 0) return 0;
  return counts_[index_of(path.substr(1))];
}

std::vector<std::string> LightPaths::counted() const {
  std::vector<std::string> out;
  for (size_t i = 0; i < kPathCount; ++i)
    if (counts_[i] != 0) out.push_back(path_of(i));
  return out;
}

bool LightPaths::empty() const {
  return std::all_of(counts_.begin(), counts_.end(), [](float c) { return c == 0; });
}

namespace {

using PathBits = std::bitset<LightPaths::kPathCount>;

// A piece of a path pattern: one of some lobes, repeated.
struct Atom {
  const char* text;
  Lobes lobes;
  int min, max;  // repetitions; max 99: as many as fit
};
const Atom kAtoms[] = {
    {"(D|G|S)+", Lobes::all(), 1, 99}, {"(D|G|S)*", Lobes::all(), 0, 99}, {"(D|G|S)", Lobes::all(), 1, 1},
    {"(D|G)", {{true, true, false}}, 1, 1}, {"D", {{true, false, false}}, 1, 1},   {"G", {{false, true, false}}, 1, 1},
    {"S", {{false, false, true}}, 1, 1},   {"S*", {{false, false, true}}, 0, 99},  {"S+", {{false, false, true}}, 1, 99},
    {"D+", {{true, false, false}}, 1, 99},
};

PathBits extend(const PathBits& from, const Atom& atom) {
  PathBits out, step = from;
  for (int k = 0; k <= atom.max && step.any(); ++k) {
    if (k >= atom.min) out |= step;
    PathBits next;
    for (size_t i = 0; i < LightPaths::kPathCount; ++i)
      if (step[i])
        for (int x = 0; x < kLobeCount; ++x)
          if (atom.lobes.has[x])
            if (auto j = appended(i, x)) next[*j] = true;
    step = next;
  }
  return out;
}

struct Pattern {
  std::string text;
  int atoms;
  PathBits paths;
};

// Every pattern "L" followed by up to four atoms, with the paths (of at least one event) each stands for.
const std::vector<Pattern>& patterns() {
  static const std::vector<Pattern> all = [] {
    std::vector<Pattern> out;
    PathBits start;
    start[0] = true;
    std::vector<Pattern> level{{"L", 0, start}};
    for (int depth = 1; depth <= 4; ++depth) {
      std::vector<Pattern> next;
      for (const Pattern& p : level)
        for (const Atom& a : kAtoms) {
          // The lone L stays in while the pattern grows ("L(D|G|S)*D" needs it) and is left out of what it matches.
          Pattern q{p.text + a.text, depth, extend(p.paths, a)};
          if ((q.paths >> 1).none()) continue;
          next.push_back(q);
        }
      for (Pattern q : next) {
        q.paths[0] = false;
        out.push_back(std::move(q));
      }
      level = std::move(next);
    }
    return out;
  }();
  return all;
}

}  // namespace

std::string LightPaths::summary() const {
  PathBits wanted;
  for (size_t i = 1; i < kPathCount; ++i) wanted[i] = counts_[i] != 0;
  std::vector<std::string> parts;
  if (counts_[0] != 0) parts.push_back("L");
  // Greedily the pattern that covers most of what is left without standing for any path not counted; the shortest
  // pattern among equals.
  PathBits left = wanted;
  while (left.any() && parts.size() < 4) {
    const Pattern* best = nullptr;
    size_t best_count = 0;
    for (const Pattern& p : patterns()) {
      if ((p.paths & ~wanted).any()) continue;
      const size_t n = (p.paths & left).count();
      if (n > best_count || (n == best_count && best && n > 0 && p.atoms < best->atoms)) {
        best = &p;
        best_count = n;
      }
    }
    if (!best) break;
    parts.push_back(best->text);
    left &= ~best->paths;
  }
  if (left.any()) parts.push_back("and " + std::to_string(left.count()) + " more paths");
  if (parts.empty()) return "nothing";
  std::string s;
  for (const auto& p : parts) s += (s.empty() ? "" : " | ") + p;
  return s;
}

}  // namespace lf
