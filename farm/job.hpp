#pragma once
// A render job: the frames one farm renders in turn (frames { first, last, step } and --frames), the camera of
// each (camera { keys } interpolated, or a function of the frame the script evaluates) and where each frame's
// image goes (image { output = "walk.####.png" }). Data only: the script fills JobSpec, expand_frames makes the
// list the director renders (actors/director/frame_loop.hpp).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/specs.hpp"
#include "core/value.hpp"

namespace lf {

// One frame to render.
struct FrameSpec {
  int number = 1;
  CameraSpec camera;
  std::string output;     // the image's output with the frame number in place of its ####
  bool selected = true;   // to render (--frames); the job's first frame is kept either way, for its camera
  // frames { materials }: the frame's changes to named materials over the script's scene (each as material { }
  // reads it, by name), whole for every frame (not a change from the frame before). Empty: the scene as shipped.
  Value::Array materials;
};

// A camera keyframe: camera { keys = { {frame = 1, eye = ..., at = ...}, ... } }.
struct CameraKey {
  double frame = 1;
  CameraSpec camera;
};

struct JobSpec {
  bool declared = false;  // frames { } was given: a job, with a record of finished frames (even of one frame)
  int first = 1, last = 1, step = 1;
  // frames { in_flight }: a frame may begin while the last one's final tiles are out (where the farm can:
  // actors/director/frame_loop.hpp); false: one frame at a time.
  bool in_flight = true;
  std::vector<Value> camera_keys;        // camera { keys }, each key's table as written
  SourceLoc keys_loc;
  std::map<int, Value> camera_of_frame;  // frames { camera = function(frame) }: each frame's table as returned
  std::map<int, Value::Array> materials_of_frame;  // frames { materials = function(frame) }: FrameSpec::materials
  // camera { gltf = ... } naming a camera the scene file animates: frame n's view is the file's at n / fps seconds
  // (Blender exports its frame f at f / fps), its eye, at and up over camera { }'s other keys.
  struct FileCameraPath {
    std::string file;
    size_t index = 0;  // in the file's catalogue of cameras
    std::string name;
    double fps = 24;
  };
  std::optional<FileCameraPath> file_camera;
  SourceLoc loc;
  // The job's frame numbers, first to last by step.
  std::vector<int> numbers() const;
};

class ParamTable;

// frames { first, last, step } into `job` (its camera function is the binding's to call): the ranges, last not
// before first, at most a million frames. Throws ParamError.
void read_frames(const ParamTable& p, JobSpec& job);

// "1-240,300" (numbers and ranges, comma-separated) -> the frame numbers, ascending, each once. Throws ParamError.
std::vector<int> parse_frame_list(const std::string& text);

// Whether an output names where the frame number goes: a run of '#' in its file name.
bool has_frame_pattern(const std::string& output);
// The output of frame `number`: the last run of '#' in the file name replaced by the number, zero-padded to the
// run's length ("walk.####.png", 7 -> "walk.0007.png"; a longer number is written whole).
std::string frame_output(const std::string& pattern, int number);

// The camera at `frame` along keys sorted by frame: eye and at follow a Catmull-Rom spline through the keys' points
// (tangents from the neighbouring keys, scaled by the keys' frame spacing, so uneven spacing keeps the speed
// smooth; one-sided at the ends), up, fov, aperture and focus distance are linear between keys; before the first
// key and after the last the camera holds. Throws ParamError if the result is no camera (eye on at, up along the
// view).
CameraSpec interpolate_camera(const std::vector<CameraKey>& keys, double frame);
// camera { keys }: each key read over `base` (the camera table's other keys), with its frame; keys strictly
// ascending by frame. Throws ParamError.
std::vector<CameraKey> read_camera_keys(const std::vector<Value>& keys, const CameraSpec& base);

// The job's frames, each with its camera and output, those in `selection` (--frames; empty: all) selected to render,
// and the job's first frame always listed first: the farm is set up seen from it, whichever frames render (so a
// setup kept over the frames is the same in every run of the job). Throws ParamError: a selected frame that is not
// one of the job's, an output without #### for a job of several frames, a key or a function's camera that is no
// camera.
std::vector<FrameSpec> expand_frames(const JobSpec& job, const CameraSpec& base, const std::string& output,
                                     const std::vector<int>& selection);

}  // namespace lf
