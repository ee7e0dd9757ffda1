#pragma once
// What a farm script's tables mean, read without Lua: each of scene { }, host { }, material { }, light { }, shape { }
// and farm { } has one reader here over a ParamTable, with its ranges, defaults and the rules between its fields (the
// image and the camera are read by ImageSpec::read and CameraSpec::read in core/, which CONFIG uses too). A bad
// value, or a parameter the table does not know, throws ParamError with the message the user sees; the Lua binding
// adds the script's file and line.
// Relative paths are taken from `script_dir`, so a farm travels with its files.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/params.hpp"
#include "farm/farm_spec.hpp"

namespace lf {

// scene { builtin = "cornell" } | scene { file = "room.obj" }: exactly one, the file there.
SceneSpec read_scene(const ParamTable& p, const std::filesystem::path& script_dir);
// The names of the scene's materials (an OBJ's MTL without loading its geometry, or a built-in scene's).
std::vector<std::string> scene_material_names(const SceneSpec& scene);

// host "name" { launcher, address, user, port, ssh_config, ssh_name, lightfarm }.
HostSpec read_host(const std::string& name, const ParamTable& p, const std::filesystem::path& script_dir);

// material "name" { emission, kd, ks, mirror, tf, ns, ior, type }: the change as the scene applies it
// ({name, ...}), checked against `scene_materials` and by the scene's own rules (kd + ks + mirror at most 1).
// camera { gltf = "Name" | index, ... }: a glTF scene file's perspective camera (by its node's name, or its place
// among the file's cameras from 0), which the table's other keys then change; without `gltf`, CameraSpec::read.
// `job`: where a camera the file animates is noted (JobSpec::file_camera), unless the table says animation = false.
CameraSpec read_camera(const ParamTable& p, const SceneSpec& scene, JobSpec* job = nullptr);

Value read_material_change(const std::string& name, const ParamTable& p, const std::vector<std::string>& scene_materials);

// light { quad | sphere + radius | point, radiance | intensity }: the light, checked by the scene's own reader.
Value read_light(const Value& light);

// environment { map = "sky.exr", intensity = 1, rotation = 0, camera = true } | environment { radiance = {r, g, b},
// intensity, camera }: the light at infinity (render/lights/environment.hpp), the map there; rotation in degrees
// about the up axis; camera = false hides it from camera rays. As the scene adds it: {environment = {...}}.
Value read_environment(const ParamTable& p, const std::filesystem::path& script_dir);
// A job frame's environment (frames { environment = function(frame) }): a map's intensity and rotation (degrees),
// or a constant one's radiance and intensity; the map and whether the camera sees it are the declared
// environment's. {environment = {...}} with only the keys given.
Value read_frame_environment(const ParamTable& p);
// A job frame's point light (frames { lights = function(frame) }): its new position (`point`) and/or `intensity`
// (W/sr); {point?, intensity?} with only the keys given.
Value read_frame_point_light(const ParamTable& p);
// sun { direction = {x, y, z}, irradiance = {r, g, b}, angle = 0.526 }: a disc towards `direction`, `angle` degrees
// across, giving `irradiance` (W/m^2) to a surface facing it. As the scene adds it: {sun = {...}}.
Value read_sun(const ParamTable& p);

// shape "name" { plane = {x,y,z}, normal = {0,1,0}, size | sphere = {x,y,z}, radius, and material = "a scene
// material" or the shape's own material's parameters (those of material { }) }. The shape as the scene adds it,
// and, when the shape has a material of its own with parameters, that material's change; `materials` (the
// scene's names so far) gains the shape's own material.
struct ShapeRead {
  Value shape;
  std::optional<Value> material_change;
};
ShapeRead read_shape(const std::string& name, const Value::Map& table, std::vector<std::string>& materials);

// farm { heartbeat_timeout, request_timeout, director_address, security, monitor, host_agents, light_paths },
// over what `spec` holds.
void read_farm_settings(const ParamTable& p, FarmSpec& spec);

// Where a plug-in's `program` runs from: a path with a slash is relative to the script; a bare name is looked up
// on PATH. Empty when it is not there or not executable.
std::string resolve_program(const std::string& program, const std::filesystem::path& script_dir);

}  // namespace lf
