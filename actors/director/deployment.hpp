#pragma once
// What a farm needs in place before its actors start, and what CONFIG later tells them about it: the hosts
// prepared (ssh connected, lightfarm found there), the scene in each host's cache and a host agent where several
// actors share it, a partitioned scene's parts, the address remote hosts reach this machine at, and the CURVE keys.
// The director makes one Deployment in its prepare stage (Deployer) and reads it from then on.
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "actors/launchers/launcher.hpp"
#include "farm/farm_spec.hpp"
#include "render/tracing/partition.hpp"
#include "render/scene/scene.hpp"
#include "render/shading/light_paths.hpp"
#include "transport/security.hpp"

namespace lf {

struct Deployment {
  std::string scene_bytes, scene_hash;              // a scene from a file, as shipped (empty for a built-in one)
  std::map<std::string, std::string> scene_paths;   // host -> the scene's path in its cache
  std::map<std::string, uint64_t> scene_sent;       // host -> bytes that crossed to it (0: it was cached)
  std::map<std::string, std::string> agent_sockets;  // host -> its host agent's socket, where one runs
  std::vector<ScenePart> parts;                     // partition { parts = N }: what each geometry actor holds
  std::string local_address;  // set when the farm spans hosts: where this machine's actors and the director listen
  // Where each actor's answer can be other than zero (answer_ends, by actor index), told to its askers in CONFIG:
  // composed once here, not for every actor configured.
  std::vector<std::optional<AnswerEnds>> answers;
  // CURVE (farm { security = "curve" }): a keypair for the director and one per actor process; the authenticator
  // lets in only the actors' keys.
  wire::CurveKeys director_keys;
  std::map<std::string, wire::CurveKeys> actor_keys;
  std::unique_ptr<wire::Authenticator> authenticator;

  bool curve() const { return !actor_keys.empty(); }
  // The actor's public key ("" without CURVE).
  std::string public_key_of(const std::string& actor) const;
  // The keys line an actor reads on its stdin: its own pair, the director's public key, every actor's public key.
  std::string keys_line_for(const std::string& actor) const;
  // {hash, bytes, bytes_shipped: {host: bytes}} for the report, or nil for a built-in scene.
  Value scene_figures() const;
};

// The scene the farm renders, read once here so that a broken scene or a network that counts light twice or
// never stops the farm before anything launches (exit 2 for the script's faults). Throws FarmFailure.
Scene load_checked_scene(const FarmSpec& spec, bool quiet);
// Lights whose flux mostly meets nothing (a quad wound away from the room, a light outside the geometry): warnings.
void warn_about_escaping_light(const FarmSpec& spec, const Scene& scene);

// Makes the Deployment in three steps, so that the slow parts overlap: remote hosts connect while the director
// reads the scene (constructor), host agents build their BVH while the director checks the lights (ship), and the
// rest needs the scene and nothing else (finish). Throws FarmFailure.
class Deployer {
 public:
  Deployer(const FarmSpec& spec, Launchers& launchers, bool quiet);
  ~Deployer();  // waits for hosts still connecting (a farm that failed before launch)
  // Waits for the hosts, puts the scene in every host's cache and starts the host agents.
  void ship(const Scene& scene);
  // Splits a partitioned scene, finds this machine's address for remote hosts, makes the CURVE keys.
  Deployment finish(const Scene& scene);

 private:
  void open_sessions_as_hosts_answer();
  void start_host_agents();
  void split_scene(const Scene& scene);
  Result<std::string> director_address() const;
  void make_keys();

  const FarmSpec& spec_;
  Launchers& launchers_;
  bool quiet_;
  // Each remote host's preparation (ssh connected, lightfarm found there), running while the scene loads here.
  struct Preparing {
    Launcher* launcher;
    std::future<Status> done;
  };
  std::vector<Preparing> preparing_;
  Status cannot_prepare_ = Ok{};  // a host whose launcher could not be made
  Deployment d_;
};

}  // namespace lf
