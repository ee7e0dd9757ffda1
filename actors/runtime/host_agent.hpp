#pragma once
// The host agent: one process per host and farm that loads the shipped scene and builds its BVH once, then forks
// that host's scene-loading actors (renderers, LightOps), which share those pages copy-on-write instead of each
// building its own (docs/decisions.md, "One BVH per host").
//
// Launchers keep starting `lightfarm actor ... --agent NAME` as before; that process (the stub) hands its standard
// input, output and error to the agent over a Unix socket in the abstract namespace (SCM_RIGHTS), the agent forks
// the actor with them, and the stub stays as its stand-in: it passes SIGTERM/SIGINT/SIGHUP on, exits with the
// actor's exit status, and when the stub dies (SIGKILL included) the actor dies with it (a lifeline pipe). So the
// director, ssh's lifeline and srun see one process per actor, as without an agent. When no agent answers, or it
// cannot fork, the stub runs the actor itself: the agent only saves memory and start-up time, it never decides
// whether a farm runs.
//
// The wire between stub and agent (one SOCK_STREAM connection per actor, same user only):
//   stub -> agent: "LFA1", stub pid and process group (uint32 each, native order), then the actor's argv as
//                  NUL-terminated strings; with it five descriptors: stdin, stdout, stderr, the lifeline's read
//                  end (EOF: the stub is gone) and the status pipe's write end (the actor writes its exit code).
//   agent -> stub: 'y' and the actor's pid (int32), or 'n' (run it yourself); later the actor's wait status
//                  (int32), if the agent is still there when it exits.
#include <functional>
#include <optional>
#include <string>

namespace lf {

struct HostAgentOptions {
  std::string scene;   // the shipped scene's path on this host
  std::string hash;    // its content hash
  std::string socket;  // the abstract socket's name
  int actors = 0;      // how many actors it will be asked for (0: unknown)
};

// Runs the agent until it has forked `actors` actors and they have all exited, or until SIGTERM/SIGINT, after which
// it takes no more actors and leaves once those it forked have exited. Ending by itself matters under Slurm: the
// agent's job step ends with it, and a step killed from outside is cancelled with every process it started.
// `actor_main` runs in each forked actor with the stub's argv.
int run_host_agent(const HostAgentOptions& options, const std::function<int(int, char**)>& actor_main);

// In the stub: has the agent named `socket` fork the actor `argv` describes and waits for it. Returns its wait
// status (as from waitpid) to pass on, or nothing when the agent did not take it (run it here instead).
std::optional<int> run_through_agent(const std::string& socket, const std::vector<std::string>& argv);

}  // namespace lf
