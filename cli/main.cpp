// lightfarm: one executable for the user's commands (run, graph) and for the actor processes a farm launches.
#include <malloc.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <cstdlib>
#include <cstring>
#include <string>
#include <algorithm>
#include <map>
#include <vector>

#include "actors/kinds/actor_kinds.hpp"
#include "actors/check/check_actor.hpp"
#include "actors/director/director.hpp"
#include "actors/launchers/host_launcher.hpp"
#include "actors/runtime/host_agent.hpp"
#include "actors/runtime/runtime.hpp"
#include "core/log.hpp"
#include "farm/builders.hpp"
#include "lua/script.hpp"
#include "render/scene/scene_report.hpp"
#include "transport/protocol.hpp"

namespace {

constexpr const char* kUsage = R"(lightfarm — a distributed lighting-simulation farm

usage:
  lightfarm run SCRIPT [--output FILE] [--set NAME=VALUE]... [--stats-json FILE] [--quiet] [--monitor [ADDR:]PORT]
                      [--frames LIST] [--checkpoint-every SECONDS] [--preview-every SECONDS] [--restart]
      Turn a farm script into processes and an image.
  lightfarm graph SCRIPT [--set NAME=VALUE]...
      Print the script's actor graph as Graphviz DOT; launches nothing.
  lightfarm actor --kind KIND --name NAME --director ENDPOINT [--bind ENDPOINT] [--curve] [--agent NAME]
      Host one actor (the director runs this; see docs/PROTOCOL.md).
  lightfarm host-agent --scene FILE --hash HASH --socket NAME [--actors N]
      Load a shipped scene and its BVH once and fork this host's N actors from it (the director runs this).
  lightfarm host-launcher
      Start this host's actors as the director asks on stdin; stop them all at EOF (the director runs this).
  lightfarm check-actor [--kind KIND] [--timeout SECONDS] [--inputs N] [--security curve|none]
                        [--heartbeat-timeout SECONDS] -- COMMAND [ARG]...
      Launch COMMAND as an actor and check it against the protocol; PASS/FAIL per check.
  lightfarm scene FILE
      Describe an OBJ or glTF scene: triangles, bounds, materials, emitters and their flux, textures, warnings,
      and a camera { } that frames it.
  lightfarm --help | --version

options:
  --output FILE       write the image here instead of image { output = ... } (.exr, .png, .tif)
  --set NAME=VALUE    override param("NAME", default) in the script
  --frames LIST       render these of the script's frames { } (e.g. 1-24,30); a job skips the frames its record
                      (OUTPUT.lfjob/) says are done and whose images are unchanged
  --stats-json FILE   also write phase timings and per-actor statistics as JSON
  --monitor [ADDR:]PORT  serve a live monitor page there (default address 127.0.0.1; port 0 picks one; the URL
                      is printed, with a token when not on loopback); docs/monitor.md
  --monitor-hold SECONDS  keep the monitor up that long after the frame
  --checkpoint-every SECONDS  write the frame's finished tiles to OUTPUT.lfresume at most this often (default 30;
                      0: never); a run of the same frame after a crash renders only the rest, to the same image
  --preview-every SECONDS  write the partial frame (unfinished tiles black) to OUTPUT's STEM.preview.EXT at most
                      this often while it renders; removed once the frame is written
  --restart           render the frame (or the job) from its start, ignoring OUTPUT.lfresume (and the job record)
  --quiet             print no tables, only errors

exit status: 0 done; 1 the farm failed; 2 bad command line or script; 128+N stopped by signal N.
docs: docs/lua-api.md (scripts), docs/PROTOCOL.md (the wire), docs/writing-an-actor.md
)";

int usage_error(const std::string& message) {
  std::fprintf(stderr, "lightfarm: error: %s\n(see lightfarm --help)\n", message.c_str());
  return 2;
}

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;
  std::map<std::string, std::string> set;
};

