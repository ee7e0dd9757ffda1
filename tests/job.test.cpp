// Render jobs: a turntable of frames over one farm. Frames are the same on any number of renderers; with
// per-frame caches each equals the single-frame render of its camera, bit for bit; only the setup that depends on
// the view is redone, or, for a cache carried over the frames, extended; a job whose director is SIGKILLed resumes
// from its record to the same frames (restoring the cache its record kept, or replaying the views it skips); runs sharing the record keep each other's
// frames; a preview shows a frame while it renders.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <optional>
#include <regex>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

// cornell_glass turned about its centre; a network with view-dependent setups (the learned lights of a pool of two
// `direct`s, which share their learning, and the camera-placed irradiance cache, which both carry what they learned
// over the frames, or with --set reuse=0 learn their own each frame) and view-independent ones (a pool of two photon maps, an area-placed cache over the path tracer).
// --set frame=K renders frame K's camera as a farm of one frame, without frames { }; --set paths_learned=1 makes the
// path tracer learn its lights where the camera looks, so the kept area-placed cache asked an op that
// saw the first frame's camera.
constexpr const char* kTurntable = R"(
scene  { builtin = "cornell_glass" }
image  { width = 40, height = 40, spp = param("spp", 4), tile = param("tile", 32), output = param("out", "turn.####.png") }
local function view(f)
  local a = (f - 1) * 0.05
  return { eye = {278 + 1073 * math.sin(a), 273, 273 - 1073 * math.cos(a)}, at = {278, 273, 273}, fov = 39.3 }
end
local single = param("frame", 0)
-- --set lit_from=K: from frame K on the light is brighter and whiter (frames { materials }; with --set frame=N,
-- material "light" { } says the same for a farm of frame N alone); --set dark_from=K turns it off from frame K.
-- --set glossy_from=K: from frame K on the white walls have a glossy lobe as well.
local lit_from, dark_from, warm_from = param("lit_from", 0), param("dark_from", 0), param("warm_from", 0)  -- warm: redder
local glossy_from = param("glossy_from", 0)
local function lamp(f)
  if dark_from > 0 and f >= dark_from then return { light = { emission = {0, 0, 0} } } elseif warm_from > 0 and f >= warm_from then return { light = { emission = {40, 20, 10} } } end
  if glossy_from > 0 and f >= glossy_from then
    return { white = { type = "glossy", kd = {0.55, 0.54, 0.52}, ks = {0.3, 0.3, 0.3}, ns = 20 } }
  end
  return lit_from > 0 and f >= lit_from and { light = { emission = {30, 27, 20} } } or {}
end
if single > 0 then
  camera(view(single))
  for name, change in pairs(lamp(single)) do material(name)(change) end
else
  frames { first = 1, last = param("last", 12), camera = view, materials = lamp, in_flight = param("in_flight", 1) == 1 }
end
local direct   = multiplexer { lightop "direct" { light_sampling = "learned", light_samples = 2, reuse = param("reuse", 1) == 1 },
                               replicas = 2 }
local caustics = multiplexer { lightop "photonmap" { photons = 20000, k = 50 }, replicas = 2 }
local paths    = lightop "pathtrace" { name = "paths", light_sampling = param("paths_learned", 0) == 1 and "learned" or "tree" }
local bounce1  = lightop "irradiance" { input = paths, name = "bounce1", placement = "area", prepass = 3000 }
local glossy1  = lightop "glossy" { input = paths, name = "glossy1" }
local through  = lightop "specular" { input = lightop "combine" { inputs = { direct, bounce1, glossy1 }, name = "seen" },
                                      emitters = false, name = "through" }
local lit1     = lightop "combine" { inputs = { direct, bounce1, glossy1, through }, name = "lit1" }
local indirect = lightop "irradiance" { input = lit1, name = "indirect", reuse = param("reuse", 1) == 1 }
local glossy   = lightop "glossy" { input = lit1, name = "glossy" }
local landing  = lightop "combine" { inputs = { direct, caustics, indirect, glossy }, name = "landing" }
local specular = lightop "specular" { input = landing }
renderers { count = param("renderers", 1),
            lighting = lightop "combine" { inputs = { direct, specular, caustics, indirect, glossy } } }
)";

