#include "farm/job.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <set>

#include "core/params.hpp"
#include "render/scene/scene.hpp"

namespace lf {

namespace {

constexpr int kMaxFrame = 10'000'000;
constexpr int64_t kMaxFrames = 1'000'000;

using Vec = std::array<double, 3>;

std::string number_text(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

Vec lerp(const Vec& a, const Vec& b, double t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
}

// Cubic Hermite on [0, 1] from p0 to p1 with end tangents m0, m1 (already scaled to the segment).
Vec hermite(const Vec& p0, const Vec& m0, const Vec& p1, const Vec& m1, double t) {
  const double t2 = t * t, t3 = t2 * t;
  const double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + t, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
  Vec r;
  for (int i = 0; i < 3; ++i) r[i] = h00 * p0[i] + h10 * m0[i] + h01 * p1[i] + h11 * m1[i];
  return r;
}

// The point's velocity (per frame) at key i: the neighbouring keys' difference over their frame distance.
Vec velocity(const std::vector<CameraKey>& keys, size_t i, Vec CameraSpec::* point) {
  const size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, keys.size() - 1);
  const double span = keys[b].frame - keys[a].frame;
  const Vec& pa = keys[a].camera.*point;
  const Vec& pb = keys[b].camera.*point;
  return {(pb[0] - pa[0]) / span, (pb[1] - pa[1]) / span, (pb[2] - pa[2]) / span};
}

// Reads a camera table over `base` and checks it is one (CameraSpec::read's rules), naming `what`.
// A key's `frame` is its own, not the camera's, and is left out of the camera's table.
CameraSpec read_camera_table(const Value& table, const CameraSpec& base, const std::string& what) {
  if (!table.is_map()) throw ParamError(what + " must be a table of camera keys (eye, at, up, fov, ...)");
  Value::Map keys = table.as_map();
  keys.erase("frame");
  ParamTable p(std::move(keys), what);
  CameraSpec c;
  try {
    c = CameraSpec::read(p, base);
    p.report_unused();
  } catch (const ParamError& e) {
    throw ParamError(what + ": " + e.what());
  }
  return c;
}

// CameraSpec::read's rules on a camera made by interpolation.
void check_camera(const CameraSpec& c, const std::string& what) {
  Value::Map m = c.to_value().as_map();
  try {
    (void)CameraSpec::read(ParamTable(m, "camera"));
  } catch (const ParamError& e) {
    throw ParamError(what + ": " + e.what());
  }
}

}  // namespace

void read_frames(const ParamTable& p, JobSpec& job) {
  job.first = static_cast<int>(p.get_int("first", 1, -kMaxFrame, kMaxFrame));
  job.last = static_cast<int>(p.get_int("last", job.first, -kMaxFrame, kMaxFrame));
  job.step = static_cast<int>(p.get_int("step", 1, 1, kMaxFrame));
  job.in_flight = p.get_bool("in_flight", true);
  p.report_unused();
  if (job.last < job.first)
    throw ParamError("frames: last (" + std::to_string(job.last) + ") comes before first (" + std::to_string(job.first) + ")");
  if ((int64_t{job.last} - job.first) / job.step >= kMaxFrames)
    throw ParamError("frames: more than " + std::to_string(kMaxFrames) + " frames");
}

std::vector<int> JobSpec::numbers() const {
  std::vector<int> n;
  for (int64_t f = first; f <= last; f += step) n.push_back(static_cast<int>(f));
  return n;
}

std::vector<int> parse_frame_list(const std::string& text) {
  std::set<int> frames;
  auto fail = [&](const std::string& why) -> std::vector<int> {
    throw ParamError("--frames '" + text + "': " + why + " (give numbers and ranges, e.g. 1-240,300)");
  };
  auto number = [&](const std::string& s) {
    if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](unsigned char ch) { return std::isdigit(ch); }))
      fail("'" + s + "' is not a frame number");
    return std::stoi(s);
  };
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    const size_t dash = item.find('-');
    const int a = number(item.substr(0, dash));
    const int b = dash == std::string::npos ? a : number(item.substr(dash + 1));
    if (b < a) fail("range " + item + " runs backwards");
    if (b - a >= kMaxFrame) fail("range " + item + " is longer than " + std::to_string(kMaxFrame) + " frames");
    for (int f = a; f <= b; ++f) frames.insert(f);
    begin = end + 1;
  }
  return {frames.begin(), frames.end()};
}

bool has_frame_pattern(const std::string& output) {
  const size_t slash = output.find_last_of('/');
  return output.find('#', slash == std::string::npos ? 0 : slash + 1) != std::string::npos;
}

std::string frame_output(const std::string& pattern, int number) {
  const size_t slash = pattern.find_last_of('/');
  const size_t name = slash == std::string::npos ? 0 : slash + 1;
  const size_t last = pattern.find_last_of('#');
  if (last == std::string::npos || last < name) return pattern;
  size_t first = last;
  while (first > name && pattern[first - 1] == '#') --first;
  const std::string digits = std::to_string(number < 0 ? -number : number);
  const size_t width = last - first + 1;
  const std::string zeros(digits.size() < width ? width - digits.size() : 0, '0');
  return pattern.substr(0, first) + (number < 0 ? "-" : "") + zeros + digits + pattern.substr(last + 1);
}

