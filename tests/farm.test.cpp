// The farm as users run it: the real binary, real processes, real images. Every test also checks that no process
// of its farm is left running.
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "render/tracing/camera.hpp"
#include "render/images/image.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/scene/scene.hpp"
#include "render/tracing/tracer.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kCornellScript = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/cornell.lua";

using FarmTest = FarmFixture;

// Renders the Cornell script small and fast; returns the result and the EXR image.
RunResult render_cornell(const std::string& output, std::vector<std::string> extra = {}) {
  std::vector<std::string> args{"run", kCornellScript, "--output", output, "--set", "width=64", "--set", "height=64",
                                "--set", "spp=4", "--set", "tile=16"};
  args.insert(args.end(), extra.begin(), extra.end());
  return run_lightfarm(args);
}

// Classifies each pixel by the material its centre ray hits, using the same scene and camera as the script.
std::vector<std::string> pixel_materials(int w, int h) {
  auto scene = Scene::builtin("cornell");
  RayTracer tracer(*scene);
  CameraSpec cam;  // the script uses the classic camera, which is the default
  Camera camera(cam, w, h);
  std::vector<std::string> names(static_cast<size_t>(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Ray ray = camera.ray(x + 0.5f, y + 0.5f);
      Hit hit;
      tracer.intersect(std::span<const Ray>(&ray, 1), std::span<Hit>(&hit, 1));
      std::string name = "none";
      if (hit.valid()) {
        name = scene->material(scene->material_of(hit.triangle)).name;
        Vec3 p = ray.origin + ray.direction * hit.t;
        if (name == "white" && p.y < 1.0f) {
          const bool under_light = p.x > 213 && p.x < 343 && p.z > 227 && p.z < 332;
          const bool corner = (p.x < 80 || p.x > 470) && p.z > 480;
          name = under_light ? "floor-under-light" : corner ? "floor-corner" : "floor";
        }
      }
      names[static_cast<size_t>(y * w + x)] = name;
    }
  return names;
}

TEST_F(FarmTest, CornellBoxImageLooksLikeTheCornellBox) {
  auto r = render_cornell(path("cornell.exr"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + path("cornell.exr")), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("phase"), std::string::npos);  // the phase table
  EXPECT_NE(r.err.find("renderer-1"), std::string::npos);  // the stats table lists every actor
  expect_no_leftovers(r);

  auto img = read_image(path("cornell.exr"));
  ASSERT_TRUE(img.ok()) << img.error().message;
  ASSERT_EQ(img->width, 64);
  auto classes = pixel_materials(64, 64);
  std::map<std::string, RGB> sum;
  std::map<std::string, int> count;
  float brightest = 0;
  std::string brightest_class;
  for (size_t i = 0; i < classes.size(); ++i) {
    sum[classes[i]] += img->pixels[i];
    ++count[classes[i]];
    if (average(img->pixels[i]) > brightest) {
      brightest = average(img->pixels[i]);
      brightest_class = classes[i];
    }
  }
  auto mean = [&](const std::string& c) { return sum[c] / static_cast<float>(count[c]); };
  for (const char* c : {"red", "green", "light", "floor-under-light", "floor-corner"})
    ASSERT_GT(count[c], 0) << "no pixel shows " << c;
  RGB red = mean("red"), green = mean("green");
  EXPECT_GT(red.x, 2 * red.y) << "left wall is not red-dominant";
  EXPECT_GT(red.x, 2 * red.z);
  EXPECT_GT(green.y, 1.5f * green.x) << "right wall is not green-dominant";
  EXPECT_GT(green.y, 1.5f * green.z);
  EXPECT_EQ(brightest_class, "light");
  for (const auto& [c, s] : sum) {
    if (c != "light") {
      EXPECT_GT(average(mean("light")), 5 * average(mean(c))) << c;
    }
  }
  EXPECT_GT(average(mean("floor-under-light")), 1.5f * average(mean("floor-corner")));
  // Pixels whose centre ray leaves the box are black but for jittered samples that graze a wall edge.
  EXPECT_LT(average(mean("none")), 0.05f * average(mean("red")));
}

// material "..." { ... } changes the picture as stated: twice the light's emission is twice every pixel under
// `direct` (light picked by relative flux, so its pdf is unchanged), for a built-in scene (each actor applies the
// change) and for an OBJ (the director applies it and ships the changed scene).
TEST_F(FarmTest, MaterialChangesReachEveryActor) {
  write("room.obj", "mtllib room.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
                    "v -0.3 1.99 -0.3\nv 0.3 1.99 -0.3\nv 0.3 1.99 0.3\nv -0.3 1.99 0.3\nusemtl white\nf 1 2 3 4\nf 8 7 6 5\n"
                    "f 5 6 2 1\nf 4 8 5 1\nf 2 6 7 3\nusemtl lamp\nf 12 11 10 9\n");
  write("room.mtl", "newmtl white\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 10 10 10\n");
  struct Case {
    std::string scene, light, emission;
  };
  for (const Case& c : {Case{"builtin = \"cornell\"", "light", "{34, 24, 8}"},
                        Case{"file = \"room.obj\"", "lamp", "{20, 20, 20}"}}) {
    const std::string head = "scene { " + c.scene + " }\n" +
                             (c.scene.find("room") != std::string::npos
                                  ? "camera { eye = {0, 1, 3.5}, at = {0, 1, 0}, fov = 50 }\n"
                                  : "") +
                             // adaptive_spp = 0: which pixels get more samples is no linear function of the light
                             "image { width = 32, height = 32, spp = 2, adaptive_spp = 0 }\n";
    const std::string tail = "renderers { count = 2, lighting = lightop \"direct\" {} }\n";
    auto plain = run_lightfarm({"run", write("plain.lua", head + tail), "--output", path("plain.exr"), "--quiet"});
    auto brighter = run_lightfarm({"run", write("bright.lua", head + "material \"" + c.light + "\" { emission = " +
                                                                  c.emission + " }\n" + tail),
                                   "--output", path("bright.exr"), "--quiet"});
    ASSERT_EQ(plain.status, 0) << plain.err;
    ASSERT_EQ(brighter.status, 0) << brighter.err;
    auto a = read_image(path("plain.exr"));
    auto b = read_image(path("bright.exr"));
    ASSERT_TRUE(a.ok() && b.ok());
    double lit = 0;
    for (size_t i = 0; i < a->pixels.size(); ++i) {
      lit += a->pixels[i].y;
      EXPECT_FLOAT_EQ(b->pixels[i].x, 2 * a->pixels[i].x) << c.scene << " pixel " << i;
      EXPECT_FLOAT_EQ(b->pixels[i].y, 2 * a->pixels[i].y) << c.scene << " pixel " << i;
    }
    EXPECT_GT(lit, 0) << c.scene;
  }
}

// A camera that sees nothing lit (here it looks out of the open Cornell box) gives an image of zeros: the farm
// still writes it and exits 0, and says why the picture is black; a lit picture says nothing of the kind.
TEST_F(FarmTest, AnImageOfZerosIsAWarningNamingLikelyCauses) {
  const std::string head = "scene { builtin = \"cornell\" }\nimage { width = 16, height = 16, spp = 1 }\n"
                           "farm { light_paths = \"partial\" }\n";
  const std::string tail = "renderers { count = 1, lighting = lightop \"direct\" {} }\n";
  auto away = run_lightfarm({"run", write("away.lua", head + "camera { eye = {278, 273, -800}, at = {278, 273, -1600} }\n" + tail),
                             "--output", path("away.exr"), "--quiet"});
  ASSERT_EQ(away.status, 0) << away.err;
  expect_no_leftovers(away);
  auto image = read_image(path("away.exr"));
  ASSERT_TRUE(image.ok());
  EXPECT_TRUE(all_black(*image));
  EXPECT_NE(away.err.find("away.exr: every pixel is 0, nothing the camera sees is lit: it may look at the back"),
            std::string::npos)
      << away.err;
  auto seen = run_lightfarm({"run", write("seen.lua", head + tail), "--output", path("seen.exr"), "--quiet"});
  ASSERT_EQ(seen.status, 0) << seen.err;
  EXPECT_EQ(seen.err.find("every pixel is 0"), std::string::npos) << seen.err;
}

TEST_F(FarmTest, RendererCountDoesNotChangeAPixel) {
  auto one = render_cornell(path("one.exr"), {"--set", "renderers=1"});
  auto three = render_cornell(path("three.exr"), {"--set", "renderers=3"});
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_EQ(three.status, 0) << three.err;
  expect_no_leftovers(one);
  expect_no_leftovers(three);
  auto a = read_image(path("one.exr")), b = read_image(path("three.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->pixels == b->pixels) << "images differ between 1 and 3 renderers";
}

// A thin lens focused just in front of the camera blurs the box: the walls' edges spread out, the light reaching
// the image is the same, and the image is still the same whatever the number of renderers.
TEST_F(FarmTest, ALensBlursWhatIsOutOfFocusAndKeepsTheImageLayoutIndependent) {
  const std::string script = write("lens.lua", R"(
scene    { builtin = "cornell" }
camera   { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3, aperture = param("aperture", 0), focus_distance = 300 }
image    { width = 64, height = 64, spp = 64 }
farm     { light_paths = "partial" }
renderers { count = param("renderers", 2), lighting = lightop "direct" { light_samples = 2 } }
)");
  auto render = [&](const std::string& out, std::vector<std::string> sets) {
    std::vector<std::string> args{"run", script, "--output", path(out), "--quiet"};
    for (const auto& s : sets) args.insert(args.end(), {"--set", s});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << r.err;
    expect_no_leftovers(r);
    auto img = read_image(path(out));
    return img.ok() ? *img : Image(64, 64);
  };
  const Image pinhole = render("pinhole.exr", {});
  const Image one = render("lens1.exr", {"aperture=60", "renderers=1"});
  const Image three = render("lens3.exr", {"aperture=60", "renderers=3"});
  EXPECT_TRUE(one.pixels == three.pixels) << "images differ between 1 and 3 renderers";
  auto mean = [](const Image& img) {
    double s = 0;
    for (const RGB& p : img.pixels) s += average(p);
    return s / static_cast<double>(img.pixels.size());
  };
  // How sharp the walls' vertical edges are: the squared steps of the rows' mean profile, taken below the light
  // (rows 24-40), where averaging rows leaves little noise. A blur spreads each step over many pixels.
  auto edges = [](const Image& img) {
    std::vector<double> profile(static_cast<size_t>(img.width), 0);
    for (int y = 24; y <= 40; ++y)
      for (int x = 0; x < img.width; ++x) profile[x] += average(img.pixels[y * img.width + x]);
    double s = 0;
    for (size_t x = 1; x < profile.size(); ++x) s += (profile[x] - profile[x - 1]) * (profile[x] - profile[x - 1]);
    return s;
  };
  EXPECT_NEAR(mean(one) / mean(pinhole), 1.0, 0.03);
  EXPECT_LT(edges(one), 0.3 * edges(pinhole)) << edges(one) << " against " << edges(pinhole);
}

// shape { sphere } puts a blue ball on the box's floor: the pixels where it projects turn blue, and every renderer
// sees it (each actor builds the built-in scene with the script's shapes).
TEST_F(FarmTest, AScriptsShapeIsInThePicture) {
  const std::string head = R"(scene { builtin = "cornell" }
image { width = 64, height = 64, spp = 16 }
)";
  const std::string tail = R"(renderers { count = param("renderers", 2), lighting = lightop "pathtrace" {} }
)";
  const std::string ball = "shape \"ball\" { sphere = {400, 60, 100}, radius = 60, kd = {0.05, 0.05, 0.8} }\n";
  auto render = [&](const std::string& name, const std::string& text, std::vector<std::string> sets) {
    std::vector<std::string> args{"run", write(name + ".lua", text), "--output", path(name + ".exr"), "--quiet"};
    for (const auto& set : sets) args.insert(args.end(), {"--set", set});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << r.err;
    expect_no_leftovers(r);
    auto img = read_image(path(name + ".exr"));
    return img.ok() ? *img : Image(64, 64);
  };
  // The ball stands on the floor in front of the tall block; the camera looks down on its lit top, which
  // projects to rows 47-50, columns 17-24.
  auto centre = [](const Image& img) {
    RGB sum{};
    for (int y = 47; y <= 50; ++y)
      for (int x = 17; x <= 24; ++x) sum += img.pixels[y * 64 + x];
    return sum;
  };
  const Image with = render("with", head + ball + tail, {});
  const Image without = render("without", head + tail, {});
  const RGB a = centre(with), b = centre(without);
  // The box's light is orange (radiance 17, 12, 4): its white floor is five times as red as blue there.
  EXPECT_GT(a.z / a.x, 3 * (b.z / b.x)) << "the ball is blue: " << a.z / a.x << " against " << b.z / b.x;
  EXPECT_TRUE(render("with1", head + ball + tail, {"renderers=1"}).pixels == with.pixels);
}

// A glTF scene goes through the farm like an OBJ: examples/material_balls.lua (Blender's ball grid, the file's
// camera) shipped to every actor; the gold balls behind come out gold and the blue ones in front blue, and the
// image is the same with one renderer as with three.
TEST_F(FarmTest, AGltfSceneRendersThroughTheFarm) {
  const std::string script = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/material_balls.lua";
  if (!std::filesystem::exists(std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/gltf/balls.glb"))
    GTEST_SKIP() << "no ../shared/scenes/gltf/balls.glb";
  auto render = [&](const std::string& name, const std::string& renderers) {
    auto r = run_lightfarm({"run", script, "--output", path(name), "--quiet", "--set", "width=64", "--set", "height=36",
                            "--set", "spp=4", "--set", "renderers=" + renderers});
    EXPECT_EQ(r.status, 0) << r.err;
    expect_no_leftovers(r);
    auto img = read_image(path(name));
    return img.ok() ? *img : Image(64, 36);
  };
  const Image one = render("one.exr", "1"), three = render("three.exr", "3");
  EXPECT_TRUE(one.pixels == three.pixels) << "images differ between 1 and 3 renderers";
  // Rows 8-14 hold the back row (gold, right half rough), rows 20-30 the front row (blue).
  RGB back{}, front{};
  for (int x = 8; x < 56; ++x) {
    for (int y = 8; y <= 14; ++y) back += one.pixels[static_cast<size_t>(y * 64 + x)];
    for (int y = 20; y <= 30; ++y) front += one.pixels[static_cast<size_t>(y * 64 + x)];
  }
  EXPECT_GT(back.x, 1.5f * back.z) << "gold reflects red over blue";
  EXPECT_GT(front.z, 1.5f * front.x) << "the dielectric balls are blue";
  // Above the floor's far edge the camera sees the courtyard's warm walls: the environment travelled with the
  // shipped scene to every renderer.
  RGB sky{};
  for (int x = 0; x < 64; ++x)
    for (int y = 0; y <= 2; ++y) sky += one.pixels[static_cast<size_t>(y * 64 + x)];
  EXPECT_GT(average(sky) / (64 * 3), 0.2f) << "the camera sees the environment";
  EXPECT_GT(sky.x, sky.z) << "the courtyard's walls are warm";
}

TEST_F(FarmTest, StatsJsonCarriesPhasesAndActors) {
  auto r = render_cornell(path("c.png"), {"--stats-json", path("stats.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  std::string json = read_file(path("stats.json"));
  for (const char* key : {"\"phases_seconds\"", "\"phases_director_cpu_seconds\"", "\"render\"", "\"setup\"", "\"actors\"", "\"renderer-0\"",
                          "\"direct\"", "\"busy_seconds\"", "\"peak_queue\"", "\"bytes_in\""})
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing from " << json;
  expect_no_leftovers(r);
}

// Farm processes ask glibc's malloc for transparent huge pages (cli/main.cpp) where the kernel's THP mode is
// "madvise": the director runs itself again with the tunable and its actors inherit it. A user's own choice about
// huge pages is kept, and so are a user's other tunables. (glibc leaves only the first tunable of GLIBC_TUNABLES in
// the environment a process shows and passes on, so with a tunable of the user's, that is what the processes show.)
TEST_F(FarmTest, ActorsGetHugePagesAndKeepTheUsersTunables) {
  const bool madvise = read_file("/sys/kernel/mm/transparent_hugepage/enabled").find("[madvise]") != std::string::npos;
  auto tunables_of = [](pid_t pid) {
    const std::string env = read_file("/proc/" + std::to_string(pid) + "/environ");
    for (size_t at = 0; at < env.size();) {
      const size_t end = std::min(env.find('\0', at), env.size());
      if (env.compare(at, 15, "GLIBC_TUNABLES=") == 0) return env.substr(at + 15, end - at - 15);
      at = end + 1;
    }
    return std::string("(unset)");
  };
  const std::pair<std::string, std::string> cases[] = {
      {"", madvise ? "glibc.malloc.hugetlb=1" : "(unset)"},
      {"glibc.malloc.hugetlb=0", "glibc.malloc.hugetlb=0"},
      {"glibc.malloc.mmap_threshold=4194304", "glibc.malloc.mmap_threshold=4194304"}};
  for (const auto& [given, expected] : cases) {
    SCOPED_TRACE(given);
    std::vector<std::string> env;
    if (!given.empty()) env.push_back("GLIBC_TUNABLES=" + given);
    // Each case interrupts the same frame: without --checkpoint-every 0 the next would resume past 20 %.
    Farm farm({"run", kCornellScript, "--output", path("thp.exr"), "--set", "spp=4096", "--set", "width=64", "--set",
               "height=64", "--checkpoint-every", "0"},
              env);
    // Read the environment once the frame is under way: a process shows its whole GLIBC_TUNABLES until its
    // loader has read them (an actor caught just after exec showed both tunables of the third case).
    std::vector<pid_t> direct;
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 20%") != std::string::npos; }, 60))
        << farm.err_so_far();  // the first of the frame's 4 tiles is done
    direct = actor_pids(farm.tag(), "direct");
    ASSERT_FALSE(direct.empty()) << farm.err_so_far();
    EXPECT_EQ(tunables_of(direct[0]), expected);
    EXPECT_EQ(tunables_of(farm.pid()), expected);  // the director, after running itself again (same pid)
    ::kill(farm.pid(), SIGINT);
    auto r = farm.wait(30);
    EXPECT_EQ(r.status, 128 + SIGINT) << r.err;
    expect_no_leftovers(r);
  }
}

// A long setup step says how far it is: a cache's pre-pass against a slowed `direct` takes seconds (8 x 24 rays a
// record, set: from the image's one lit sample the cache would derive 6 x 18 and finish in about a second), and the
// log shows its quarters in order, ending at 100%; --quiet shows none.
TEST_F(FarmTest, ALongCachePrePassShowsItsProgress) {
  const std::string script = write("prepass.lua", R"(
scene { builtin = "cornell" }
image { width = 16, height = 16, spp = 1 }
local slow = multiplexer { lightop "direct" {}, replicas = 1, slowdown = {40} }
renderers { lighting = lightop "irradiance" { input = slow, placement = "area", prepass = 2000, theta = 8, phi = 24 } }
)");
  auto r = run_lightfarm({"run", script, "--output", path("p.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const size_t last = r.err.find("lightfarm: irradiance: cache pre-pass 100% (2000 of 2000)\n");
  ASSERT_NE(last, std::string::npos) << r.err;
  size_t at = 0, lines = 0;
  int previous = 0;
  for (size_t found; (found = r.err.find("irradiance: cache pre-pass ", at)) != std::string::npos; at = found + 1) {
    const int percent = std::atoi(r.err.c_str() + found + std::strlen("irradiance: cache pre-pass "));
    EXPECT_GT(percent, previous) << r.err;
    EXPECT_EQ(percent % 25, 0) << r.err;
    previous = percent;
    ++lines;
  }
  EXPECT_GE(lines, 2u) << r.err;  // the step takes seconds: at least one quarter before the end
  auto quiet = run_lightfarm({"run", script, "--output", path("q.png"), "--quiet"});
  ASSERT_EQ(quiet.status, 0) << quiet.err;
  EXPECT_EQ(quiet.err.find("pre-pass"), std::string::npos) << quiet.err;
  expect_no_leftovers(r);
}

// Stats asked for and not written is a failure, said as one: exit 1, the reason, and the image still there.
TEST_F(FarmTest, UnwritableStatsJsonFailsTheRun) {
  auto r = render_cornell(path("c.png"), {"--stats-json", path("no/such/dir/stats.json")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("lightfarm: error: could not write stats to '" + path("no/such/dir/stats.json") + "'"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::exists(path("c.png")));
  expect_no_leftovers(r);
}

// A PNG that does not fit (a full disk: a 48 KiB tmpfs this test mounts) is an error that says why, exit 1, and the
// previous image stays whole (and the writer's own success is not believed: the file is checked before it replaces
// anything).
TEST_F(FarmTest, APngOntoAFullDiskFailsAndKeepsTheOldImage) {
  const std::string disk = path("disk");
  fs::create_directories(disk);
  if (std::system(("mount -t tmpfs -o size=48k tmpfs " + disk + " 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root)";
  struct Unmount {
    std::string dir;
    ~Unmount() { std::system(("umount " + dir).c_str()); }
  } unmount{disk};
  const std::string out = disk + "/c.png";
  auto small = run_lightfarm({"run", kCornellScript, "--quiet", "--output", out, "--set", "width=16", "--set",
                              "height=16", "--set", "spp=1"});
  ASSERT_EQ(small.status, 0) << small.err;
  const std::string before = read_file(out);
  auto big = run_lightfarm({"run", kCornellScript, "--quiet", "--output", out, "--set", "width=256", "--set",
                            "height=256", "--set", "spp=1"});
  EXPECT_EQ(big.status, 1) << big.err;
  EXPECT_NE(big.err.find("lightfarm: error: cannot write '" + out + "': No space left on device"), std::string::npos)
      << big.err;
  EXPECT_EQ(read_file(out), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(disk), fs::directory_iterator{}), 1);  // no partial file left
  expect_no_leftovers(big);
}

TEST_F(FarmTest, LuaSyntaxErrorNamesFileAndLine) {
  auto script = write("bad.lua", "scene { builtin = \"cornell\" }\nimage { width = }\n");
  auto r = run_lightfarm({"run", script, "--output", path("x.png")});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(script + ":2:"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("x.png")));
  expect_no_leftovers(r);
}

TEST_F(FarmTest, UnknownLightOpKindIsOneClearMessage) {
  auto script = write("bad.lua", "scene { builtin = \"cornell\" }\nlocal p = lightop \"photonz\" {}\n");
  auto r = run_lightfarm({"run", script, "--output", path("x.png")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "lightfarm: error: " + script + ":2: unknown LightOp kind 'photonz' (known kinds: " + lightop_kind_list() + ")\n");
  EXPECT_EQ(files_in_dir(), 1u);
  expect_no_leftovers(r);
}

TEST_F(FarmTest, MissingSceneFileIsOneClearMessage) {
  auto script = write("bad.lua", "\nscene { file = \"nowhere/room.obj\" }\n");
  auto r = run_lightfarm({"run", script, "--output", path("x.png")});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "lightfarm: error: " + script + ":2: scene file '" + path("nowhere/room.obj") + "' not found\n");
  expect_no_leftovers(r);
}

// A bad command line exits 2 (README): an output that cannot be written is one, found before launching.
TEST_F(FarmTest, UnwritableOutputStopsBeforeLaunching) {
  auto r = render_cornell("/proc/lightfarm-cannot-write-here.png");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("lightfarm: error: output '/proc/lightfarm-cannot-write-here.png': directory '/proc' is not writable"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "expected one message, got:\n" << r.err;
  auto missing_dir = render_cornell(path("no/such/dir/x.png"));
  EXPECT_EQ(missing_dir.status, 2);
  EXPECT_NE(missing_dir.err.find("does not exist"), std::string::npos) << missing_dir.err;
  auto device = render_cornell("/dev/full");
  EXPECT_EQ(device.status, 2);
  EXPECT_EQ(device.err, "lightfarm: error: output '/dev/full': unsupported image format '' (use .exr, .png or .tif)\n");
  expect_no_leftovers(r);
  expect_no_leftovers(missing_dir);
  expect_no_leftovers(device);
}

// The farm's only `direct` (no replica to take over) dying at start-up stops it (renderers and pool replicas are
// recovered: FailureTest.RenderersAndReplicasLostAtStartUpAreLeftOut).
TEST_F(FarmTest, ActorDyingDuringStartUpStopsTheFarmCleanly) {
  auto r = run_lightfarm({"run", kCornellScript, "--output", path("x.png"), "--set", "width=32", "--set", "height=32"},
                         {"LIGHTFARM_FAULT=crash-at-start:direct"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("lightfarm: error: actor 'direct' (pid "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("was killed by signal 6 (Aborted) during start-up"), std::string::npos) << r.err;
  EXPECT_EQ(files_in_dir(), 0u) << "no image, not even a partial one";
  expect_no_leftovers(r);
}

// A render big enough to interrupt: 512x512 at 64 spp takes seconds.
std::vector<std::string> long_render(const std::string& output) {
  return {"run", kCornellScript, "--output", output, "--set", "spp=64", "--set", "light_samples=4"};
}

TEST_F(FarmTest, SigintAndSigtermStopEverythingAndWriteNoImage) {
  for (int sig : {SIGINT, SIGTERM}) {
    Farm farm(long_render(path("x.png")));
    ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60))
        << farm.err_so_far();
    ::kill(farm.pid(), sig);
    auto r = farm.wait(30);
    EXPECT_EQ(r.status, 128 + sig) << r.err;
    EXPECT_NE(r.err.find("interrupted by signal " + std::to_string(sig)), std::string::npos) << r.err;
    // No image; the tiles done so far wait beside where it goes, for the next run of the frame.
    EXPECT_EQ(files_in_dir(), 1u);
    EXPECT_TRUE(fs::exists(path("x.png.lfresume")));
    expect_no_leftovers(r);
  }
}

TEST_F(FarmTest, KilledDirectorTakesItsActorsWithIt) {
  Farm farm(long_render(path("x.png")));
  ASSERT_TRUE(Farm::eventually([&] { return !actor_pids(farm.tag(), "direct").empty(); }, 30));
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60));
  ::kill(farm.pid(), SIGKILL);
  auto r = farm.wait(10);
  EXPECT_EQ(r.status, 128 + SIGKILL);
  expect_no_leftovers(r);
}

TEST_F(FarmTest, LightOpKilledMidFrameStopsTheFarmNamingIt) {
  Farm farm(long_render(path("x.png")));
  ASSERT_TRUE(Farm::eventually([&] { return farm.err_so_far().find("render 10%") != std::string::npos; }, 60));
  auto pids = actor_pids(farm.tag(), "direct");
  ASSERT_EQ(pids.size(), 1u);
  ::kill(pids[0], SIGKILL);
  auto r = farm.wait(30);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("actor 'direct' (pid " + std::to_string(pids[0]) + ") was killed by signal 9 (Killed) during render"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(files_in_dir(), 1u) << "no image; only the frame's checkpoint";
  EXPECT_TRUE(fs::exists(path("x.png.lfresume")));
  expect_no_leftovers(r);
}

// A frame whose director was SIGKILLed mid-render resumes from the checkpoint beside its output (the tiles done by
// then, written every 0.1 s here): the next run renders only the rest, says how many tiles were done, writes the
// uninterrupted frame's image bit for bit and removes the checkpoint. Another frame (a different spp) does not
// take it, nor does a run with --restart.
TEST_F(FarmTest, AKilledFrameResumesToTheSameImage) {
  auto run_args = [&](const std::string& out, const std::string& spp, std::vector<std::string> extra) {
    std::vector<std::string> a{"run", kCornellScript, "--output", path(out), "--set", "width=96", "--set", "height=96",
                               "--set", "spp=" + spp, "--set", "light_samples=4", "--checkpoint-every", "0.1"};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  const auto reference = run_lightfarm(run_args("ref.png", "256", {"--checkpoint-every", "0"}));
  ASSERT_EQ(reference.status, 0) << reference.err;
  Farm farm(run_args("x.png", "256", {}));
  ASSERT_TRUE(Farm::eventually([&] { return fs::exists(path("x.png.lfresume")); }, 60)) << farm.err_so_far();
  ::kill(farm.pid(), SIGKILL);
  const auto killed = farm.wait(10);
  EXPECT_EQ(killed.status, 128 + SIGKILL);
  expect_no_leftovers(killed);
  ASSERT_FALSE(fs::exists(path("x.png"))) << "the frame ended before the kill";
  fs::copy_file(path("x.png.lfresume"), path("kept.lfresume"));

  const auto other = run_lightfarm(run_args("x.png", "128", {}));
  EXPECT_EQ(other.status, 0) << other.err;
  EXPECT_NE(other.err.find("x.png.lfresume holds another frame's tiles"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("x.png.lfresume")));
  fs::copy_file(path("kept.lfresume"), path("x.png.lfresume"));
  const auto restarted = run_lightfarm(run_args("x.png", "256", {"--restart"}));
  EXPECT_EQ(restarted.status, 0) << restarted.err;
  EXPECT_EQ(restarted.err.find("resumed"), std::string::npos) << restarted.err;
  EXPECT_FALSE(fs::exists(path("x.png.lfresume")));

  fs::copy_file(path("kept.lfresume"), path("x.png.lfresume"));
  const auto resumed = run_lightfarm(run_args("x.png", "256", {}));
  ASSERT_EQ(resumed.status, 0) << resumed.err;
  const auto at = resumed.err.find("resumed from " + path("x.png.lfresume") + ": ");
  ASSERT_NE(at, std::string::npos) << resumed.err;
  int done = 0, total = 0;
  ASSERT_EQ(std::sscanf(resumed.err.c_str() + at + 13 + path("x.png.lfresume").size(), ": %d of %d tiles", &done, &total), 2)
      << resumed.err;
  EXPECT_GT(done, 0);
  EXPECT_LT(done, total);
  auto a = read_image(path("ref.png")), b = read_image(path("x.png"));
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->pixels == b->pixels) << "the resumed frame differs from the uninterrupted one";
  EXPECT_FALSE(fs::exists(path("x.png.lfresume")));
  expect_no_leftovers(resumed);
}

// image { time_limit }: passes of spp samples while the time lasts, each pass taking each pixel's next spp samples
// (through a pool of lean inputs too, which rebuild the samples' keys from the tile), so that N passes are the
// image of N x spp samples (and N x edge_spp at a light's outline; up to the order of the sums); a limit no pass
// fits in still gives one whole pass.
TEST_F(FarmTest, ATimeLimitedFrameIsTheMeanOfWholePassesOfTheNextSamples) {
  const std::string script = write("limited.lua", R"(
scene { builtin = "cornell" }
-- Adaptive sampling, off in a time-limited frame, is turned off in the plain ones compared with it.
local limit = param("time_limit", 0)
image { width = 48, height = 48, spp = param("spp", 2), tile = 16, time_limit = limit,
        edge_spp = param("edge_spp", 32), adaptive_spp = limit == 0 and 0 or nil }
farm { light_paths = "partial" }
renderers { count = 2, lighting = multiplexer { lightop "direct" {}, replicas = 2 } }
)");
  auto render = [&](const std::string& out, std::vector<std::string> sets) {
    std::vector<std::string> args{"run", script, "--output", path(out)};
    for (auto& s : sets) args.insert(args.end(), {"--set", s});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << r.err;
    expect_no_leftovers(r);
    return r;
  };
  const auto limited = render("limited.exr", {"time_limit=1.5"});
  int passes = 0, samples = 0;
  const size_t at = limited.err.find("limited.exr: ");
  ASSERT_NE(at, std::string::npos) << limited.err;
  ASSERT_EQ(std::sscanf(limited.err.c_str() + at, "limited.exr: %d pass%*[es] of 2 samples a pixel (%d)", &passes, &samples), 2)
      << limited.err;
  EXPECT_GE(passes, 2) << "a pass of this frame takes a few hundredths of a second";
  EXPECT_EQ(samples, 2 * passes);
  // The file says what made it.
  auto notes = read_image_notes(path("limited.exr"));
  ASSERT_TRUE(notes.ok()) << notes.error().message;
  EXPECT_EQ(*notes, (ImageNotes{{"lightfarm:passes", std::to_string(passes)}, {"lightfarm:samples", std::to_string(samples)}}));
  // Each pass also took 30 more seen samples at the light's outline, the next 30 of each such pixel's own.
  render("plain.exr", {"spp=" + std::to_string(samples), "edge_spp=" + std::to_string(16 * samples)});
  auto a = read_image(path("limited.exr")), b = read_image(path("plain.exr"));
  ASSERT_TRUE(a.ok() && b.ok());
  float worst = 0;
  for (size_t i = 0; i < a->pixels.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::fabs(a->pixels[i][c] - b->pixels[i][c]) / std::max(1e-3f, b->pixels[i][c]));
  EXPECT_LT(worst, 1e-4f) << passes << " passes of 2 samples are not the image of " << samples << " samples";

  const auto one = render("one.exr", {"time_limit=0.000001"});
  EXPECT_NE(one.err.find("one.exr: 1 pass of 2 samples a pixel (2)"), std::string::npos) << one.err;
  render("two.exr", {});
  auto c = read_image(path("one.exr")), d = read_image(path("two.exr"));
  ASSERT_TRUE(c.ok() && d.ok());
  EXPECT_TRUE(c->pixels == d->pixels) << "one pass is the image of spp samples";
}

TEST_F(FarmTest, GraphPrintsDotAndLaunchesNothing) {
  auto r = run_lightfarm({"graph", kCornellScript});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.rfind("digraph farm {", 0), 0u);
  EXPECT_NE(r.out.find("\"direct\" -> \"renderers\""), std::string::npos);
  expect_no_leftovers(r);
}

TEST_F(FarmTest, CommandLineBasics) {
  auto help = run_lightfarm({"--help"});
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("lightfarm run SCRIPT"), std::string::npos);
  for (const char* command : {"run", "check-actor", "actor", "scene"}) {
    auto command_help = run_lightfarm({command, "--help"});
    EXPECT_EQ(command_help.status, 0) << command << ": " << command_help.err;
    EXPECT_NE(command_help.out.find("lightfarm check-actor [--kind KIND]"), std::string::npos) << command;
  }
  auto version = run_lightfarm({"--version"});
  EXPECT_EQ(version.status, 0);
  EXPECT_NE(version.out.find("protocol 1"), std::string::npos);
  auto bad = run_lightfarm({"frobnicate"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("unknown command 'frobnicate'"), std::string::npos);
  auto bad_set = run_lightfarm({"run", kCornellScript, "--set", "spp"});
  EXPECT_EQ(bad_set.status, 2);
  EXPECT_NE(bad_set.err.find("--set needs NAME=VALUE, got 'spp'"), std::string::npos) << bad_set.err;
  auto inline_set = run_lightfarm({"graph", kCornellScript, "--set=renderers=3"});
  EXPECT_EQ(inline_set.status, 0) << inline_set.err;
  EXPECT_NE(inline_set.out.find("renderer × 3"), std::string::npos);
  auto unknown_actor = run_lightfarm({"actor", "--kind", "teapot", "--name", "t", "--director", "tcp://127.0.0.1:9"});
  EXPECT_EQ(unknown_actor.status, 2);
  EXPECT_NE(unknown_actor.err.find("unknown actor kind 'teapot' (known kinds: renderer, multiplexer, radiosity_node, geometry, " + lightop_kind_list() + ")"), std::string::npos);
}

}  // namespace
}  // namespace lf::test
