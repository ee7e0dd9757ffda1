#pragma once
// What every actor needs to see the same picture: the scene, the camera, the image. The farm's graph and placement
// (farm/farm_spec.hpp) build on these; CONFIG carries them to each actor.
#include <array>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "core/result.hpp"
#include "core/value.hpp"

namespace lf {

// Where in the script something was declared, so that a later error can point at it.
struct SourceLoc {
  std::string file;
  int line = 0;
  std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

// Whether `v` has the form of a list of material changes (SceneSpec::materials, a job frame's): maps, each with a
// string "name". What each change says is the scene's to check (Scene::apply_material_overrides).
bool is_material_change_list(const Value& v);

struct SceneSpec {
  std::string builtin;  // e.g. "cornell"; empty when file is set
  std::string file;     // absolute path of an OBJ or glTF file
  Value::Array lights;  // lights the script adds: {quad = {4 corners}, radiance} | {sphere, radius, radiance} |
                        // {point, intensity}
  Value::Array materials;  // the script's changes to named materials: {name, emission?, kd?, ks?, ns?, ior?, type?}
  Value::Array shapes;     // geometry the script adds: {name, plane = {x,y,z}, normal?, size?} | {name, sphere, radius},
                           // each with material? (a scene material's name; else one named after the shape)
  // Set by the director for its actors: the scene, lights included, as shipped to the actor's host
  // (render/scene/scene_file.hpp); an actor then reads that and never the OBJ file.
  std::string cache;  // its path on the actor's host
  std::string hash;   // its content hash
  SourceLoc loc;
  Value to_value() const;
  static SceneSpec from_value(const Value& v);
};

struct CameraSpec {
  std::array<double, 3> eye{278, 273, -800};
  std::array<double, 3> at{278, 273, 0};
  std::array<double, 3> up{0, 1, 0};
  double fov = 39.3;  // vertical, degrees
  // A thin lens (0: a pinhole): the lens's diameter in scene units, and the distance along the view at which the
  // image is sharp (0: the distance from eye to at).
  double aperture = 0;
  double focus_distance = 0;
  // camera { } with its ranges and rules (eye and at apart, up not along the view): how a script is read and how
  // an actor reads CONFIG back. Throws ParamError.
  static CameraSpec read(const ParamTable& p) { return read(p, CameraSpec{}); }
  // The same over other defaults (a scene file's camera, which the table's own keys then change).
  static CameraSpec read(const ParamTable& p, const CameraSpec& defaults);
  Value to_value() const;
  static Result<CameraSpec> from_value(const Value& v);
};

struct ImageSpec {
  int width = 256;
  int height = 256;
  int spp = 4;
  // Of each pixel's spp camera samples, how many the lighting shades (the first ones; 0: all). The others only
  // see what the camera sees directly (emitters and the edges of lit ones): cheap samples that antialias torches
  // and lamps without paying for their lighting. The pixel is then mean(emission over spp) + mean(lighting over
  // shade_spp), both unbiased.
  int shade_spp = 0;
  int shaded_per_pixel() const { return shade_spp > 0 && shade_spp < spp ? shade_spp : spp; }
  // Adaptive sampling (0: off): a pixel whose lighting is still noisy after its shade_spp samples (the standard
  // error its mean would have, from its neighbours' spread, above adaptive_threshold of display white at
  // `exposure`) gets more of its samples shaded, in doublings of shade_spp, up to adaptive_spp: the rest of its spp
  // first, then the next of its sequence (render/shading/tile_kernel.hpp, adaptive_shaded_counts).
  // Default: on, up to 16 x spp (default_adaptive_spp); 0 turns it off.
  int adaptive_spp = 0;
  double adaptive_threshold = 0.05;
  static int default_adaptive_spp(const ImageSpec& image);
  // Seen samples a pixel on a light's outline takes in all (render/shading/emitter_edges.hpp): its spp, then more
  // that only see what the camera sees directly, where whether a sample lands on a small light is the pixel's
  // largest noise. Default 16 x spp, at most 4096 (default_edge_spp); spp or fewer: none.
  int edge_spp = 0;
  static int default_edge_spp(int spp);
  int tile = 32;
  // Seconds a frame may take (0: no limit): it renders passes of spp samples a pixel (pass p: samples p*spp up to
  // (p+1)*spp, the continuation of each pixel's sequence) while the time lasts, and the image is the mean of the
  // passes completed, at least one.
  double time_limit = 0;
  std::string output = "out.png";
  // For 8-bit outputs (PNG, TIFF) only: scale by 2^exposure, then map to [0, 1] ("clamp", "reinhard", "aces").
  // EXR stays linear and untouched.
  double exposure = 0;
  std::string tonemap = "clamp";
  // The numbers camera, direct light and path tracing draw: "independent" (PCG32) or "sobol" (Owen-scrambled
  // Sobol points, render/shading/sampler.hpp).
  std::string sampler = "sobol";
  // image { } with its ranges, defaults and rules (shade_spp at most spp; adaptive sampling needs 2 or more shaded
  // samples): how a script is read and how an actor reads CONFIG back. Throws ParamError.
  static ImageSpec read(const ParamTable& p);
  static const std::vector<std::string>& tonemaps();  // clamp, reinhard, aces
  Value to_value() const;  // what read() takes back
  static Result<ImageSpec> from_value(const Value& v);
};

}  // namespace lf