// Parses "--key value" pairs and repeated --set; `flags` are options without a value.
bool parse(int argc, char** argv, int first, const std::vector<std::string>& known, const std::vector<std::string>& flags,
           Args& out, std::string& error) {
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) != 0) {
      out.positional.push_back(a);
      continue;
    }
    // --key value, or --key=value (for --set=name=value the first '=' ends the key).
    std::string key = a.substr(2), value;
    bool inline_value = false;
    if (auto eq = key.find('='); eq != std::string::npos) {
      value = key.substr(eq + 1);
      key = key.substr(0, eq);
      inline_value = true;
    }
    if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
      out.options[key] = "1";
      continue;
    }
    if (key != "set" && std::find(known.begin(), known.end(), key) == known.end()) {
      error = "unknown option '" + a + "'";
      return false;
    }
    if (!inline_value) {
      if (i + 1 >= argc) {
        error = "option '" + a + "' needs a value";
        return false;
      }
      value = argv[++i];
    }
    if (key == "set") {
      auto eq = value.find('=');
      if (eq == std::string::npos || eq == 0) {
        error = "--set needs NAME=VALUE, got '" + value + "'";
        return false;
      }
      out.set[value.substr(0, eq)] = value.substr(eq + 1);
    } else {
      out.options[key] = value;
    }
  }
  return true;
}

int cmd_run(int argc, char** argv, bool graph_only) {
  Args args;
  std::string error;
  std::vector<std::string> known = graph_only ? std::vector<std::string>{} : std::vector<std::string>{"output", "stats-json", "monitor", "monitor-hold", "checkpoint-every", "frames", "preview-every"};
  std::vector<std::string> flags = graph_only ? std::vector<std::string>{} : std::vector<std::string>{"quiet", "restart"};
  if (!parse(argc, argv, 2, known, flags, args, error)) return usage_error(error);
  if (args.positional.size() != 1) return usage_error(std::string(graph_only ? "graph" : "run") + " needs one SCRIPT");
  lf::ScriptOptions so;
  so.set = args.set;
  if (args.options.count("output")) so.output = args.options["output"];
  if (args.options.count("frames")) {
    try {
      so.frames = lf::parse_frame_list(args.options["frames"]);
    } catch (const lf::ParamError& e) {
      return usage_error(e.what());
    }
  }
  auto spec = lf::evaluate_script(args.positional[0], so);
  if (!spec) {
    std::fprintf(stderr, "lightfarm: error: %s\n", spec.error().message.c_str());
    return 2;
  }
  if (graph_only) {
    std::fputs(lf::to_dot(*spec).c_str(), stdout);
    return 0;
  }
  lf::RunOptions ro;
  ro.progress_on_terminal = ::isatty(STDERR_FILENO);
  ro.quiet = args.options.count("quiet") > 0;
  if (args.options.count("stats-json")) ro.stats_json = args.options["stats-json"];
  ro.monitor = args.options.count("monitor") ? args.options["monitor"] : spec->monitor;
  if (args.options.count("monitor-hold")) {
    char* end = nullptr;
    ro.monitor_hold = std::strtod(args.options["monitor-hold"].c_str(), &end);
    if (*end != '\0' || !(ro.monitor_hold >= 0)) return usage_error("--monitor-hold needs seconds (0 or more)");
  }
  if (args.options.count("checkpoint-every")) {
    char* end = nullptr;
    ro.checkpoint_every = std::strtod(args.options["checkpoint-every"].c_str(), &end);
    if (*end != '\0' || !(ro.checkpoint_every >= 0) || !std::isfinite(ro.checkpoint_every))
      return usage_error("--checkpoint-every needs seconds (0 or more; 0: no checkpoint)");
  }
  if (args.options.count("preview-every")) {
    char* end = nullptr;
    ro.preview_every = std::strtod(args.options["preview-every"].c_str(), &end);
    if (*end != '\0' || !(ro.preview_every > 0) || !std::isfinite(ro.preview_every))
      return usage_error("--preview-every needs seconds (more than 0)");
  }
  ro.restart = args.options.count("restart") > 0;
  return lf::run_farm(*spec, ro);
}

