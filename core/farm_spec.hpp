#pragma once
// FarmSpec: what a farm script describes once evaluated — scene, camera, image, the actor graph, placement.
// The Lua layer builds it; the director validates, launches and drives it; actors receive their part as CONFIG.
#include <array>
#include <string>
#include <vector>

#include "core/value.hpp"

namespace lf {

// Where in the script something was declared, so that a later error can point at it.
struct SourceLoc {
  std::string file;
  int line = 0;
  std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

struct SceneSpec {
  std::string builtin;  // e.g. "cornell"; empty when file is set
  std::string file;     // absolute path of an OBJ file
  Value::Array lights;  // lights the script adds: {quad = {4 corners}, radiance} | {sphere, radius, radiance} |
                        // {point, intensity}
  SourceLoc loc;
  Value to_value() const;
  static SceneSpec from_value(const Value& v);
};

struct CameraSpec {
  std::array<double, 3> eye{278, 273, -800};
  std::array<double, 3> at{278, 273, 0};
  std::array<double, 3> up{0, 1, 0};
  double fov = 39.3;  // vertical, degrees
  Value to_value() const;
  static CameraSpec from_value(const Value& v);
};

struct ImageSpec {
  int width = 256;
  int height = 256;
  int spp = 4;
  int tile = 32;
  std::string output = "out.png";
  Value to_value() const;
  static ImageSpec from_value(const Value& v);
};

struct HostSpec {
  std::string name = "local";
  std::string launcher = "local";
  std::string address = "127.0.0.1";
  SourceLoc loc;
};

// One actor process. Renderers are expanded from `renderers { count = N }` into N specs.
struct ActorSpec {
  std::string name;       // unique in the farm, e.g. "direct" or "renderer-1"
  std::string kind;       // "renderer" or a LightOp kind such as "direct"
  Value::Map params;      // the script's parameters, minus wiring keys
  Value::Map runtime;     // settings for the runtime that wraps the actor, not the algorithm (e.g. slowdown)
  std::vector<int> inputs;  // indices into FarmSpec::actors; a multiplexer's inputs are its replicas
  std::string host = "local";
  SourceLoc loc;
  bool is_renderer() const { return kind == "renderer"; }
  bool is_multiplexer() const { return kind == "multiplexer"; }
};

struct FarmSpec {
  std::string script;
  SceneSpec scene;
  CameraSpec camera;
  ImageSpec image;
  std::vector<HostSpec> hosts;
  std::vector<ActorSpec> actors;
  int lighting = -1;  // index of the MasterLightOp the renderers ask
  double heartbeat_timeout = 10.0;  // seconds of silence before an actor counts as dead
  double request_timeout = 120.0;   // seconds a shading request may wait for its answer
  int renderer_count() const;
  // Index of the multiplexer whose replica actor `i` is, or -1.
  int pool_of(int i) const;
};

}  // namespace lf
