// The live monitor (issue 15): the page as headless Chromium shows it while a farm runs (every actor, the image
// filling in, a replica killed mid-frame shown as lost), /api/state and /metrics against the end-of-run figures,
// many and vanishing clients, the token off loopback, and a port in use.
#include <httplib.h>

#include <atomic>
#include <cstdio>
#include <regex>
#include <thread>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kCornell = kSource + "/examples/cornell.lua";
const std::string kSlowPool = kSource + "/tests/scripts/slow_pool.lua";

// The monitor's address, from the line the director prints at start.
std::string monitor_url(Farm& farm) {
  std::string url;
  Farm::eventually([&] {
    std::smatch m;
    const std::string err = farm.err_so_far();
    if (std::regex_search(err, m, std::regex("monitor: (http://[^ \n]+)"))) url = m[1];
    return !url.empty();
  }, 20);
  return url;
}

std::string run_command(const std::string& command) {
  std::string out;
  if (FILE* p = ::popen(command.c_str(), "r")) {
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    ::pclose(p);
  }
  return out;
}

bool have_chromium() { return ::system("command -v chromium > /dev/null 2>&1") == 0; }

// The page's DOM once its scripts have run, as headless Chromium renders it (one look: ?snapshot).
std::string page_dom(const std::string& url) {
  return run_command("timeout 60 chromium --headless=new --no-sandbox --disable-gpu --no-first-run "
                     "--user-data-dir=$(mktemp -d) --virtual-time-budget=2000 --dump-dom '" +
                     url + (url.find('?') == std::string::npos ? "?" : "&") + "snapshot' 2>/dev/null");
}

std::string attribute(const std::string& dom, const std::string& element_id, const std::string& name) {
  std::smatch m;
  if (!std::regex_search(dom, m, std::regex("id=\"" + element_id + "\"[^>]*" + name + "=\"([^\"]*)\""))) return "";
  return m[1];
}

std::string state_of(const std::string& dom, const std::string& actor) {
  std::smatch m;
  if (!std::regex_search(dom, m, std::regex("<tr data-actor=\"" + actor + "\" data-state=\"([a-z]+)\""))) return "";
  return m[1];
}

std::pair<std::string, httplib::Client> client_for(const std::string& url) {
  std::smatch m;
  std::regex_search(url, m, std::regex("http://([^:/]+):([0-9]+)/(\\?token=[0-9a-f]+)?"));
  return {m[3], httplib::Client(m[1].str(), std::stoi(m[2]))};
}

// /api/state of a farm run with --monitor 0 and --monitor-hold, read once it holds after the frame; "" if it never
// does. `url`: the monitor's.
std::string held_state(Farm& farm, std::string& url) {
  url = monitor_url(farm);
  if (url.empty() ||
      !Farm::eventually([&] { return farm.err_so_far().find("monitor: holding") != std::string::npos; }, 60))
    return {};
  auto [token, client] = client_for(url);
  auto state = client.Get("/api/state");
  return state ? state->body : std::string();
}

class MonitorTest : public FarmFixture {};

