#include "actors/director/deployment.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>
#include <thread>

#include "actors/director/farm_failure.hpp"
#include "core/log.hpp"
#include "farm/light_path_check.hpp"
#include "render/tracing/camera.hpp"
#include "render/lights/light_checks.hpp"
#include "render/scene/scene_file.hpp"
#include "transport/socket.hpp"

namespace lf {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kShippers = 16;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

std::string Deployment::public_key_of(const std::string& actor) const {
  return actor_keys.empty() ? std::string() : actor_keys.at(actor).public_key;
}

std::string Deployment::keys_line_for(const std::string& actor) const {
  wire::FarmKeys k;
  k.own = actor_keys.at(actor);
  k.director = director_keys.public_key;
  for (const auto& [name, keys] : actor_keys) k.allowed.push_back(keys.public_key);
  return k.to_line();
}

Value Deployment::scene_figures() const {
  if (scene_bytes.empty()) return {};
  Value::Map sent;
  for (const auto& [host, bytes] : scene_sent) sent[host] = static_cast<int64_t>(bytes);
  return Value::Map{{"hash", scene_hash}, {"bytes", static_cast<int64_t>(scene_bytes.size())},
                    {"bytes_shipped", std::move(sent)}};
}

namespace {

// A job whose frames change materials or the sky (frames { materials, sun, environment }): each distinct frame's changes are checked before
// launch as the script's own are (the scene takes them, some light is left, the network counts every light path
// of those materials once), and every actor must be one that takes a frame's materials.
void check_frame_materials(const FarmSpec& spec, const Scene& scene) {
  std::set<std::string> checked;
  for (const FrameSpec& f : spec.frames) {
    if (f.materials.empty() || !checked.insert(to_json(Value(f.materials))).second) continue;
    const std::string what = spec.job.loc.str() + ": frames: frame " + std::to_string(f.number) + "'s materials";
    for (const Value& change : f.materials)
      if (change.find("sun") && !(scene.environment() && scene.environment()->sun()))
        throw FarmFailure{spec.job.loc.str() + ": frames: the sun changes from frame to frame, but the scene has no "
                          "sun: declare its first state with sun { }", 2};
    if (auto st = scene.check_light_changes(f.materials); !st)
      throw FarmFailure{spec.job.loc.str() + ": frames: frame " + std::to_string(f.number) + ": " + st.error().message, 2};
    std::vector<Material> materials = scene.materials();
    if (auto st = Scene::change_materials(materials, f.materials); !st) throw FarmFailure{what + ": " + st.error().message, 2};
    const SceneLobes lobes = scene_lobes(scene, &materials);
    if (!lobes.emits) throw FarmFailure{what + " leave the scene without light (nothing emits)", 2};
    if (const LightPathReport paths = check_light_paths(spec, lobes); !paths.errors.empty())
      throw FarmFailure{what + ": " + paths.error_text(), 2};
  }
  if (checked.empty()) return;
  for (const ActorSpec& a : spec.actors) {
    if (a.is_ring_node())
      throw FarmFailure{spec.job.loc.str() + ": frames: materials change over the job, which the radiosity ring's "
                        "solution, made once for the farm, cannot follow ('" + a.name + "'): render such a job without "
                        "radiosity { }, or one job for each set of materials", 2};
    if (a.runtime.count("cmd"))
      log_warn("frames: the materials change over the job: '" + a.name + "' runs a process of its own (lightop.exec), "
               "which must take each frame's materials from PHASE frame (docs/PROTOCOL.md), or it lights the "
               "script's scene throughout");
  }
}

}  // namespace

Scene load_checked_scene(const FarmSpec& spec, bool quiet) {
  if (!spec.scene.file.empty())
    if (auto catalogue = Scene::catalogue_file(spec.scene.file))
      for (const auto& warning : catalogue->warnings) log_warn(warning);
  const auto load_start = Clock::now();
  auto scene = Scene::load(spec.scene);
  if (!scene) throw FarmFailure{spec.scene.loc.str() + ": " + scene.error().message};
  if (const double took = seconds_since(load_start); took >= 1.0 && !quiet)
    log_info("scene: read " + spec.scene.file + " (" + std::to_string(scene->triangle_count()) + " triangles) in " +
             seconds_text(std::round(took * 10) / 10));
  // Light counted twice or left out by the network, for this scene's materials: a script error, before launch.
  const LightPathReport paths = check_light_paths(spec, scene_lobes(*scene));
  for (const auto& warning : paths.warnings) log_warn(warning);
  if (!paths.errors.empty()) throw FarmFailure{paths.error_text(), 2};
  check_frame_materials(spec, *scene);
  return std::move(*scene);
}

void warn_about_escaping_light(const FarmSpec& spec, const Scene& scene) {
  std::vector<std::string> point_labels;
  for (const Value& l : spec.scene.lights)
    if (l.find("point"))
      point_labels.push_back(l.find("at") && l.find("at")->is_string() ? l.find("at")->as_string() + ": light"
                                                                       : "a script's point light");
  auto escapes = light_escapes(scene, point_labels);
  for (auto& e : escapes)
    if (e.light.rfind("material '", 0) == 0 && !spec.scene.file.empty()) e.light = spec.scene.file + ": " + e.light;
  for (const auto& warning : escaping_light_warnings(escapes)) log_warn(warning);
}

Deployer::Deployer(const FarmSpec& spec, Launchers& launchers, bool quiet)
    : spec_(spec), launchers_(launchers), quiet_(quiet) {
  for (const auto& warning : spec_.setting_warnings()) log_warn(warning);
  // ssh's key exchange and the check for lightfarm there take about as long as reading a real scene here: every
  // host at once, on threads of their own.
  if (!spec_.has_remote_hosts()) return;
  for (const HostSpec* h : spec_.hosts_in_use()) {
    auto launcher = launchers_.for_host(*h);
    if (!launcher) {
      cannot_prepare_ = launcher.error();
      return;
    }
    preparing_.push_back({*launcher, std::async(std::launch::async, [l = *launcher] { return l->prepare(); })});
  }
}

Deployer::~Deployer() {
  for (auto& p : preparing_)  // hosts still connecting (a farm that failed before launch)
    if (p.done.valid()) p.done.wait();
}

// Each host's session (Launcher::open_session) opens as soon as that host has answered, here on the director's
// thread (a child forked on prepare's threads would die with them: PR_SET_PDEATHSIG follows the thread). Its ssh
// master connection then stays in use; opened only once every host had answered, the early hosts' masters lapsed
// after ControlPersist's 5 idle seconds and connected again (64 rig hosts: prepare median 13.5 -> 12.4 s).
void Deployer::open_sessions_as_hosts_answer() {
  if (!cannot_prepare_) throw FarmFailure{"cannot start the farm: " + cannot_prepare_.error().message};
  for (size_t left = preparing_.size(); left > 0;) {
    for (auto& p : preparing_) {
      if (!p.done.valid() || p.done.wait_for(std::chrono::seconds(0)) != std::future_status::ready) continue;
      --left;
      if (auto st = p.done.get(); !st) throw FarmFailure{"cannot start the farm: " + st.error().message};
      if (auto st = p.launcher->open_session(); !st) throw FarmFailure{"cannot start the farm: " + st.error().message};
    }
    if (left > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// A scene from a file travels to the hosts in its binary form; actors never parse the OBJ themselves. Every host
// that runs an actor gets it once (its cache may have it already). Shipped, and the agents started, before the
// light checks: an agent builds its BVH meanwhile. Lost Empire on one host: an actor's start 0.41 -> 0.24 s (6
// replicas, scene_share_bench), launch to first tile 1.70 -> 1.32 s (8 replicas and 3 renderers, medians of 5).
void Deployer::ship(const Scene& scene) {
  if (!spec_.scene.file.empty()) {
    d_.scene_bytes = scene_to_bytes(scene);
    d_.scene_hash = content_hash(d_.scene_bytes);
  }
  open_sessions_as_hosts_answer();
  if (d_.scene_bytes.empty()) return;
  const auto hosts = spec_.hosts_in_use();  // remote ones prepared already (open_sessions_as_hosts_answer)
  std::vector<Launcher*> launchers;
  for (const HostSpec* h : hosts) {
    auto launcher = launchers_.for_host(*h);
    if (!launcher) throw FarmFailure{launcher.error().message};
    launchers.push_back(*launcher);
  }
  // Every host at once (at most kShippers at a time), not one after another with two ssh round trips each: 64 rig
  // hosts, cold caches, prepare 30.4 -> 24.5 s.
  std::vector<Result<Launcher::Shipped>> shipped(hosts.size(), make_error("not shipped"));
  std::atomic<size_t> next{0};
  std::vector<std::thread> shippers;
  for (size_t t = 0; t < std::min(hosts.size(), kShippers); ++t)
    shippers.emplace_back([&] {
      for (size_t i; (i = next++) < hosts.size();) shipped[i] = launchers[i]->ship(d_.scene_bytes, d_.scene_hash);
    });
  for (auto& t : shippers) t.join();
  for (size_t i = 0; i < hosts.size(); ++i) {
    if (!shipped[i]) throw FarmFailure{"cannot start the farm: " + shipped[i].error().message};
    d_.scene_paths[hosts[i]->name] = shipped[i]->path;
    d_.scene_sent[hosts[i]->name] = shipped[i]->bytes_sent;
  }
  start_host_agents();
}

// A host with two or more scene-loading actors gets a host agent: the scene's BVH is built once there and shared
// by the actors it forks (actors/runtime/host_agent.hpp). An agent that cannot start is only a warning: the
// actors then load the scene themselves.
void Deployer::start_host_agents() {
  if (!spec_.host_agents) return;
  std::map<std::string, int> loaders;
  for (const auto& a : spec_.actors)
    if (const HostSpec* h = spec_.host_of(a); h && a.loads_scene()) ++loaders[h->name];
  std::random_device random;
  for (const HostSpec* h : spec_.hosts_in_use()) {
    if (loaders[h->name] < 2) continue;
    char tag[17];
    std::snprintf(tag, sizeof tag, "%08x%08x", random(), random());
    const std::string socket = "lightfarm-agent-" + d_.scene_hash + "-" + tag;
    LaunchRequest how;
    how.argv = {"lightfarm", "host-agent", "--scene", d_.scene_paths.at(h->name), "--hash", d_.scene_hash,
                "--socket", socket, "--actors", std::to_string(loaders[h->name])};
    how.hold_stdin = true;
    auto pid = launchers_.start(*h, how);
    if (!pid) {
      log_warn("host '" + h->name + "': no host agent (" + pid.error().message + "); its actors load the scene themselves");
      continue;
    }
    d_.agent_sockets[h->name] = socket;
  }
}

Deployment Deployer::finish(const Scene& scene) {
  if (spec_.partition_parts > 0) split_scene(scene);
  // A farm on one machine talks over loopback; one that spans hosts listens where they all reach it.
  if (spec_.has_remote_hosts()) {
    auto address = director_address();
    if (!address) throw FarmFailure{address.error().message};
    d_.local_address = *address;
  }
  if (spec_.security == "curve") make_keys();
  d_.answers = answer_ends(spec_);
  return std::move(d_);
}

// partition { parts = N }: the split the geometry actors hold, weighted by probe rays from the farm's camera
// (render/tracing/partition.hpp), made once here so that every actor agrees on it.
void Deployer::split_scene(const Scene& scene) {
  const auto start = Clock::now();
  RayTracer whole(scene);
  const int width = std::min(spec_.image.width, 160);
  const int height = std::max(1, spec_.image.height * width / std::max(1, spec_.image.width));
  const Camera probe(spec_.camera, width, height);
  d_.parts = partition_by_probes(scene, whole, probe, width, height, spec_.partition_parts);
  if (static_cast<int>(d_.parts.size()) < spec_.partition_parts)
    throw FarmFailure{spec_.partition_loc.str() + ": partition: the scene has " + std::to_string(scene.triangle_count()) +
                      " triangles, fewer than the " + std::to_string(spec_.partition_parts) + " parts asked for"};
  if (quiet_) return;
  std::string shares;
  for (const ScenePart& p : d_.parts) shares += (shares.empty() ? "" : ", ") + std::to_string(p.triangles.size());
  log_info("partition: " + std::to_string(d_.parts.size()) + " parts of " + shares + " triangles (split in " +
           seconds_text(std::round(seconds_since(start) * 100) / 100) + ")");
}

// Where the remote hosts reach this machine: farm { director_address }, or the source address of the route to the
// first remote host.
Result<std::string> Deployer::director_address() const {
  if (!spec_.director_address.empty()) return spec_.director_address;
  for (const auto& a : spec_.actors) {
    const HostSpec* h = spec_.host_of(a);
    if (!h || !h->remote()) continue;
    auto source = wire::local_address_towards(h->address);
    if (!source) return make_error("host '" + h->name + "': " + source.error().message + " (set farm { director_address })");
    return source;
  }
  return std::string("127.0.0.1");
}

void Deployer::make_keys() {
  d_.director_keys = wire::make_curve_keypair();
  if (d_.director_keys.public_key.empty()) throw FarmFailure{"cannot make CURVE keys (ZeroMQ built without CURVE?)"};
  std::set<std::string> allowed;
  for (const auto& a : spec_.actors)
    if (a.has_process()) allowed.insert((d_.actor_keys[a.name] = wire::make_curve_keypair()).public_key);
  d_.authenticator = std::make_unique<wire::Authenticator>(allowed);
}

}  // namespace lf