CameraSpec interpolate_camera(const std::vector<CameraKey>& keys, double frame) {
  if (keys.empty()) throw ParamError("camera: keys is empty");
  if (keys.size() == 1 || frame <= keys.front().frame) return keys.front().camera;
  if (frame >= keys.back().frame) return keys.back().camera;
  size_t i = 0;
  while (keys[i + 1].frame < frame) ++i;
  const CameraKey& k0 = keys[i];
  const CameraKey& k1 = keys[i + 1];
  const double span = k1.frame - k0.frame;
  const double t = (frame - k0.frame) / span;
  auto curve = [&](Vec CameraSpec::* point) {
    Vec m0 = velocity(keys, i, point), m1 = velocity(keys, i + 1, point);
    for (int c = 0; c < 3; ++c) m0[c] *= span, m1[c] *= span;
    return hermite(k0.camera.*point, m0, k1.camera.*point, m1, t);
  };
  CameraSpec c = k0.camera;
  c.eye = curve(&CameraSpec::eye);
  c.at = curve(&CameraSpec::at);
  c.up = lerp(k0.camera.up, k1.camera.up, t);
  c.fov = k0.camera.fov + (k1.camera.fov - k0.camera.fov) * t;
  c.aperture = k0.camera.aperture + (k1.camera.aperture - k0.camera.aperture) * t;
  c.focus_distance = k0.camera.focus_distance + (k1.camera.focus_distance - k0.camera.focus_distance) * t;
  return c;
}

std::vector<CameraKey> read_camera_keys(const std::vector<Value>& keys, const CameraSpec& base) {
  std::vector<CameraKey> out;
  for (size_t i = 0; i < keys.size(); ++i) {
    const std::string what = "camera: keys[" + std::to_string(i + 1) + "]";
    const Value* frame = keys[i].is_map() ? keys[i].find("frame") : nullptr;
    if (keys[i].is_map() && !frame) throw ParamError(what + " has no frame");
    CameraKey k;
    k.camera = read_camera_table(keys[i], base, what);
    k.frame = frame->is_number() ? frame->as_double() : NAN;
    if (!std::isfinite(k.frame)) throw ParamError(what + ": frame must be a number");
    if (!out.empty() && !(k.frame > out.back().frame))
      throw ParamError(what + ": frame " + number_text(k.frame) + " does not come after the key before it (" +
                       number_text(out.back().frame) + "); keys go in order of frame");
    out.push_back(std::move(k));
  }
  return out;
}

std::vector<FrameSpec> expand_frames(const JobSpec& job, const CameraSpec& base, const std::string& output,
                                     const std::vector<int>& selection) {
  const std::vector<int> numbers = job.numbers();
  const std::set<int> known(numbers.begin(), numbers.end());
  for (int f : selection)
    if (!known.count(f))
      throw ParamError("--frames: frame " + std::to_string(f) + " is not one of the script's frames (" +
                       std::to_string(job.first) + "-" + std::to_string(job.last) +
                       (job.step > 1 ? " by " + std::to_string(job.step) : std::string()) + ")");
  const std::set<int> chosen(selection.begin(), selection.end());
  if (numbers.size() > 1 && !has_frame_pattern(output))
    throw ParamError("image: output '" + output + "' has no #### where the frame number goes, so every frame of the "
                     "job's " + std::to_string(numbers.size()) + " would write the same file (e.g. \"walk.####.png\")");
  const std::vector<CameraKey> keys = read_camera_keys(job.camera_keys, base);
  // A camera the scene file animates: every frame's view at its time in the file.
  std::vector<CameraSpec> file_views;
  if (job.file_camera) {
    const JobSpec::FileCameraPath& path = *job.file_camera;
    if (!keys.empty() || !job.camera_of_frame.empty())
      throw ParamError("camera: the scene file animates camera '" + path.name + "', and " +
                       (keys.empty() ? "frames { camera }" : "camera { keys }") +
                       " moves it too: give the camera animation = false to follow " + (keys.empty() ? "the function" : "the keys"));
    std::vector<double> seconds;
    for (int n : numbers) seconds.push_back(n / path.fps);
    auto views = Scene::gltf_camera_views(path.file, path.index, seconds);
    if (!views) throw ParamError("camera: " + views.error().message);
    file_views = std::move(*views);
  }
  std::vector<FrameSpec> frames;
  for (int n : numbers) {
    FrameSpec f;
    f.number = n;
    f.selected = chosen.empty() || chosen.count(n) > 0;
    f.output = frame_output(output, n);
    if (auto it = job.materials_of_frame.find(n); it != job.materials_of_frame.end()) f.materials = it->second;
    if (auto it = job.camera_of_frame.find(n); it != job.camera_of_frame.end()) {
      f.camera = read_camera_table(it->second, base, "frames: the camera function's table for frame " + std::to_string(n));
    } else if (!keys.empty()) {
      f.camera = interpolate_camera(keys, n);
      check_camera(f.camera, "camera: keys at frame " + std::to_string(n));
    } else if (!file_views.empty()) {
      f.camera = base;
      const CameraSpec& v = file_views[frames.size()];
      f.camera.eye = v.eye, f.camera.at = v.at, f.camera.up = v.up;
    } else {
      f.camera = base;
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

}  // namespace lf