TEST_F(MonitorTest, ThePageShowsTheNetworkTheImageFillingInAndALostReplica) {
  if (!have_chromium()) GTEST_SKIP() << "no chromium (Debian's chromium package) for the page test";
  // A frame of some 8 s: long enough to look at the page, then kill a replica, while it renders.
  Farm farm({"run", kSlowPool, "--set", "spp=192", "--set", "slowdown=6", "--set", "heartbeat_timeout=1.5",
             "--monitor", "0", "--monitor-hold", "120", "--output", path("slow.exr")});
  const std::string url = monitor_url(farm);
  ASSERT_FALSE(url.empty()) << farm.err_so_far();
  EXPECT_EQ(url.find("token"), std::string::npos) << "loopback needs no token";
  // A browser that watches the live page from the start to the end of the farm (?watch: it hangs up only when
  // the farm has gone, then its page is dumped): it is sent the whole image, then only the blocks that change.
  std::string watched;
  std::thread watcher([&] {
    watched = run_command("timeout 300 chromium --headless=new --no-sandbox --disable-gpu --no-first-run "
                          "--user-data-dir=$(mktemp -d) --virtual-time-budget=600000 --dump-dom '" + url +
                          "?watch=600000' 2>/dev/null");
  });
  struct StopFirst {  // an assertion that fails below must not leave the watcher's thread joinable
    std::thread& watcher;
    pid_t farm;
    ~StopFirst() {
      if (!watcher.joinable()) return;
      ::kill(farm, SIGINT);
      watcher.join();
    }
  } stop_first{watcher, farm.pid()};
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60));

  // The page is refreshed once a second: the first look that shows the render under way (every actor rendering,
  // tiles in the preview). A state published just before the actors started counts as not yet.
  std::string first;
  Farm::eventually([&] {
    first = page_dom(url);
    for (const char* actor : {"renderer-0", "renderer-1", "direct.0", "direct.1"})
      if (state_of(first, actor) != "rendering") return false;
    return std::atoi(attribute(first, "preview", "data-tiles").c_str()) > 0;
  }, 30);
  // Every actor of the farm, in the graph and in the table.
  for (const char* actor : {"renderer-0", "renderer-1", "direct", "direct.0", "direct.1"}) {
    EXPECT_NE(first.find(std::string("<g class=\"node\" data-actor=\"") + actor + "\""), std::string::npos) << actor;
    // The pool itself has no process: its renderers dispatch to its replicas.
    EXPECT_EQ(state_of(first, actor), std::string(actor) == "direct" ? "pool" : "rendering") << actor;
  }
  EXPECT_NE(first.find("<g class=\"host\" data-host=\"local\">"), std::string::npos) << "the actors' host band";
  const int tiles_first = std::atoi(attribute(first, "preview", "data-tiles").c_str());
  EXPECT_GT(tiles_first, 0) << "the preview shows the first tiles";
  EXPECT_EQ(attribute(first, "preview", "width"), "128");

  auto replica = actor_pids(farm.tag(), "direct.1");
  ASSERT_EQ(replica.size(), 1u);
  ::kill(replica[0], SIGKILL);
  std::string later;
  ASSERT_TRUE(Farm::eventually([&] {
    later = page_dom(url);
    return state_of(later, "direct.1") == "lost";
  }, 30)) << later;
  // Tiles keep landing, and the preview shows them (it is refreshed at most once a second).
  EXPECT_TRUE(Farm::eventually([&] {
    later = page_dom(url);
    return std::atoi(attribute(later, "preview", "data-tiles").c_str()) > tiles_first;
  }, 30)) << later;
  EXPECT_NE(attribute(later, "preview", "data-checksum"), attribute(first, "preview", "data-checksum"));
  EXPECT_NE(later.find("class=\"loss\""), std::string::npos) << "the loss is marked in the log";

  // The frame completes; the held page shows it done. One screenshot is kept beside the build as an artifact.
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("monitor: holding") != std::string::npos; }, 120));
  const std::string done = page_dom(url);
  EXPECT_EQ(state_of(done, "direct.1"), "lost");
  EXPECT_EQ(state_of(done, "direct.0"), "done");
  EXPECT_EQ(attribute(done, "preview", "data-tiles"), "64");
  run_command("timeout 60 chromium --headless=new --no-sandbox --disable-gpu --no-first-run --user-data-dir=$(mktemp -d) "
              "--virtual-time-budget=2000 --window-size=1280,1000 --screenshot=" LIGHTFARM_BUILD_DIR
              "/monitor-screenshot.png '" + url + "?snapshot' > /dev/null 2>&1");
  auto [token, client] = client_for(url);
  auto final_preview = client.Get("/api/preview");
  ASSERT_TRUE(final_preview);
  long long final_sum = 0;  // the page's checksum: byte k weighted by (k mod 251) + 1
  for (size_t k = 0; k < final_preview->body.size(); ++k)
    final_sum += static_cast<unsigned char>(final_preview->body[k]) * static_cast<long long>(k % 251 + 1);
  // The hold is long (a browser on a loaded machine took over 5 s to fetch the held page); Ctrl-C ends it, and a
  // signal once the image is written is still a clean exit.
  ::kill(farm.pid(), SIGINT);
  auto r = farm.wait(60);
  watcher.join();
  EXPECT_EQ(r.status, 0) << r.err;
  // The watching page built the final image from a whole one and the changes that followed.
  EXPECT_EQ(attribute(watched, "preview", "data-tiles"), "64") << watched;
  EXPECT_GT(std::atoi(attribute(watched, "preview", "data-updates").c_str()), 2) << watched;
  EXPECT_EQ(attribute(watched, "preview", "data-checksum"), std::to_string(final_sum));
  expect_no_leftovers(r);
}

