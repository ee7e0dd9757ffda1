// Plugging actors in as processes (issue 6): a Python LightOp and an out-of-tree C++ LightOp built against the
// installed SDK pass check-actor and render in farms; broken actors fail check-actor saying why, and farms that
// contain them stop cleanly with that message.
#include <gtest/gtest.h>

#include <cstdlib>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kTint = kSource + "/examples/plugin-python/tint.py";
const std::string kBroken = kSource + "/tests/actors/broken_actor.py";

using PluginTest = FarmFixture;

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

TEST_F(PluginTest, ExamplesAndBuiltinsPassCheckActor) {
  struct Case {
    std::vector<std::string> args;
    int checks;  // hello configure setup render requests [inputs] malformed frame heartbeat bye orphaned sigterm
  };
  for (const auto& c : std::vector<Case>{{{"check-actor", "--", kTint}, 11},
                                         {{"check-actor", "--inputs", "1", "--", kTint}, 12},
                                         {{"check-actor", "--kind", "direct", "--", LIGHTFARM_BINARY, "actor"}, 11},
                                         {{"check-actor", "--inputs", "1", "--", kBroken, "--mode", "ok"}, 12}}) {
    auto r = run_lightfarm(c.args);
    EXPECT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_EQ(count(r.out, "PASS "), c.checks) << r.out;
    EXPECT_EQ(count(r.out, "FAIL "), 0) << r.out;
    expect_no_leftovers(r);
  }
}

// Each way an actor can break the contract fails exactly its own check, saying why.
TEST_F(PluginTest, EachBrokenContractFailsItsOwnCheck) {
  struct Case {
    const char* mode;
    const char* says;
  };
  for (const Case& c :
       {Case{"no_ready_render", "FAIL render     no READY render within 2 s"},
        Case{"no_ready_frame", "FAIL frame      no READY frame within 2 s"},
        Case{"ignore_input", "FAIL inputs     asked its input nothing while shading"},
        Case{"ignore_sigterm", "FAIL sigterm    still running 2 s after SIGTERM"},
        Case{"silent_on_malformed", "FAIL malformed  no ERROR for malformed packet 1: nothing within 2 s"},
        Case{"wrong_n", "FAIL requests   shade reply says n = 2 but holds 1 radiance values"},
        Case{"no_routing_id", "FAIL hello      HELLO came from routing id '"}}) {
    auto r = run_lightfarm({"check-actor", "--inputs", "1", "--timeout", "2", "--", kBroken, "--mode", c.mode});
    EXPECT_EQ(r.status, 1) << c.mode;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.mode << ":\n" << r.out;
    // wrong_n also fails the good requests after the malformed ones and after a frame; every other variant fails once.
    EXPECT_EQ(count(r.out, "FAIL "), std::string(c.mode) == "wrong_n" ? 3 : 1) << c.mode << ":\n" << r.out;
    expect_no_leftovers(r);
  }
}

TEST_F(PluginTest, BrokenActorsFailCheckActorSayingWhy) {
  struct Case {
    const char* mode;
    const char* says;
  };
  for (const Case& c : {Case{"wrong_version", "FAIL hello      no HELLO: incompatible peer: protocol version 2, expected 1"},
                        Case{"silent", "FAIL requests   no REPLY to 1 points within 2 s"},
                        Case{"crash", "FAIL requests   the actor exited with status 3 while shading 1 points"}}) {
    auto r = run_lightfarm({"check-actor", "--timeout", "2", "--", kBroken, "--mode", c.mode});
    EXPECT_EQ(r.status, 1) << c.mode;
    EXPECT_NE(r.out.find(c.says), std::string::npos) << c.mode << ":\n" << r.out;
    expect_no_leftovers(r);
  }
}

