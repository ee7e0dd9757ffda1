// Chaos soak: frames of mixed networks (pools, photon maps, irradiance caches, radiosity rings) while
// random recoverable actors are SIGKILLed, or SIGSTOPped and continued, at random moments of the frame. Reports per network: frames, frames finished, finished frames whose
// image differs from the fault-free one (goal 0), failed frames, processes left behind (goal 0) and files left in
// /tmp, /dev/shm and the output folder (goal 0). Writes bench-chaos.json.
//
// Victims are what the farm promises to survive: a renderer while another lives, a pool replica while another of
// its pool lives (photon-map replicas only once rendering began: their shares cannot be redone during setup), and
// any radiosity ring node (restarted; the ring rolls back to its checkpoint).
// Stops last 0.2-3 s against a heartbeat timeout of 1.5 s, so some are taken for death and some are not.
// Usage: build/bench/chaos_soak [--frames N per network] [--seed S] [--only NETWORK] [--json FILE]
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include "bench/bench_util.hpp"
#include "core/value.hpp"
#include "render/images/image.hpp"
#include "tests/process_harness.hpp"

namespace {

namespace fs = std::filesystem;
using lf::test::Farm;

struct Network {
  std::string name;
  std::string script;
  std::vector<std::vector<std::string>> groups;  // each group: actors of which at least one must survive
  std::set<std::string> render_only;             // victims only once "render" has begun
  std::set<std::string> restarted;               // victims at any time, none need survive (ring nodes)
};

// Files lightfarm leaves in shared places: private folders, shared memory, temporary images in `out_dir`.
std::set<std::string> lightfarm_files(const fs::path& out_dir) {
  std::set<std::string> found;
  std::error_code ec;
  for (const char* dir : {"/tmp", "/dev/shm"})
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      if (it->path().filename().string().rfind("lightfarm-", 0) == 0) found.insert(it->path().string());
  for (fs::directory_iterator it(out_dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename().string().find(".partial") != std::string::npos) found.insert(it->path().string());
  return found;
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/chaos_soak [--frames N per network] [--seed S] [--only NETWORK]"
                            " [--json FILE]",
                            {"--frames", "--seed", "--only", "--json"});
  int frames = 10;
  unsigned seed = 1;
  std::string json_path = "bench-chaos.json";
  std::string only;  // one network by name
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--frames") frames = std::atoi(argv[i + 1]);
    else if (a == "--seed") seed = static_cast<unsigned>(std::atoi(argv[i + 1]));
    else if (a == "--json") json_path = argv[i + 1];
    else if (a == "--only") only = argv[i + 1];
  }
  const fs::path dir = fs::temp_directory_path() / ("chaos-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string head = "scene { builtin = \"cornell\" }\nimage { width = 128, height = 128, spp = 192, tile = 16 }\n"
                           "farm { heartbeat_timeout = 1.5 }\n";
  std::vector<Network> networks{
      {"pool",
       bench::temp_script("chaos-pool.lua",
                          head + "local d = multiplexer { lightop \"direct\" { light_samples = 4 }, replicas = 3 }\n"
                                 "renderers { count = 2, lighting = d }\n"),
       {{"renderer-0", "renderer-1"}, {"direct.0", "direct.1", "direct.2"}},
       {}},
      {"photons",
       bench::temp_script(
           "chaos-photons.lua",
           "scene { builtin = \"cornell_glass\" }\nimage { width = 96, height = 96, spp = 96, tile = 16 }\n"
           "farm { heartbeat_timeout = 1.5 }\n"
           "local c = multiplexer { lightop \"photonmap\" { photons = 200000, k = 50 }, replicas = 2 }\n"
           "local d = multiplexer { lightop \"direct\" {}, replicas = 2 }\n"
           "renderers { count = 2, lighting = lightop \"combine\" { inputs = { d, c } } }\n"),
       {{"renderer-0", "renderer-1"}, {"photonmap.0", "photonmap.1"}, {"direct.0", "direct.1"}},
       {"photonmap.0", "photonmap.1"}},
      {"nested",
       bench::temp_script("chaos-nested.lua",
                          head + "local inner = multiplexer { lightop \"direct\" { light_samples = 4 }, replicas = 2 }\n"
                                 "local outer = multiplexer { inner, replicas = 2 }\n"
                                 "renderers { count = 3, lighting = outer }\n"),
       {{"renderer-0", "renderer-1", "renderer-2"}, {"direct.0.0", "direct.0.1"}, {"direct.1.0", "direct.1.1"}},
       {}},
      {"cache",
       bench::temp_script("chaos-cache.lua",
                          "scene { builtin = \"cornell\" }\nimage { width = 96, height = 96, spp = 64, tile = 16 }\n"
                          "farm { heartbeat_timeout = 1.5 }\n"
                          "local d = multiplexer { lightop \"direct\" {}, replicas = 2 }\n"
                          "local c = multiplexer { lightop \"irradiance\" { input = d, prepass = 4000 }, replicas = 2 }\n"
                          "renderers { count = 2, lighting = lightop \"combine\" { inputs = { d, c } } }\n"),
       {{"renderer-0", "renderer-1"}, {"irradiance.0", "irradiance.1"}, {"direct.0", "direct.1"}},
       {"irradiance.0", "irradiance.1"}},
      {"radiosity",
       bench::temp_script("chaos-radiosity.lua",
                          "scene { builtin = \"cornell\" }\nimage { width = 64, height = 64, spp = 16, tile = 16 }\n"
                          "farm { heartbeat_timeout = 1.5 }\n"
                          "local ring = radiosity { rings = 2, ring_length = 2, patch_size = 60, converge = 0, "
                          "max_iterations = 60, checkpoint_every = 5 }\n"
                          "renderers { count = 2, lighting = ring }\n"),
       {{"renderer-0", "renderer-1"}},
       {},
       {"radiosity.0.0", "radiosity.0.1", "radiosity.1.0", "radiosity.1.1"}},
  };

  std::mt19937 rng(seed);
  lf::Value::Map doc;
  std::printf("lightfarm chaos soak: %d frames per network, seed %u\n", frames, seed);
  std::printf("%-9s %7s %9s %9s %7s %8s %11s %7s\n", "network", "frames", "finished", "differing", "failed", "orphans",
              "files_left", "faults");
  for (const auto& net : networks) {
    if (!only.empty() && net.name != only) continue;
    const std::string reference_path = (dir / (net.name + "-reference.exr")).string();
    bench::run_farm(net.script, {}, reference_path);
    auto reference = lf::read_image(reference_path);
    if (!reference) {
      std::fprintf(stderr, "chaos_soak: %s\n", reference.error().message.c_str());
      return 1;
    }
    int finished = 0, differing = 0, failed = 0, orphans = 0, files_left = 0, faults = 0;
    std::vector<std::string> failures;
    for (int f = 0; f < frames; ++f) {
      const auto before = lightfarm_files(dir);
      const std::string out = (dir / (net.name + ".exr")).string();
      fs::remove(out);
      Farm farm({"run", net.script, "--output", out});
      std::vector<size_t> alive;  // per group: members not yet hit
      for (const auto& group : net.groups) alive.push_back(group.size());
      std::set<std::string> hit;
      const int planned = 1 + static_cast<int>(rng() % 3);
      std::uniform_real_distribution<double> when(0.3, 2.5);
      for (int k = 0; k < planned; ++k) {
        std::this_thread::sleep_for(std::chrono::duration<double>(when(rng) / planned));
        const std::string err = farm.err_so_far();
        const bool rendering = err.find("render ") != std::string::npos;
        if (err.find("render 100%") != std::string::npos) break;
        // A victim whose group keeps a survivor.
        std::vector<std::pair<size_t, std::string>> candidates;
        for (size_t g = 0; g < net.groups.size(); ++g)
          if (alive[g] > 1)
            for (const auto& name : net.groups[g])
              if (!hit.count(name) && (rendering || !net.render_only.count(name))) candidates.emplace_back(g, name);
        for (const auto& name : net.restarted)
          if (!hit.count(name)) candidates.emplace_back(net.groups.size(), name);
        if (candidates.empty()) break;
        const auto [group, victim] = candidates[rng() % candidates.size()];
        const auto pids = lf::test::actor_pids(farm.tag(), victim);
        if (pids.empty()) continue;
        hit.insert(victim);
        if (group < alive.size()) --alive[group];  // a stopped one may be declared dead: count it gone either way
        ++faults;
        if (rng() % 5 < 3) {
          ::kill(pids[0], SIGKILL);
        } else {
          ::kill(pids[0], SIGSTOP);
          std::this_thread::sleep_for(std::chrono::duration<double>(0.2 + 2.8 * (rng() % 1000) / 1000.0));
          ::kill(pids[0], SIGCONT);
        }
      }
      auto r = farm.wait(120);
      if (r.status == 0) {
        ++finished;
        auto img = lf::read_image(out);
        if (!img || img->pixels != reference->pixels) ++differing;
      } else {
        ++failed;
        failures.push_back(net.name + " frame " + std::to_string(f) + ": exit " + std::to_string(r.status) + ": " +
                           r.err.substr(r.err.rfind("lightfarm: error:") == std::string::npos ? 0 : r.err.rfind("lightfarm: error:")));
      }
      orphans += static_cast<int>(lf::test::wait_no_leftovers(r.tag, 5.0).size());
      for (const auto& file : lightfarm_files(dir))
        if (!before.count(file)) ++files_left;
    }
    std::printf("%-9s %7d %9d %9d %7d %8d %11d %7d\n", net.name.c_str(), frames, finished, differing, failed, orphans,
                files_left, faults);
    for (const auto& why : failures) std::printf("  %s", why.back() == '\n' ? why.c_str() : (why + "\n").c_str());
    auto n = [](int v) { return lf::Value(static_cast<int64_t>(v)); };
    doc[net.name] = lf::Value::Map{{"frames", n(frames)}, {"finished", n(finished)}, {"differing", n(differing)},
                                   {"failed", n(failed)}, {"orphans", n(orphans)},   {"files_left", n(files_left)},
                                   {"faults", n(faults)}};
  }
  fs::remove_all(dir);
  std::ofstream(json_path) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json_path.c_str());
  return 0;
}