// /api/state and /metrics, read while the page is held after the frame, hold what the end-of-run figures say.
TEST_F(MonitorTest, StateAndMetricsHoldTheEndOfRunFigures) {
  Farm farm({"run", kCornell, "--set", "width=64", "--set", "height=64", "--set", "spp=4", "--monitor", "0",
             "--monitor-hold", "30", "--stats-json", path("stats.json"), "--output", path("c.exr")});
  const std::string url = monitor_url(farm);
  ASSERT_FALSE(url.empty()) << farm.err_so_far();
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("monitor: holding") != std::string::npos; }, 60));
  auto [token, client] = client_for(url);
  auto state = client.Get("/api/state");
  auto metrics = client.Get("/metrics");
  ASSERT_TRUE(state && metrics);
  EXPECT_EQ(state->status, 200);
  write("state.json", state->body);
  // Parsed by Python's json (a parser we did not write), and held against --stats-json's figures.
  const std::string check = run_command(
      "python3 -c \"import json,sys; s=json.load(open('" + path("state.json") + "')); t=json.load(open('" +
      path("stats.json") + "')); st={a['name']: a for a in t['actors']}; "
      "print(s['farm']['stage'], s['farm']['tiles_done'], s['farm']['tiles_total'], "
      "all(a['live']['points'] == st[a['name']]['points'] and a['live']['requests'] == st[a['name']]['requests'] "
      "for a in s['actors']), sorted(a['name'] for a in s['actors']))\"");
  EXPECT_EQ(check, "done 4 4 True ['direct', 'renderer-0', 'renderer-1']\n") << state->body;
  // Metrics: Prometheus text, one series per actor, the same counts.
  EXPECT_EQ(metrics->get_header_value("Content-Type").rfind("text/plain", 0), 0u);
  const std::string points = run_command("python3 -c \"import json; t=json.load(open('" + path("stats.json") +
                                         "')); print([a['points'] for a in t['actors'] if a['name']=='direct'][0])\"");
  EXPECT_NE(metrics->body.find("lightfarm_actor_points_total{actor=\"direct\",kind=\"direct\"} " +
                               points.substr(0, points.size() - 1) + ".000000\n"),
            std::string::npos)
      << metrics->body;
  EXPECT_NE(metrics->body.find("lightfarm_tiles_done 4.000000\n"), std::string::npos);
  EXPECT_NE(metrics->body.find("# TYPE lightfarm_actor_busy_seconds_total counter\n"), std::string::npos);
  ::kill(farm.pid(), SIGINT);  // ends the hold
  auto r = farm.wait(30);
  EXPECT_EQ(r.status, 0) << r.err;
  expect_no_leftovers(r);
}

// A job of frames: /api/state says how far it is, and its output is the frame's.
TEST_F(MonitorTest, StateShowsAJobsFrames) {
  const std::string script = write("job.lua", "scene { builtin = \"cornell\" }\n"
                                              "image { width = 32, height = 32, spp = 2, output = \"" + path("j.####.exr") + "\" }\n"
                                              "frames { first = 3, last = 5 }\n"
                                              "renderers { count = 1, lighting = lightop \"direct\" { } }\n"
                                              "farm { light_paths = \"partial\" }\n");
  Farm farm({"run", script, "--monitor", "0", "--monitor-hold", "30"});
  std::string url;
  const std::string state = held_state(farm, url);
  ASSERT_FALSE(state.empty()) << farm.err_so_far();
  write("state.json", state);
  const std::string check = run_command("python3 -c \"import json; s=json.load(open('" + path("state.json") +
                                        "')); j=s['job']; print(j['frames_total'], j['frames_done'], j['frame'], "
                                        "j['eta_seconds'], s['farm']['output'].endswith('j.0005.exr'))\"");
  EXPECT_EQ(check, "3 3 0 0 True\n") << state;
  if (have_chromium()) {  // the page says it too
    const std::string dom = page_dom(url);
    EXPECT_NE(dom.find("frame - (3 of 3 done, ~0 s left) · tiles 1 / 1"), std::string::npos) << dom;
  }
  ::kill(farm.pid(), SIGINT);
  auto r = farm.wait(30);
  EXPECT_EQ(r.status, 0) << r.err;
  expect_no_leftovers(r);
}