// A 10-wide ground with a unit block on it: the sky tests' yard, whose shadow shows where the light comes from.
constexpr const char* kYard =
    "v -5 0 -5\nv 5 0 -5\nv 5 0 5\nv -5 0 5\nf 1 4 3 2\n"
    "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\n"
    "v -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n"
    "f 9 10 11 12\nf 5 6 7 8\nf 5 9 10 6\nf 6 10 11 7\nf 7 11 12 8\nf 8 12 9 5\n";

class JobTest : public FarmFixture {
 protected:
  std::string script;
  void SetUp() override {
    FarmFixture::SetUp();
    script = write("turn.lua", kTurntable);
  }
  RunResult run(const std::string& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> a{"run", script, "--set", "out=" + path(out), "--checkpoint-every", "0"};
    a.insert(a.end(), extra.begin(), extra.end());
    return run_lightfarm(a);
  }
  // `script_file` run quietly with `out` as its output parameter.
  RunResult run_quiet(const std::string& script_file, const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> a{"run", script_file, "--set", "out=" + path(out), "--quiet"};
    a.insert(a.end(), extra.begin(), extra.end());
    return run_lightfarm(a);
  }
  // Frame n of outputs "NAME.####.exr".
  std::string frame(const std::string& name, int n) const {
    char file[64];
    std::snprintf(file, sizeof file, "%s.%04d.exr", name.c_str(), n);
    return path(file);
  }
  static bool same_pixels(const std::string& a, const std::string& b) {
    auto x = read_image(a), y = read_image(b);
    return x.ok() && y.ok() && x->width == y->width && x->pixels == y->pixels;
  }
  // `script_file` as a job of frames 1..last to NAME.####.exr, then each frame alone (--set frame=N): each job frame
  // must equal its farm alone, and the first and last differ in a quarter of their pixels (`what` did change).
  void expect_frames_are_their_farms_alone(const std::string& script_file, const std::string& name, int last,
                                           const char* what) {
    const auto job = run_quiet(script_file, name + ".####.exr", {});
    ASSERT_EQ(job.status, 0) << job.err;
    expect_no_leftovers(job);
    for (int n = 1; n <= last; ++n) {
      const auto alone = run_quiet(script_file, "alone.exr", {"--set", "frame=" + std::to_string(n)});
      ASSERT_EQ(alone.status, 0) << alone.err;
      EXPECT_TRUE(same_pixels(frame(name, n), path("alone.exr"))) << "frame " << n << " is not its farm alone";
    }
    auto a = read_image(frame(name, 1)), b = read_image(frame(name, last));
    ASSERT_TRUE(a.ok() && b.ok());
    size_t differ = 0;
    for (size_t i = 0; i < a->pixels.size(); ++i) differ += !(a->pixels[i] == b->pixels[i]);
    EXPECT_GT(differ, a->pixels.size() / 4) << what << " did not change";
  }
  // A LightOp's figure `key` from the end-of-run table ("NAME   a 1, b 2, ..."); -1 if it is not there.
  static int figure(const std::string& err, const std::string& actor, const std::string& key) {
    std::smatch m;
    if (!std::regex_search(err, m, std::regex("\n" + actor + " +[^\n]*\\b" + key + " ([0-9]+)"))) return -1;
    return std::stoi(m[1]);
  }
};