int cmd_actor(int argc, char** argv) {
  Args args;
  std::string error;
  if (!parse(argc, argv, 2, {"kind", "name", "director", "bind", "agent"}, {"curve"}, args, error))
    return usage_error(error);
  for (const char* required : {"kind", "name", "director"})
    if (!args.options.count(required)) return usage_error(std::string("actor needs --") + required);
  if (args.options.count("agent")) {
    // The host's agent forks this actor with the scene and BVH it already holds; this process stands in for it.
    // Without an answer from the agent, the actor runs here as usual (nothing read from stdin yet).
    std::vector<std::string> forwarded;
    for (int i = 0; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--agent") ++i;
      else if (a.rfind("--agent=", 0) != 0) forwarded.push_back(a);
    }
    if (auto status = lf::run_through_agent(args.options["agent"], forwarded)) {
      if (WIFEXITED(*status)) return WEXITSTATUS(*status);
      const int sig = WIFSIGNALED(*status) ? WTERMSIG(*status) : SIGKILL;
      std::signal(sig, SIG_DFL);
      ::raise(sig);
      return 128 + sig;
    }
  }
  lf::ActorArgs a;
  a.kind = args.options["kind"];
  a.name = args.options["name"];
  a.director = args.options["director"];
  if (args.options.count("bind")) a.bind = args.options["bind"];
  lf::set_log_name(a.name);
  if (args.options.count("curve")) {
    auto keys = lf::read_farm_keys_from_stdin();
    if (!keys) {
      lf::log_error(keys.error().message);
      return 2;
    }
    a.keys = std::move(*keys);
  }
  auto actor = lf::make_actor(a.kind);
  if (!actor) {
    lf::log_error("unknown actor kind '" + a.kind + "' (known kinds: " + lf::actor_kind_list() + ")");
    return 2;
  }
  // Fault injection for the failure tests (CONTRIBUTING.md): the actors named in
  // LIGHTFARM_FAULT=crash-at-start:NAME[,NAME...] die before they say hello.
  if (const char* fault = std::getenv("LIGHTFARM_FAULT"); fault && std::string_view(fault).starts_with("crash-at-start:")) {
    std::string names = "," + std::string(fault).substr(std::string_view("crash-at-start:").size()) + ",";
    if (names.find("," + a.name + ",") != std::string::npos) std::abort();
  }
  lf::install_stop_signals();
  lf::Runtime runtime(a);
  return runtime.run(*actor);
}

// The host agent (internal, like `actor`): loads a shipped scene and its BVH once, forks this host's actors.
int cmd_host_agent(int argc, char** argv) {
  Args args;
  std::string error;
  if (!parse(argc, argv, 2, {"scene", "hash", "socket", "actors"}, {}, args, error)) return usage_error(error);
  for (const char* required : {"scene", "hash", "socket"})
    if (!args.options.count(required)) return usage_error(std::string("host-agent needs --") + required);
  const int actors = args.options.count("actors") ? std::atoi(args.options["actors"].c_str()) : 0;
  return lf::run_host_agent({args.options["scene"], args.options["hash"], args.options["socket"], actors},
                            [](int c, char** v) { return cmd_actor(c, v); });
}

}  // namespace

int cmd_check_actor(int argc, char** argv) {
  lf::CheckOptions o;
  int i = 2;
  for (; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--") {
      ++i;
      break;
    }
    if (i + 1 >= argc) return usage_error("option '" + a + "' needs a value");
    if (a == "--kind") o.kind = argv[++i];
    else if (a == "--timeout") o.timeout = std::atof(argv[++i]);
    else if (a == "--inputs") o.inputs = std::atoi(argv[++i]);
    else if (a == "--security") o.security = argv[++i];
    else if (a == "--heartbeat-timeout") o.heartbeat_timeout = std::atof(argv[++i]);
    else return usage_error("unknown option '" + a + "' (the actor's command goes after --)");
  }
  for (; i < argc; ++i) o.command.push_back(argv[i]);
  if (o.command.empty()) return usage_error("check-actor needs a command after --");
  if (!(o.timeout > 0)) return usage_error("--timeout must be positive");
  if (o.security != "curve" && o.security != "none") return usage_error("--security must be curve or none");
  if (!(o.heartbeat_timeout >= 0.5)) return usage_error("--heartbeat-timeout must be at least 0.5 s");
  return lf::check_actor(o);
}