// Fifty clients on /events at once, one of which drops its stream mid-way, do not break the farm or change its
// image.
TEST_F(MonitorTest, ManyClientsAndADroppedStreamLeaveTheFarmAndItsImageAlone) {
  const std::vector<std::string> base{"run", kSlowPool, "--set", "spp=32", "--set", "slowdown=3"};
  auto plain = base;
  plain.insert(plain.end(), {"--output", path("plain.exr")});
  auto r0 = run_lightfarm(plain);
  ASSERT_EQ(r0.status, 0) << r0.err;

  auto watched = base;
  // Held 8 s after the frame, so that every client has connected before the server goes, on a loaded machine too
  // (with 3 s, 36 of the 50 had connected once while a build ran beside the tests).
  watched.insert(watched.end(), {"--monitor", "0", "--monitor-hold", "8", "--output", path("watched.exr")});
  Farm farm(watched);
  const std::string url = monitor_url(farm);
  ASSERT_FALSE(url.empty()) << farm.err_so_far();
  std::atomic<int> got_state{0}, got_preview{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < 50; ++c)
    clients.emplace_back([&, c] {
      auto [token, client] = client_for(url);
      client.set_read_timeout(60, 0);
      size_t seen = 0;
      bool counted_state = false, counted_preview = false;
      std::string tail;  // the end of the last read: an event's name may be split across two reads
      client.Get("/events", [&](const char* data, size_t n) {
        const std::string chunk = tail + std::string(data, n);
        tail = chunk.substr(chunk.size() > 32 ? chunk.size() - 32 : 0);
        if (!counted_state && chunk.find("event: state") != std::string::npos) counted_state = true, ++got_state;
        if (!counted_preview && chunk.find("event: preview") != std::string::npos) counted_preview = true, ++got_preview;
        seen += n;
        return c != 0 || seen < 2000;  // client 0 hangs up after its first events
      });
    });
  auto r = farm.wait(120);
  for (auto& t : clients) t.join();
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(got_state.load(), 50);
  EXPECT_GE(got_preview.load(), 49);
  auto a = read_image(path("plain.exr")), b = read_image(path("watched.exr"));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->pixels, b->pixels) << "the monitor does not change the image";
  expect_no_leftovers(r);
}

// A partitioned scene's parts appear in the state with whose rays they answer (the page draws them dotted).
TEST_F(MonitorTest, APartitionedFarmsStateSaysWhoseRaysThePartsAnswer) {
  const std::string script = write("parts.lua", R"(scene { builtin = "cornell" }
image { width = 32, height = 32, spp = 1 }
partition { parts = 2 }
renderers { count = 1, lighting = lightop "direct" {} }
)");
  Farm farm({"run", script, "--monitor", "0", "--monitor-hold", "30", "--output", path("parts.exr")});
  std::string url;
  const std::string state = held_state(farm, url);
  ASSERT_FALSE(state.empty()) << farm.err_so_far();
  write("parts-state.json", state);
  const std::string check = run_command("python3 -c \"import json; s=json.load(open('" + path("parts-state.json") +
                                        "')); print(sorted((a['name'], a.get('rays_from')) for a in s['actors'] "
                                        "if a['kind'] != 'geometry'))\"");
  EXPECT_EQ(check, "[('direct', ['geometry.0', 'geometry.1']), ('renderer-0', ['geometry.0', 'geometry.1'])]\n")
      << state;
  ::kill(farm.pid(), SIGINT);  // ends the hold
  auto r = farm.wait(30);
  EXPECT_EQ(r.status, 0) << r.err;
  expect_no_leftovers(r);
}

// Off loopback, a request without the token printed at start is refused.
TEST_F(MonitorTest, AMonitorBeyondLoopbackWantsItsToken) {
  Farm farm({"run", kCornell, "--set", "width=32", "--set", "height=32", "--set", "spp=1", "--monitor", "0.0.0.0:0",
             "--monitor-hold", "30", "--output", path("c.exr")});
  const std::string url = monitor_url(farm);
  ASSERT_NE(url.find("?token="), std::string::npos) << farm.err_so_far();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(url, m, std::regex(":([0-9]+)/\\?token=([0-9a-f]{16})$"))) << url;
  httplib::Client client("127.0.0.1", std::stoi(m[1]));
  auto refused = client.Get("/api/state");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 403);
  auto let_in = client.Get("/api/state?token=" + m[2].str());
  ASSERT_TRUE(let_in);
  EXPECT_EQ(let_in->status, 200);
  auto wrong = client.Get("/metrics?token=0000000000000000");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 403);
  ::kill(farm.pid(), SIGINT);
  auto r = farm.wait(30);
  expect_no_leftovers(r);
}

// A port that is taken stops the farm before anything launches, saying so.
TEST_F(MonitorTest, APortInUseIsAClearErrorBeforeAnythingStarts) {
  httplib::Server holder;
  const int port = holder.bind_to_any_port("127.0.0.1");
  ASSERT_GT(port, 0);
  auto r = run_lightfarm({"run", kCornell, "--monitor", std::to_string(port), "--output", path("c.exr")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "lightfarm: error: --monitor: cannot listen on 127.0.0.1:" + std::to_string(port) +
                       " (in use, or not an address of this machine)\n");
  EXPECT_FALSE(fs::exists(path("c.exr")));
  expect_no_leftovers(r);
}

}  // namespace
}  // namespace lf::test