TEST_F(JobTest, FramesEqualSingleFrameRendersOnAnyLayoutAndRedoOnlyViewDependentSetup) {
  // The camera-placed cache made anew each frame: every setup a frame uses is its own view's or the scene's.
  const auto one = run("a.####.exr", {"--stats-json", path("a.json"), "--set", "reuse=0"});
  ASSERT_EQ(one.status, 0) << one.err;
  expect_no_leftovers(one);
  EXPECT_NE(one.out.find("wrote 12 frames: " + frame("a", 1) + " ... " + frame("a", 12)),
            std::string::npos) << one.out;
  const auto three = run("b.####.exr", {"--set", "renderers=3", "--set", "reuse=0"});
  ASSERT_EQ(three.status, 0) << three.err;
  for (int n = 1; n <= 12; ++n)
    EXPECT_TRUE(same_pixels(frame("a", n), frame("b", n))) << "frame " << n << ": 1 and 3 renderers differ";
  // Frames after the first, whose view-dependent setups were redone for them, equal farms of that frame alone.
  for (int n : {1, 6, 12}) {
    const auto single = run("single.exr", {"--set", "frame=" + std::to_string(n)});
    ASSERT_EQ(single.status, 0) << single.err;
    EXPECT_TRUE(same_pixels(frame("a", n), path("single.exr"))) << "frame " << n << " differs from its farm alone";
  }
  EXPECT_FALSE(same_pixels(frame("a", 1), frame("a", 2))) << "the camera did not move";
  // Setup keys: what depends on the camera was set up once a frame, the rest once for the job.
  EXPECT_EQ(figure(one.err, "direct.0", "setups"), 12) << "learned lights follow the view\n" << one.err;
  EXPECT_EQ(figure(one.err, "indirect", "setups"), 12) << "a camera-placed cache follows the view";
  EXPECT_EQ(figure(one.err, "paths", "setups"), 1);
  EXPECT_EQ(figure(one.err, "bounce1", "setups"), 1) << "an area-placed cache is the scene's";
  EXPECT_EQ(figure(one.err, "photonmap.0", "setups"), 1) << "photons do not depend on the camera";
  EXPECT_EQ(figure(one.err, "photonmap.1", "setups"), 1);
  EXPECT_EQ(figure(one.err, "glossy", "setups"), 1);
  EXPECT_EQ(figure(one.err, "direct.1", "frames"), 12);
  // The cache carried over the frames: records added where each new view needs them, the same on any layout.
  const auto carried = run("c.####.exr");
  ASSERT_EQ(carried.status, 0) << carried.err;
  const auto carried3 = run("d.####.exr", {"--set", "renderers=3"});
  ASSERT_EQ(carried3.status, 0) << carried3.err;
  for (int n = 1; n <= 12; ++n)
    EXPECT_TRUE(same_pixels(frame("c", n), frame("d", n))) << "frame " << n << ": 1 and 3 renderers differ";
  EXPECT_TRUE(same_pixels(frame("a", 1), frame("c", 1))) << "the first frame has only its own view's records";
  EXPECT_FALSE(same_pixels(frame("a", 6), frame("c", 6))) << "frame 6 used no record of the frames before it";
  EXPECT_EQ(figure(carried.err, "indirect", "setups"), 1) << carried.err;
  EXPECT_EQ(figure(carried.err, "indirect", "extended"), 11);
  EXPECT_EQ(figure(carried.err, "direct.1", "setups"), 1) << "learned lights are carried too";
  EXPECT_EQ(figure(carried.err, "direct.0", "extended"), 11);
  const std::string stats = read_file(path("a.json"));
  EXPECT_NE(stats.find("\"job\""), std::string::npos);
  size_t frames = 0;
  for (size_t at = stats.find("\"frame\":"); at != std::string::npos; at = stats.find("\"frame\":", at + 1)) ++frames;
  EXPECT_EQ(frames, 12u) << stats;
}

// Frames in flight: each frame begins while the last one's final tiles render, every actor answering both views at
// once (the carried cache and learned lights as they were for the frame before). The frames are those of the job
// rendered one frame at a time, bit for bit.
TEST_F(JobTest, FramesInFlightEqualFramesRenderedOneAtATime) {
  // The path tracer learns its lights too (paths_learned): an op whose copy must not share what the original holds.
  const auto flying = run("f.####.exr", {"--set", "renderers=3", "--set", "paths_learned=1", "--stats-json", path("f.json")});
  ASSERT_EQ(flying.status, 0) << flying.err;
  expect_no_leftovers(flying);
  const auto one = run("o.####.exr", {"--set", "in_flight=0", "--set", "paths_learned=1", "--stats-json", path("o.json")});
  ASSERT_EQ(one.status, 0) << one.err;
  for (int n = 1; n <= 12; ++n)
    EXPECT_TRUE(same_pixels(frame("f", n), frame("o", n))) << "frame " << n << ": in flight and one at a time differ";
  EXPECT_FALSE(same_pixels(frame("f", 1), frame("f", 2))) << "the camera did not move";
  const std::regex begun("\"begun_in_flight\": *([0-9]+)");
  std::smatch m;
  const std::string flying_stats = read_file(path("f.json")), one_stats = read_file(path("o.json"));
  ASSERT_TRUE(std::regex_search(flying_stats, m, begun)) << flying_stats;
  EXPECT_EQ(m[1], "11") << "every frame after the first begins beside the one before";
  ASSERT_TRUE(std::regex_search(one_stats, m, begun)) << one_stats;
  EXPECT_EQ(m[1], "0");
}