// A fresh page costs ~13 µs on the virtual machines this runs on (a 27 MB photon share: 80 ms of faults in each
// buffer it passes through). glibc's malloc asks for transparent huge pages (a fault per 2 MB) when its tunable
// says so, which it reads only at start: so a farm process sets it and runs itself again, once. Children inherit
// it; where the kernel's THP mode is not "madvise" it would change nothing, and a user's own setting is kept. (glibc
// leaves only the first tunable in the environment it passes on: after a user's own tunable, ours does not reach the
// children, and each runs itself again too. Put first, it would drop the user's.)
// Measured (Lost Empire, 12 local actors): launch to first tile 2.41 -> 2.00 s, the director's CPU 1.82 -> 1.46 s.
static void prefer_huge_pages(char** argv) {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb")) return;
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  if (!std::getline(thp, mode) || mode.find("[madvise]") == std::string::npos) return;
  const std::string value = tunables && *tunables ? std::string(tunables) + ":glibc.malloc.hugetlb=1" : "glibc.malloc.hugetlb=1";
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);  // only returns if it failed: then go on as we are
}

int main(int argc, char** argv) {
  if (argc >= 2 && (std::strcmp(argv[1], "run") == 0 || std::strcmp(argv[1], "actor") == 0 ||
                    std::strcmp(argv[1], "host-agent") == 0 || std::strcmp(argv[1], "host-launcher") == 0))
    prefer_huge_pages(argv);
  // Shading batches are a few hundred KB each. Keep such buffers in the heap rather than mmap/munmap-ing them per
  // message: that churn (page faults, zeroing) cost more than the copies themselves.
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  // One arena for every thread, so that the settings above hold for ZeroMQ's I/O thread too: with CURVE it
  // allocates two message-sized buffers per message, and in an arena of its own those pages were given back and
  // faulted in zeroed again (clear_page_erms 2.5 % of a farm across hosts, 0.15 % on one). The threads are few.
  mallopt(M_ARENA_MAX, 1);
  if (argc < 2) return usage_error("no command given");
  std::string cmd = argv[1];
  if (cmd == "--help" || cmd == "-h" || cmd == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  // `lightfarm COMMAND --help`: the same page (a command's options would otherwise take --help for a value).
  if (argc >= 3 && (std::strcmp(argv[2], "--help") == 0 || std::strcmp(argv[2], "-h") == 0)) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  if (cmd == "--version") {
    std::printf("lightfarm %s (protocol %u)\n", LIGHTFARM_VERSION, lf::wire::kProtocolVersion);
    return 0;
  }
  // Allocation failure anywhere is a message and exit 1, never an abort (the director and the runtime catch it
  // where they can still stop their actors; this is the last line).
  try {
    if (cmd == "run") return cmd_run(argc, argv, false);
    if (cmd == "graph") return cmd_run(argc, argv, true);
    if (cmd == "actor") return cmd_actor(argc, argv);
    if (cmd == "host-agent") return cmd_host_agent(argc, argv);
    if (cmd == "host-launcher") {
      if (argc != 2) return usage_error("host-launcher takes no arguments");
      return lf::run_host_launcher();
    }
    if (cmd == "check-actor") return cmd_check_actor(argc, argv);
    if (cmd == "scene") {
      if (argc != 3) return usage_error("scene needs one FILE.obj");
      auto text = lf::describe_scene(argv[2]);
      if (!text) {
        std::fprintf(stderr, "lightfarm: error: %s\n", text.error().message.c_str());
        return 2;
      }
      std::fputs(text->c_str(), stdout);
      return 0;
    }
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "lightfarm: error: out of memory\n");
    return 1;
  }
  return usage_error("unknown command '" + cmd + "'");
}