// check-actor runs an actor as a farm does, with CURVE: one written without it fails hello saying so, naming the
// actor and the way out, where it used to pass every check and then time out in every farm; --security none checks
// it as a farm without CURVE would run it.
TEST_F(PluginTest, CheckActorSpeaksCurveAsFarmsDo) {
  auto r = run_lightfarm({"check-actor", "--timeout", "2", "--", kBroken, "--mode", "no_curve"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("FAIL hello      no HELLO: the director's side refused "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("connection(s) from 'check' that did not speak CURVE"), std::string::npos) << r.out;
  expect_no_leftovers(r);
  auto plain = run_lightfarm({"check-actor", "--timeout", "2", "--security", "none", "--", kBroken, "--mode", "no_curve"});
  EXPECT_EQ(plain.status, 0) << plain.out << plain.err;
  EXPECT_EQ(count(plain.out, "FAIL "), 0) << plain.out;
  expect_no_leftovers(plain);
}

// check-actor keeps a configured actor alive with HEARTBEATs as a director does: a correct actor whose answers take
// longer in all than its heartbeat timeout (0.35 s a request, a 1 s timeout) passes, where it used to take check-actor's
// silence for a dead director, exit, and be blamed for it.
TEST_F(PluginTest, CheckActorKeepsASlowActorAlive) {
  auto r = run_lightfarm({"check-actor", "--heartbeat-timeout", "1", "--timeout", "3", "--", kBroken, "--mode", "slow"});
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_EQ(count(r.out, "PASS "), 11) << r.out;
  expect_no_leftovers(r);
}

TEST_F(PluginTest, FarmsWithBrokenActorsStopCleanlyNamingTheProblem) {
  struct Case {
    const char* mode;
    const char* says;
  };
  for (const Case& c : {Case{"wrong_version", "lightfarm: error: actor 'broken' is an incompatible peer: protocol version 2, expected 1"},
                        Case{"silent", "lightfarm: error: actor 'renderer-0' failed: lighting failed: no answer from 'broken' within 2 s (request 1, shade, waited 2"},
                        Case{"crash", "lightfarm: error: actor 'broken' (pid "},
                        Case{"no_ready_render", "lightfarm: error: every tile is done, but 'broken' never answered PHASE "
                                                "render with READY render"},
                        Case{"wrong_n", "lightfarm: error: actor 'renderer-0' failed: lighting 'broken': shade reply "
                                        "says n = "}}) {
    auto script = write(std::string(c.mode) + ".lua", "scene { builtin = \"cornell\" }\n"
                                                      "image { width = 32, height = 32, spp = 1 }\n"
                                                      "farm { request_timeout = 2 }\n"
                                                      "local b = lightop.exec { cmd = {\"" + kBroken + "\", \"--mode\", \"" +
                                                      c.mode + "\"}, name = \"broken\" }\n"
                                                      "renderers { count = 1, lighting = b }\n");
    auto r = run_lightfarm({"run", script, "--output", path(std::string(c.mode) + ".png")});
    EXPECT_EQ(r.status, 1) << c.mode << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.mode << ":\n" << r.err;
    if (std::string(c.mode) == "crash") {
      EXPECT_NE(r.err.find("exited with status 3 during render"), std::string::npos) << r.err;
    }
    EXPECT_FALSE(fs::exists(path(std::string(c.mode) + ".png")));
    expect_no_leftovers(r);
  }
}

// Once the image is written the farm's work is done: an actor that then ends badly (here it exits 3 on PHASE
// finish; a cut host's ssh exits 255) is a warning, and the exit status is 0.
TEST_F(PluginTest, AnActorEndingBadlyAfterTheImageIsWrittenIsAWarning) {
  auto script = write("finish.lua", "scene { builtin = \"cornell\" }\n"
                                    "image { width = 16, height = 16, spp = 1 }\n"
                                    "local b = lightop.exec { cmd = {\"" + kBroken + "\", \"--mode\", \"crash_at_finish\"}, "
                                    "name = \"broken\" }\n"
                                    "renderers { count = 1, lighting = b }\n");
  auto r = run_lightfarm({"run", script, "--output", path("finish.png")});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("lightfarm: warning: actor 'broken' (pid "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("exited with status 3 during finish after the image was written"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("error:"), std::string::npos) << r.err;
  auto image = read_image(path("finish.png"));
  ASSERT_TRUE(image.ok()) << image.error().message;
  EXPECT_EQ(image->width, 16);
  expect_no_leftovers(r);
}

TEST_F(PluginTest, PythonTintMultipliesItsInputsLight) {
  // adaptive_spp = 0: which pixels get more samples would follow the tinted light, not the plain one
  auto plain_script = write("plain.lua", "scene { builtin = \"cornell\" }\n"
                                         "image { width = 48, height = 48, spp = 2, tile = 16, adaptive_spp = 0 }\n"
                                         "renderers { count = 2, lighting = lightop \"direct\" { light_samples = 2 } }\n");
  auto tint_script = write("tint.lua", "scene { builtin = \"cornell\" }\n"
                                       "image { width = 48, height = 48, spp = 2, tile = 16, adaptive_spp = 0 }\n"
                                       "local d = lightop \"direct\" { light_samples = 2 }\n"
                                       "local t = multiplexer { lightop.exec { cmd = {\"" + kTint +
                                       "\"}, input = d, color = {1, 0, 0} }, replicas = 2 }\n"
                                       "renderers { count = 2, lighting = t }\n");
  auto plain = run_lightfarm({"run", plain_script, "--output", path("plain.exr")});
  auto tinted = run_lightfarm({"run", tint_script, "--output", path("tint.exr")});
  ASSERT_EQ(plain.status, 0) << plain.err;
  ASSERT_EQ(tinted.status, 0) << tinted.err;
  expect_no_leftovers(plain);
  expect_no_leftovers(tinted);
  auto a = read_image(path("plain.exr")), b = read_image(path("tint.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  // Emission the camera sees is added by the renderer (to both), so green and blue are compared only on pixels with
  // no light source in view: not the light, nor its outline's pixels next to it.
  const int w = a->width, h = a->height;
  auto light = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h && a->pixels[static_cast<size_t>(y * w + x)].x > 1.0f; };
  int compared = 0;
  for (size_t i = 0; i < a->pixels.size(); ++i) {
    EXPECT_EQ(b->pixels[i].x, a->pixels[i].x) << i;  // red passes unchanged, bit for bit
    const int x = static_cast<int>(i) % w, y = static_cast<int>(i) / w;
    bool near = false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) near = near || light(x + dx, y + dy);
    if (near) continue;
    EXPECT_EQ(b->pixels[i].y, 0.0f) << i;
    EXPECT_EQ(b->pixels[i].z, 0.0f) << i;
    ++compared;
  }
  EXPECT_GT(compared, 2000);
}

TEST_F(PluginTest, SdkBuildsAnOutOfTreeLightOpThatRendersInAFarm) {
  const std::string prefix = path("prefix"), build = path("build");
  auto sh = [&](const std::string& cmd) {
    int rc = std::system((cmd + " > " + path("sdk.log") + " 2>&1").c_str());
    EXPECT_EQ(rc, 0) << cmd << "\n" << read_file(path("sdk.log"));
    return rc == 0;
  };
  ASSERT_TRUE(sh("cmake --install " + std::string(LIGHTFARM_BUILD_DIR) + " --prefix " + prefix));
  ASSERT_TRUE(sh("cmake -S " + kSource + "/examples/plugin-cpp -B " + build + " -DCMAKE_PREFIX_PATH=" + prefix));
  ASSERT_TRUE(sh("cmake --build " + build + " -j2"));
  const std::string program = build + "/ambient_occlusion";

  auto check = run_lightfarm({"check-actor", "--", program});
  EXPECT_EQ(check.status, 0) << check.out << check.err;
  EXPECT_EQ(count(check.out, "PASS "), 11) << check.out;  // every check but inputs

  const std::string script = kSource + "/examples/plugin-cpp/ao_cornell.lua";
  auto one = run_lightfarm({"run", script, "--set", "program=" + program, "--set", "replicas=1", "--set", "width=48",
                            "--set", "height=48", "--output", path("ao1.exr")});
  auto two = run_lightfarm({"run", script, "--set", "program=" + program, "--set", "replicas=2", "--set", "width=48",
                            "--set", "height=48", "--output", path("ao2.exr")});
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_EQ(two.status, 0) << two.err;
  expect_no_leftovers(one);
  expect_no_leftovers(two);
  auto a = read_image(path("ao1.exr")), b = read_image(path("ao2.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->pixels == b->pixels) << "the out-of-tree op gives the same image on one or two replicas";
  // Ambient occlusion of albedo <= 1 under ambient 1: every non-emitting pixel in [0, 1], and open surfaces bright.
  double sum = 0;
  int n = 0;
  for (const RGB& p : a->pixels) {
    if (p.x > 1.0f) continue;  // the light, seen directly
    EXPECT_GE(p.y, 0.0f);
    sum += p.y;
    ++n;
  }
  EXPECT_GT(sum / n, 0.3);
}

}  // namespace
}  // namespace lf::test