TEST_F(JobTest, AKilledJobResumesFromItsRecordToTheSameFrames) {
  const auto reference = run("ref.####.exr", {"--set", "last=8", "--set", "paths_learned=1"});
  ASSERT_EQ(reference.status, 0) << reference.err;
  Farm farm({"run", script, "--set", "out=" + path("x.####.exr"), "--set", "last=8", "--set", "paths_learned=1", "--checkpoint-every", "0"});
  // Frame 5 is done once the record lists it: its image is written a moment before, and a kill between the two
  // leaves it to render again.
  ASSERT_TRUE(Farm::eventually([&] { return read_file(path("x.lfjob/frames")).find("\n5 ") != std::string::npos; }, 120))
      << farm.err_so_far();
  ::kill(farm.pid(), SIGKILL);
  const auto killed = farm.wait(10);
  EXPECT_EQ(killed.status, 128 + SIGKILL);
  expect_no_leftovers(killed);
  ASSERT_TRUE(fs::exists(path("x.lfjob/frames")));
  // A frame whose image was overwritten since it was recorded is not done.
  fs::copy_file(frame("ref", 1), frame("x", 2), fs::copy_options::overwrite_existing);

  const auto resumed = run("x.####.exr", {"--set", "last=8", "--set", "paths_learned=1"});
  ASSERT_EQ(resumed.status, 0) << resumed.err;
  expect_no_leftovers(resumed);
  int done = 0, total = 0;
  const auto at = resumed.err.find(" of the job's ");
  ASSERT_NE(at, std::string::npos) << resumed.err;
  ASSERT_EQ(std::sscanf(resumed.err.c_str() + resumed.err.rfind(' ', at - 1) + 1, "%d of the job's %d", &done, &total), 2);
  EXPECT_GE(done, 4) << "frames 1, 3, 4, 5 were done and unchanged";
  // The cache carried over the frames: the killed run kept it after each view, so the resumed one restores it
  // (where it stood after frame 5, or after frame 6 if the killed run had extended it that far) instead of replaying
  // the views it skips.
  EXPECT_TRUE(std::regex_search(resumed.err, std::regex("restored the setups carried over the views to frame [56] "))) << resumed.err;
  // The pool's replicas hold the same learned lights: the first kept them for both.
  EXPECT_TRUE(fs::exists(path("x.lfjob/setups/direct.0.5.setup")));
  EXPECT_TRUE(fs::exists(path("x.lfjob/setups/indirect.5.setup")));
  EXPECT_FALSE(fs::exists(path("x.lfjob/setups/direct.1.5.setup")));
  EXPECT_EQ(resumed.err.find("replaying the views"), std::string::npos) << resumed.err;
  EXPECT_LT(done, 8);
  EXPECT_EQ(total, 8);
  EXPECT_NE(resumed.err.find("frame 2 written"), std::string::npos) << "the overwritten frame renders again";
  for (int n = 1; n <= 8; ++n)
    EXPECT_TRUE(same_pixels(frame("ref", n), frame("x", n))) << "frame " << n << " differs after the resume";

  // Done: nothing launches; --restart renders what --frames asks; another image (spp) renders its frames again.
  const auto again = run("x.####.exr", {"--set", "last=8", "--set", "paths_learned=1"});
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.out.find("nothing to render: every frame of the job is done"), std::string::npos) << again.out;
  const auto only = run("x.####.exr", {"--set", "last=8", "--set", "paths_learned=1", "--frames", "3-4", "--restart"});
  EXPECT_EQ(only.status, 0) << only.err;
  EXPECT_NE(only.out.find("wrote 2 frames"), std::string::npos) << only.out;
  EXPECT_NE(only.err.find("replaying the views of the 1 frames before frame 3"), std::string::npos) << only.err;
  for (int n : {3, 4})
    EXPECT_TRUE(same_pixels(frame("ref", n), frame("x", n))) << "frame " << n << " of --frames 3-4 is not the job's";
  const auto other = run("x.####.exr", {"--set", "last=8", "--set", "paths_learned=1", "--set", "spp=2", "--frames", "1"});
  EXPECT_EQ(other.status, 0) << other.err;
  EXPECT_EQ(other.err.find(" of the job's "), std::string::npos) << "frame 1 at 2 spp is not the frame recorded";
  EXPECT_NE(other.err.find("frame 1 written"), std::string::npos) << other.err;

  // Two runs of the job at once in one folder, each with its --frames (a Slurm array's tasks): every frame is
  // recorded, and each equals the uninterrupted job's.
  auto task = [&](const std::string& frames) {
    return std::make_unique<Farm>(std::vector<std::string>{"run", script, "--set", "out=" + path("y.####.exr"), "--set", "last=8",
                                                           "--set", "paths_learned=1", "--checkpoint-every", "0", "--frames", frames});
  };
  auto first = task("1-4"), second = task("5-8");
  const auto first_done = first->wait(300), second_done = second->wait(300);
  ASSERT_EQ(first_done.status, 0) << first_done.err;
  ASSERT_EQ(second_done.status, 0) << second_done.err;
  expect_no_leftovers(first_done);
  expect_no_leftovers(second_done);
  for (int n = 1; n <= 8; ++n)
    EXPECT_TRUE(same_pixels(frame("ref", n), frame("y", n))) << "frame " << n << " of a task differs from the job's";
  const auto whole = run("y.####.exr", {"--set", "last=8", "--set", "paths_learned=1"});
  EXPECT_NE(whole.err.find("8 of the job's 8 frames are done"), std::string::npos) << whole.err;
}

