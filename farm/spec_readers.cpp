#include "farm/spec_readers.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <set>

#include "render/scene/scene.hpp"

namespace lf {

namespace fs = std::filesystem;

namespace {

// `file` relative to the script, made absolute; "" when no regular file is there.
std::string existing_file(const std::string& file, const fs::path& script_dir) {
  fs::path f(file);
  if (f.is_relative()) f = script_dir / f;
  std::error_code ec;
  return fs::is_regular_file(f, ec) ? fs::absolute(f).lexically_normal().string() : std::string();
}

std::string script_relative(const std::string& file, const fs::path& script_dir) {
  fs::path f(file);
  return (f.is_relative() ? script_dir / f : f).string();
}

}  // namespace

SceneSpec read_scene(const ParamTable& p, const fs::path& script_dir) {
  SceneSpec s;
  s.builtin = p.get_string("builtin", "", Scene::builtin_names());
  s.file = p.get_string("file", "");
  p.report_unused();
  if (s.builtin.empty() == s.file.empty())
    throw ParamError("scene needs exactly one of builtin = \"cornell\" or file = \"path.obj\"");
  if (!s.file.empty()) {
    const std::string found = existing_file(s.file, script_dir);
    if (found.empty()) throw ParamError("scene file '" + script_relative(s.file, script_dir) + "' not found");
    s.file = found;
  }
  return s;
}

std::vector<std::string> scene_material_names(const SceneSpec& scene) {
  std::vector<std::string> names;
  if (!scene.file.empty()) {
    if (auto listed = Scene::catalogue_file(scene.file)) names = listed->material_names;
  } else if (auto s = Scene::builtin_unlit(scene.builtin)) {
    for (const auto& m : s->materials()) names.push_back(m.name);
  }
  return names;
}

HostSpec read_host(const std::string& name, const ParamTable& p, const fs::path& script_dir) {
  HostSpec h;
  h.name = name;
  h.launcher = p.get_string("launcher", "local", {"local", "ssh", "slurm"});
  h.address = p.get_string("address", h.launcher == "local" ? "127.0.0.1" : "");
  if (h.launcher != "local") h.lightfarm = p.get_string("lightfarm", "");
  if (h.launcher == "ssh") {
    h.user = p.get_string("user", "");
    h.port = static_cast<int>(p.get_int("port", 0, 0, 65535));
    h.ssh_config = p.get_string("ssh_config", "");
    h.ssh_name = p.get_string("ssh_name", "");
  }
  p.report_unused();
  if (h.name == "local") throw ParamError("host 'local' is this machine; give another name");
  if (h.address.empty()) {
    const bool ssh = h.launcher == "ssh";
    throw ParamError("host '" + name + "': a" + (ssh ? "n ssh" : " slurm") + " host needs address = \"...\" (where its actors listen" +
                     (ssh ? " and ssh reaches it" : "") + ")");
  }
  if (!h.ssh_config.empty()) {
    const std::string found = existing_file(h.ssh_config, script_dir);
    if (found.empty())
      throw ParamError("host '" + name + "': ssh_config '" + script_relative(h.ssh_config, script_dir) + "' not found");
    h.ssh_config = found;
  }
  return h;
}

CameraSpec read_camera(const ParamTable& p, const SceneSpec& scene, JobSpec* job) {
  if (!p.has("gltf")) {
    for (const char* key : {"fps", "animation"})
      if (p.has(key)) throw ParamError(std::string("camera: ") + key + " is for a camera the scene file animates (gltf = ...)");
    return CameraSpec::read(p);
  }
  if (scene.file.empty() || !Scene::is_gltf_path(scene.file))
    throw ParamError("camera: gltf names a camera of the scene file, so it needs scene { file = \"x.gltf\" or \"x.glb\" } "
                     "before it");
  auto catalogue = Scene::catalogue_gltf(scene.file);
  if (!catalogue) throw ParamError("camera: " + catalogue.error().message);
  const auto& cameras = catalogue->cameras;
  std::string known;
  for (size_t i = 0; i < cameras.size(); ++i) known += (i ? ", " : "") + cameras[i].name;
  if (known.empty()) known = "none";
  const Value& which = p.values().at("gltf");
  const ObjCatalogue::FileCamera* found = nullptr;
  if (which.is_string()) {
    const std::string name = p.get_string("gltf", "");
    for (const auto& c : cameras)
      if (c.name == name) found = &c;
    if (!found) throw ParamError("camera: the scene file has no camera '" + which.as_string() + "' (its cameras: " + known + ")");
  } else {
    const auto index = p.get_int("gltf", 0, 0, 1 << 20);
    if (static_cast<size_t>(index) >= cameras.size())
      throw ParamError("camera: the scene file has " + std::to_string(cameras.size()) + " camera(s), so no camera " +
                       std::to_string(index) + " (its cameras: " + known + ")");
    found = &cameras[static_cast<size_t>(index)];
  }
  const double fps = p.get_float("fps", 24, 1e-3, 1e6);
  const bool follow = p.get_bool("animation", true);
  if (job && found->animated && follow)
    job->file_camera = JobSpec::FileCameraPath{scene.file, static_cast<size_t>(found - cameras.data()), found->name, fps};
  return CameraSpec::read(p, found->view);
}

Value read_material_change(const std::string& name, const ParamTable& p, const std::vector<std::string>& names) {
  if (std::find(names.begin(), names.end(), name) == names.end()) {
    std::string known;
    for (size_t i = 0; i < names.size() && i < 12; ++i) known += (i ? ", " : "") + names[i];
    if (names.size() > 12) known += ", ... (" + std::to_string(names.size()) + " in all)";
    throw ParamError("material '" + name + "' is not in the scene (its materials: " + (known.empty() ? "none" : known) + ")");
  }
  Value::Map change{{"name", name}};
  auto colour = [&](const char* key, double max) {
    if (!p.has(key)) return;
    const auto c = p.get_vec3(key, {0, 0, 0});
    for (double v : c)
      if (!(v >= 0 && v <= max))
        throw ParamError("material '" + name + "': " + key + " must be between 0 and " + (max > 1 ? "1e6" : "1") +
                         " in each channel");
    change[key] = Value::Array{c[0], c[1], c[2]};
  };
  colour("emission", 1e6);
  for (const char* key : {"kd", "ks", "mirror", "tf", "base_color"}) colour(key, 1);
  if (p.has("ns")) change["ns"] = p.get_float("ns", 0, 0, 1e6);
  if (p.has("ior")) change["ior"] = p.get_float("ior", 1.5, 1, 3);
  for (const char* key : {"metallic", "roughness", "transmission"})
    if (p.has(key)) change[key] = p.get_float(key, 0, 0, 1);
  if (p.has("type"))
    change["type"] = p.get_string("type", "diffuse", {"diffuse", "glossy", "mirror", "glass", "metal_rough"});
  p.report_unused();
  // The scene's own check (kd + ks + mirror at most 1) with the words it would use later.
  Scene probe;
  probe.add_material({name, {}, {}});
  if (auto st = probe.apply_material_overrides(Value::Array{Value(change)}); !st) throw ParamError(st.error().message);
  return change;
}

Value read_light(const Value& light) {
  if (!light.is_map()) throw ParamError("light needs quad, sphere or point");
  for (const auto& [key, v] : light.as_map())
    if (key != "quad" && key != "sphere" && key != "radius" && key != "point" && key != "radiance" && key != "intensity" &&
        key != "name")
      throw ParamError("light: unknown parameter '" + key + "' (known: quad, sphere, radius, radiance, point, intensity, name)");
  if (const Value* name = light.find("name"))
    if (!name->is_string() || name->as_string().empty()) throw ParamError("light: name must be a non-empty string");
  const int shapes = (light.find("quad") != nullptr) + (light.find("sphere") != nullptr) + (light.find("point") != nullptr);
  if (shapes != 1) throw ParamError("light needs exactly one of quad, sphere or point");
  for (const char* colour : {"radiance", "intensity"})
    if (const Value* c = light.find(colour); c && c->is_array())
      for (const auto& e : c->as_array())
        if (e.is_number() && e.as_double() < 0) throw ParamError(std::string("light: ") + colour + " must not be negative");
  Scene check;  // the scene's own reader says what is wrong, with the same words it would use later
  if (auto st = check.add_script_lights(Value::Array{light}); !st) {
    const std::string& why = st.error().message;
    throw ParamError("light: " + why.substr(why.find(':') + 2));
  }
  return light;
}

Value read_environment(const ParamTable& p, const fs::path& script_dir) {
  Value::Map e;
  const std::string map = p.get_string("map", "");
  if (!map.empty() == p.has("radiance"))
    throw ParamError("environment needs exactly one of map = \"sky.exr\" or radiance = {r, g, b}");
  if (!map.empty()) {
    const std::string found = existing_file(map, script_dir);
    if (found.empty()) throw ParamError("environment map '" + script_relative(map, script_dir) + "' not found");
    e["map"] = found;
    e["rotation"] = p.get_float("rotation", 0, -360, 360);
  } else {
    const auto c = p.get_vec3("radiance", {0, 0, 0});
    for (double v : c)
      if (!(v >= 0 && v <= 1e6)) throw ParamError("environment: radiance must be between 0 and 1e6 in each channel");
    e["radiance"] = Value::Array{c[0], c[1], c[2]};
  }
  e["intensity"] = p.get_float("intensity", 1, 0, 1e6);
  e["camera"] = p.get_bool("camera", true);
  p.report_unused();
  return Value(Value::Map{{"environment", Value(std::move(e))}});
}

Value read_frame_environment(const ParamTable& p) {
  if (p.has("map"))
    throw ParamError("environment: a frame cannot change the map (it is shipped with the scene once): declare it with "
                     "environment { map = ... } and change its intensity or rotation");
  if (p.has("camera")) throw ParamError("environment: whether the camera sees it is the declared environment's, for every frame");
  Value::Map e;
  if (p.has("radiance")) {
    const auto c = p.get_vec3("radiance", {0, 0, 0});
    for (double v : c)
      if (!(v >= 0 && v <= 1e6)) throw ParamError("environment: radiance must be between 0 and 1e6 in each channel");
    e["radiance"] = Value::Array{c[0], c[1], c[2]};
  }
  if (p.has("rotation")) e["rotation"] = p.get_float("rotation", 0, -360, 360);
  if (p.has("intensity")) e["intensity"] = p.get_float("intensity", 1, 0, 1e6);
  if (e.empty()) throw ParamError("environment: a frame's table gives its intensity, rotation or radiance");
  p.report_unused();
  return Value(Value::Map{{"environment", Value(std::move(e))}});
}

Value read_frame_point_light(const ParamTable& p) {
  Value::Map light;
  if (!p.has("point") && !p.has("intensity")) throw ParamError(p.owner() + " gives neither point nor intensity");
  if (p.has("point")) {
    const auto at = p.get_vec3("point", {0, 0, 0});
    light["point"] = Value::Array{at[0], at[1], at[2]};
  }
  if (p.has("intensity")) {
    const auto i = p.get_vec3("intensity", {0, 0, 0});
    for (double v : i)
      if (!(v >= 0 && v <= 1e9)) throw ParamError(p.owner() + ": intensity must be between 0 and 1e9 in each channel");
    light["intensity"] = Value::Array{i[0], i[1], i[2]};
  }
  p.report_unused();
  return Value(std::move(light));
}

Value read_sun(const ParamTable& p) {
  Value::Map sun;
  if (!p.has("direction")) throw ParamError("sun needs a direction = {x, y, z} (towards the sun)");
  const auto d = p.get_vec3("direction", {0, 1, 0});
  if (d[0] == 0 && d[1] == 0 && d[2] == 0) throw ParamError("sun: direction must not be {0, 0, 0}");
  sun["direction"] = Value::Array{d[0], d[1], d[2]};
  if (!p.has("irradiance")) throw ParamError("sun needs irradiance = {r, g, b} (W/m^2 on a surface facing it)");
  const auto e = p.get_vec3("irradiance", {0, 0, 0});
  for (double v : e)
    if (!(v >= 0 && v <= 1e9)) throw ParamError("sun: irradiance must be between 0 and 1e9 in each channel");
  sun["irradiance"] = Value::Array{e[0], e[1], e[2]};
  sun["angle"] = p.get_float("angle", 0.526, 1e-3, 45);
  p.report_unused();
  return Value(Value::Map{{"sun", Value(std::move(sun))}});
}

ShapeRead read_shape(const std::string& name, const Value::Map& table, std::vector<std::string>& materials) {
  const std::string which = "shape '" + name + "'";
  static const std::set<std::string, std::less<>> kGeometry{"plane", "normal", "size", "sphere", "radius", "material"};
  Value::Map geometry, look;
  for (const auto& [key, v] : table) (kGeometry.count(key) ? geometry : look)[key] = v;
  ParamTable g(geometry, which);
  if (g.has("plane") == g.has("sphere")) throw ParamError(which + " needs exactly one of plane or sphere");
  auto vec = [](const std::array<double, 3>& a) { return Value(Value::Array{a[0], a[1], a[2]}); };
  Value::Map shape{{"name", name}};
  if (g.has("plane")) {
    shape["plane"] = vec(g.get_vec3("plane", {0, 0, 0}));
    const auto n = g.get_vec3("normal", {0, 1, 0});
    if (n[0] == 0 && n[1] == 0 && n[2] == 0) throw ParamError(which + ": normal must not be {0, 0, 0}");
    shape["normal"] = vec(n);
    if (g.has("size")) shape["size"] = g.get_float("size", 1, 1e-9, 1e30);
  } else {
    shape["sphere"] = vec(g.get_vec3("sphere", {0, 0, 0}));
    if (!g.has("radius")) throw ParamError(which + ": a sphere needs a radius");
    shape["radius"] = g.get_float("radius", 1, 1e-9, 1e30);
  }
  const std::string material = g.get_string("material", "");
  g.report_unused();
  if (!material.empty()) {
    if (!look.empty())
      throw ParamError(which + ": give material = \"" + material + "\" or the material's own parameters (" +
                       look.begin()->first + ", ...), not both");
    if (std::find(materials.begin(), materials.end(), material) == materials.end())
      throw ParamError(which + ": material '" + material + "' is not in the scene");
    shape["material"] = material;
    return {Value(std::move(shape)), std::nullopt};
  }
  if (std::find(materials.begin(), materials.end(), name) != materials.end())
    throw ParamError(which + ": the scene already has a material '" + name + "'; name the shape otherwise, or give " +
                     "material = \"" + name + "\"");
  materials.push_back(name);
  if (look.empty()) return {Value(std::move(shape)), std::nullopt};
  return {Value(std::move(shape)), read_material_change(name, ParamTable(look, which), materials)};
}

void read_farm_settings(const ParamTable& p, FarmSpec& spec) {
  spec.heartbeat_timeout = p.get_float("heartbeat_timeout", spec.heartbeat_timeout, 0.5, 3600);
  spec.request_timeout = p.get_float("request_timeout", spec.request_timeout, 0.1, 86400);
  spec.director_address = p.get_string("director_address", spec.director_address);
  // Actors connect to this address: "every interface" is where a server listens, not a place to reach it.
  for (const char* any : {"0.0.0.0", "::", "*", "[::]"})
    if (spec.director_address == any)
      throw ParamError("farm: director_address '" + spec.director_address +
                       "' is no address the actors can reach; give this machine's address on the hosts' network "
                       "(or leave it out: it is found from the route to the first remote host)");
  spec.security = p.get_string("security", spec.security, {"curve", "none"});
  spec.monitor = p.get_string("monitor", spec.monitor);
  spec.host_agents = p.get_bool("host_agents", spec.host_agents);
  spec.light_paths = p.get_string("light_paths", spec.light_paths, {"check", "complete", "partial", "off"});
  p.report_unused();
}

std::string resolve_program(const std::string& program, const fs::path& script_dir) {
  auto executable = [](const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
  };
  if (program.find('/') != std::string::npos) {
    fs::path p = fs::path(program).is_absolute() ? fs::path(program) : script_dir / program;
    return executable(p) ? fs::absolute(p).lexically_normal().string() : std::string();
  }
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/bin:/bin";
  for (size_t start = 0; start <= dirs.size();) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    if (fs::path candidate = fs::path(dirs.substr(start, end - start)) / program; executable(candidate))
      return candidate.string();
    start = end + 1;
  }
  return {};
}

}  // namespace lf
