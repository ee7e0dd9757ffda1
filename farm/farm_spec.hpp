#pragma once
// FarmSpec: what a farm script describes once evaluated — scene, camera, image, the actor graph, placement. The
// Lua binding builds it with the builders in farm/builders.hpp; the director launches and drives it; each actor
// receives its part as CONFIG.
#include <string>
#include <vector>

#include "core/specs.hpp"
#include "core/value.hpp"
#include "farm/actor_kinds.hpp"
#include "farm/job.hpp"

namespace lf {

struct HostSpec {
  std::string name = "local";
  std::string launcher = "local";  // which Launcher starts this host's actors (actors/launchers/launcher.hpp)
  std::string address = "127.0.0.1";  // where its actors listen, and (ssh) where to reach it
  // ssh hosts:
  std::string user;        // login name; empty: ssh's default
  int port = 0;            // 0: ssh's default
  std::string ssh_config;  // an ssh_config file (ssh -F); empty: the user's
  std::string ssh_name;    // what ssh connects to: a Host of the ssh config (its key, user, options); empty: address
  std::string lightfarm;   // the lightfarm binary on the host; empty: this binary's path
  SourceLoc loc;
  bool remote() const { return launcher != "local"; }
};

// One actor process. Renderers are expanded from `renderers { count = N }` into N specs.
struct ActorSpec {
  std::string name;       // unique in the farm, e.g. "direct" or "renderer-1"
  std::string kind;       // an actor kind (farm/actor_kinds.hpp): "renderer", "multiplexer", ... or a LightOp kind
  Value::Map params;      // the script's parameters, minus wiring keys
  Value::Map runtime;     // how to run it, not the algorithm: {cmd, cwd} for exec actors
  Value::Map debug;       // test knobs, never needed in production: {slowdown = factor} (see docs/lua-api.md)
  std::vector<int> inputs;  // indices into FarmSpec::actors; a multiplexer's inputs are its replicas
  std::string host = "local";
  SourceLoc loc;
  // A pool whose clients dispatch to its replicas themselves (actors/runtime/pool_client.hpp): it is a name in the
  // graph, with no process of its own. Set by settle_pool_dispatch (farm/builders.hpp).
  bool dispatched_by_clients = false;
  bool has_process() const { return !dispatched_by_clients; }
  // Its kind's role; a program run by its own command (runtime.cmd) is a plug-in whatever it is called.
  ActorRole role() const;
  bool is_renderer() const { return role() == ActorRole::renderer; }
  bool is_multiplexer() const { return role() == ActorRole::multiplexer; }
  bool is_ring_node() const { return role() == ActorRole::ring_node; }
  bool is_geometry() const { return role() == ActorRole::geometry; }
  // Whether its process loads the farm's scene and builds its BVH (ActorKind::loads_scene).
  bool loads_scene() const;
};

struct FarmSpec {
  std::string script;
  SceneSpec scene;
  CameraSpec camera;
  ImageSpec image;
  // frames { } and camera { keys } as the script gave them, and the frames to render (farm/job.hpp): empty for a
  // farm of one frame that is no job (no frames { }, no --frames), which renders `camera` to `image.output`.
  JobSpec job;
  std::vector<FrameSpec> frames;
  std::vector<HostSpec> hosts;
  std::vector<ActorSpec> actors;
  int lighting = -1;  // index of the MasterLightOp the renderers ask
  double heartbeat_timeout = 10.0;  // seconds of silence before an actor counts as dead
  double request_timeout = 120.0;   // seconds a shading request may wait for its answer
  std::string director_address;     // where remote actors reach the director; empty: found from the routes
  std::string security = "curve";   // "curve": every link authenticated and encrypted; "none": to measure its cost
  std::string monitor;              // farm { monitor = "[ADDR:]PORT" }: the live monitor's address (--monitor wins)
  // farm { light_paths }: how the lighting network's light paths are checked against the scene before launch
  // (farm/light_path_check.hpp): "check" (paths counted twice are an error, paths left out a warning), "complete"
  // (both errors), "partial" (the network computes part of the light on purpose), "off".
  std::string light_paths = "check";
  // A host with two or more scene-loading actors of a shipped scene loads it and builds its BVH once, in a host
  // agent that forks those actors (actors/runtime/host_agent.hpp); false: every actor loads its own.
  bool host_agents = true;
  // partition { parts = N }: the scene split by space into N parts, each held by a `geometry` actor (0: not split).
  int partition_parts = 0;
  // partition { colocate = true }: replica j of a pool whose op traces through the parts also holds part j mod N
  // itself, and renderers send it the points that lie there, so that the rays that stay in a part stay in its process.
  bool partition_colocate = false;
  SourceLoc partition_loc;

  int renderer_count() const;
  std::vector<std::string> renderer_names() const;
  // Index of the multiplexer whose replica actor `i` is, or -1 (a look at every actor: for all of them, pools()).
  int pool_of(int i) const;
  // pool_of of every actor, in one pass.
  std::vector<int> pools() const;
  // Index of the actor named `name`, or -1.
  int find(const std::string& name) const;
  // The host an actor runs on ("local" unless declared); nullptr for an undeclared name.
  const HostSpec* host_of(const ActorSpec& actor) const;
  // The hosts that run at least one actor, each once, in the order actors first name them.
  std::vector<const HostSpec*> hosts_in_use() const;
  // True when some actor runs on a host that is not this machine.
  bool has_remote_hosts() const;
  // What a user should hear before the farm starts, about settings that work but may not be what they meant
  // (security off across hosts).
  std::vector<std::string> setting_warnings() const;
};

}  // namespace lf