// frames { materials }: where a frame changes materials every setup starts anew, seen from that frame (it equals
// a farm of that frame alone whose script makes the same changes), carried setups are carried on from there, and a
// run that skips to a later frame takes the change's frame first: resumed or not, every frame is the job's.
TEST_F(JobTest, MaterialsChangedByAFrameSetEverythingUpAnewFromThatFrame) {
  const std::vector<std::string> job{"--set", "last=5", "--set", "lit_from=3"};
  auto with = [&](std::vector<std::string> more) {
    more.insert(more.begin(), job.begin(), job.end());
    return more;
  };
  const auto whole = run("m.####.exr", with({}));
  ASSERT_EQ(whole.status, 0) << whole.err;
  expect_no_leftovers(whole);
  for (const char* op : {"photonmap.0", "paths", "bounce1", "glossy", "indirect", "direct.0"})
    EXPECT_EQ(figure(whole.err, op, "setups"), 2) << op << ": set up for frame 1 and again for frame 3\n" << whole.err;
  EXPECT_EQ(figure(whole.err, "indirect", "extended"), 3) << "carried to frames 2, 4 and 5";
  auto mean = [](const std::string& file) {
    double sum = 0;
    auto img = read_image(file);
    for (const RGB& p : img->pixels) sum += p.x + p.y + p.z;
    return sum / static_cast<double>(img->pixels.size());
  };
  EXPECT_GT(mean(frame("m", 3)), 1.5 * mean(frame("m", 2))) << "the light did not brighten at frame 3";

  const auto alone = run("alone.exr", {"--set", "frame=3", "--set", "lit_from=3"});
  ASSERT_EQ(alone.status, 0) << alone.err;
  EXPECT_TRUE(same_pixels(frame("m", 3), path("alone.exr"))) << "frame 3 is not the farm of frame 3 alone";

  // Frame 5 alone: the run takes frame 3 first (no render), then replays frame 4.
  const auto skipped = run("s.####.exr", with({"--frames", "5"}));
  ASSERT_EQ(skipped.status, 0) << skipped.err;
  EXPECT_NE(skipped.err.find("taking frame 3 first, where the materials change"), std::string::npos) << skipped.err;
  EXPECT_TRUE(same_pixels(frame("m", 5), frame("s", 5))) << "frame 5 of --frames 5 is not the job's";
  // Frames 1-4, then 5 in a run of its own: frame 3 first, then the setups kept after frame 4 restored.
  ASSERT_EQ(run("r.####.exr", with({"--frames", "1-4"})).status, 0);
  const auto resumed = run("r.####.exr", with({"--frames", "5"}));
  ASSERT_EQ(resumed.status, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("restored the setups carried over the views to frame 4 "), std::string::npos) << resumed.err;
  expect_no_leftovers(resumed);
  for (int n = 1; n <= 5; ++n)
    EXPECT_TRUE(same_pixels(frame("m", n), frame("r", n))) << "frame " << n << " differs from the job run in one go";

  // The job's first frame changes materials (set up with them, CONFIG frame_materials), and the next changes them
  // again: each frame equals its farm alone.
  const auto twice = run("w.####.exr", {"--set", "last=2", "--set", "lit_from=1", "--set", "warm_from=2"});
  ASSERT_EQ(twice.status, 0) << twice.err;
  for (int n : {1, 2}) {
    const auto single = run("w_alone.exr", {"--set", "frame=" + std::to_string(n), "--set", "lit_from=1", "--set", "warm_from=2"});
    ASSERT_EQ(single.status, 0) << single.err;
    EXPECT_TRUE(same_pixels(frame("w", n), path("w_alone.exr"))) << "frame " << n << " is not its farm alone";
  }
}

// Each op is asked only about the points its answer reaches, by the lobes of the frame's materials: where a frame
// gives the walls a glossy lobe, the glossy ops, asked about no point before, are asked about the walls' from that
// frame on, and the frame equals its farm alone (whose shipped walls are glossy). Asked by the shipped scene's
// materials, the job's frame would lose its walls' glossy light.
TEST_F(JobTest, AFrameThatGivesAMaterialALobeAsksTheOpsOfThatLobe) {
  const auto job = run("g.####.exr", {"--set", "last=3", "--set", "glossy_from=3"});
  ASSERT_EQ(job.status, 0) << job.err;
  expect_no_leftovers(job);
  EXPECT_GT(figure(job.err, "glossy", "glossy_points"), 0) << job.err;
  const auto before = run("b.####.exr", {"--set", "last=2", "--set", "glossy_from=3"});
  ASSERT_EQ(before.status, 0) << before.err;
  EXPECT_EQ(figure(before.err, "glossy", "glossy_points"), 0) << "no glossy material in frames 1 and 2\n" << before.err;
  const auto alone = run("alone.exr", {"--set", "frame=3", "--set", "glossy_from=3"});
  ASSERT_EQ(alone.status, 0) << alone.err;
  EXPECT_TRUE(same_pixels(frame("g", 3), path("alone.exr"))) << "frame 3 is not the farm of frame 3 alone";
  EXPECT_TRUE(same_pixels(frame("g", 2), frame("b", 2))) << "frame 2 changed with frame 3's materials";
}

// frames { sun }: the sun moves from frame to frame (here across the sky over a block on the ground), and each
// frame equals the farm of that frame alone whose script declares the sun where the job's frame puts it. A job
// that moves a sun the script never declared is refused before launch, at the frames line.
TEST_F(JobTest, TheSunMovesFromFrameToFrame) {
  write("yard.obj", kYard);
  const std::string sun_script = write("sun.lua", R"(
scene  { file = "yard.obj" }
camera { eye = {0, 4, 7}, at = {0, 0.3, 0}, fov = 50 }
image  { width = 32, height = 32, spp = 2, tile = 16, output = param("out", "sun.####.exr") }
farm   { light_paths = "partial" }  -- direct light alone
local function sun_at(f) return { direction = {f - 2, 1.5, 0.5}, irradiance = {3, 3, 3} } end
local single = param("frame", 0)
if param("declared", true) then sun(sun_at(single > 0 and single or 1)) else light { point = {0, 5, 0}, intensity = {20, 20, 20} } end
if single == 0 then frames { first = 1, last = 3, sun = sun_at } end
renderers { count = 2, lighting = lightop "direct" {} }
)");
  expect_frames_are_their_farms_alone(sun_script, "sun", 3, "the block's shadow");
  auto run_sun = [&](const std::string& out, std::vector<std::string> extra) { return run_quiet(sun_script, out, extra); };

  const auto undeclared = run_sun("u.####.exr", {"--set", "declared=false"});
  EXPECT_EQ(undeclared.status, 2) << undeclared.err;
  EXPECT_NE(undeclared.err.find("sun.lua:9: frames: the sun changes from frame to frame, but the scene has no sun: "
                                "declare its first state with sun { }"),
            std::string::npos)
      << undeclared.err;
  expect_no_leftovers(undeclared);
}

// frames { lights }: a named point light moves and brightens from frame to frame, and each frame equals the farm of
// that frame alone whose script declares the light where the job's frame puts it. A name that is no point light of
// the script is refused before launch, at the frames line, naming those it has.
TEST_F(JobTest, APointLightMovesFromFrameToFrame) {
  write("yard.obj", kYard);
  const std::string script = write("bulb.lua", R"(
scene  { file = "yard.obj" }
camera { eye = {0, 4, 7}, at = {0, 0.3, 0}, fov = 50 }
image  { width = 32, height = 32, spp = 2, tile = 16, output = param("out", "bulb.####.exr") }
farm   { light_paths = "partial" }  -- direct light alone
local function bulb_at(f) return { point = {3 * f - 4.5, 2, 1}, intensity = {10 * f, 10 * f, 10 * f} } end
local single = param("frame", 0)
local first = bulb_at(single > 0 and single or 1)
light { name = param("name", "bulb"), point = first.point, intensity = first.intensity }
if single == 0 then frames { first = 1, last = 2, lights = function(f) return { bulb = bulb_at(f) } end } end
renderers { count = 2, lighting = lightop "direct" {} }
)");
  expect_frames_are_their_farms_alone(script, "bulb", 2, "the light");
  auto run_bulb = [&](const std::string& out, std::vector<std::string> extra) { return run_quiet(script, out, extra); };

  const auto unnamed = run_bulb("u.####.exr", {"--set", "name=lamp"});
  EXPECT_EQ(unnamed.status, 2) << unnamed.err;
  EXPECT_NE(unnamed.err.find("bulb.lua:10: frames: the lights function's table for frame 1: 'bulb' is not a named "
                             "point light of the script (named: lamp)"),
            std::string::npos)
      << unnamed.err;
  expect_no_leftovers(unnamed);
}

// frames { environment }: the sky map turns from frame to frame (a turntable lit by its HDRI), and each frame equals
// the farm of that frame alone whose script declares the map turned as the job's frame turns it. A change that does
// not fit the declared environment is refused before launch, at the frames line.
TEST_F(JobTest, TheEnvironmentTurnsFromFrameToFrame) {
  write("yard.obj", kYard);
  // A dim sky with one bright patch low in the east: the block's shadow points away from it.
  Image sky;
  sky.width = 16;
  sky.height = 8;
  sky.pixels.assign(16 * 8, RGB{0.05f, 0.05f, 0.08f});
  sky.pixels[3 * 16 + 8] = {400, 380, 300};
  ASSERT_TRUE(write_image(sky, path("sky.exr")).ok());
  const std::string script = write("sky.lua", R"(
scene  { file = "yard.obj" }
camera { eye = {0, 4, 7}, at = {0, 0.3, 0}, fov = 50 }
image  { width = 32, height = 32, spp = 2, tile = 16, output = param("out", "sky.####.exr") }
farm   { light_paths = "partial" }  -- direct light alone
local function turned(f) return { rotation = 90 * (f - 1), intensity = 1 + f / 4 } end
local single = param("frame", 0)
if param("map", true) then
  local first = turned(single > 0 and single or 1)
  environment { map = "sky.exr", rotation = first.rotation, intensity = first.intensity }
else environment { radiance = {1, 1, 1} } end
if single == 0 then frames { first = 1, last = 3, environment = turned } end
renderers { count = 2, lighting = lightop "direct" {} }
)");
  expect_frames_are_their_farms_alone(script, "sky", 3, "the light from the sky");
  auto run_sky = [&](const std::string& out, std::vector<std::string> extra) { return run_quiet(script, out, extra); };

  const auto constant = run_sky("c.####.exr", {"--set", "map=false"});
  EXPECT_EQ(constant.status, 2) << constant.err;
  EXPECT_NE(constant.err.find("sky.lua:12: frames: frame 1: the environment is one radiance: a frame gives its "
                              "radiance (and intensity), it has no map to rotate"),
            std::string::npos)
      << constant.err;
  expect_no_leftovers(constant);
}

// --preview-every: while a frame renders its partial image (finished tiles, the rest black) is beside the output;
// it goes once the frame is written.
TEST_F(JobTest, APreviewShowsTheFrameWhileItRenders) {
  // 25 tiles over several seconds: a preview a twentieth of a second apart catches some landed and some not.
  Farm farm({"run", script, "--set", "out=" + path("p.####.exr"), "--set", "last=1", "--set", "spp=64", "--set", "tile=8",
             "--checkpoint-every", "0", "--preview-every", "0.05"});
  const std::string preview = path("p.0001.preview.exr");
  std::optional<Image> seen;
  ASSERT_TRUE(Farm::eventually([&] {
    if (!fs::exists(preview)) return false;
    auto img = read_image(preview);
    if (img.ok()) seen = *img;
    return img.ok();
  }, 120)) << farm.err_so_far();
  const auto done = farm.wait(300);
  ASSERT_EQ(done.status, 0) << done.err;
  expect_no_leftovers(done);
  EXPECT_FALSE(fs::exists(preview)) << "the preview outlived its frame";
  ASSERT_TRUE(seen.has_value());
  size_t black = 0, lit = 0;
  for (const RGB& p : seen->pixels) (p.x == 0 && p.y == 0 && p.z == 0 ? black : lit) += 1;
  EXPECT_GT(lit, 0u) << "a preview is written once a tile has landed";
  EXPECT_GT(black, 0u) << "and before the last";
  auto bad = run_lightfarm({"run", script, "--preview-every", "0"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("--preview-every needs seconds (more than 0)"), std::string::npos) << bad.err;
}

TEST_F(JobTest, BadJobsAreRefusedBeforeAnythingStarts) {
  auto r = run_lightfarm({"run", script, "--set", "out=" + path("plain.exr")});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("has no #### where the frame number goes"), std::string::npos) << r.err;
  r = run_lightfarm({"run", script, "--frames", "13"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--frames: frame 13 is not one of the script's frames (1-12)"), std::string::npos) << r.err;
  r = run_lightfarm({"run", script, "--frames", "3-1"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("range 3-1 runs backwards"), std::string::npos) << r.err;
  expect_no_leftovers(r);
  r = run("dark.####.exr", {"--set", "last=3", "--set", "dark_from=2"});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("turn.lua:25: frames: frame 2's materials leave the scene without light"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(frame("dark", 1))) << "refused before anything rendered";
  expect_no_leftovers(r);
  // A radiosity ring's solution is made once: it cannot follow a job's change of materials.
  const std::string ring = write("ring.lua", R"(
scene { builtin = "cornell_glass" }
image { width = 16, height = 16, spp = 1, output = "ring.####.png" }
frames { last = 2, materials = function(f) return { light = { emission = {f, f, f} } } end }
farm { light_paths = "partial" }
renderers { count = 1, lighting = radiosity { rings = 1, ring_length = 2, patch_size = 140, element_size = 70 } }
)");
  r = run_lightfarm({"run", ring});
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("ring.lua:4: frames: materials change over the job, which the radiosity ring's solution, made "
                       "once for the farm, cannot follow"),
            std::string::npos) << r.err;
  expect_no_leftovers(r);
}

}  // namespace
}  // namespace lf::test
