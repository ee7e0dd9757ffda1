#include "lua/script.hpp"
#include "farm/builders.hpp"
#include "farm/light_path_check.hpp"
#include "render/scene/scene_report.hpp"
#include "render/lightops/lightop_registry.hpp"

#include <gtest/gtest.h>

#include "render/scene/scene.hpp"

#include <map>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace lf {

namespace fs = std::filesystem;

class ScriptTest : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    dir = fs::temp_directory_path() / ("lightfarm-script-test-" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    auto p = dir / name;
    std::ofstream(p) << text;
    return p.string();
  }
  std::string error_of(const std::string& text, ScriptOptions o = {}) {
    auto path = write("farm.lua", text);
    auto r = evaluate_script(path, o);
    EXPECT_FALSE(r.ok());
    if (r.ok()) return {};
    // Make messages independent of the temporary directory.
    std::string m = r.error().message;
    auto pos = m.find(path);
    if (pos != std::string::npos) m.replace(pos, path.size(), "farm.lua");
    return m;
  }
};

static const char* kCornell = R"(scene { builtin = "cornell" }
camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }
image { width = 64, height = 48, spp = 2, output = "x.png" }
local direct = lightop "direct" { light_samples = param("light_samples", 2) }
renderers { count = param("renderers", 2), lighting = direct }
)";

TEST_F(ScriptTest, CornellScriptBuildsTheGraph) {
  auto r = evaluate_script(write("farm.lua", kCornell));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const FarmSpec& s = *r;
  EXPECT_EQ(s.scene.builtin, "cornell");
  EXPECT_EQ(s.image.width, 64);
  EXPECT_EQ(s.image.spp, 2);
  ASSERT_EQ(s.actors.size(), 3u);
  EXPECT_EQ(s.actors[0].name, "direct");
  EXPECT_EQ(s.actors[0].params.at("light_samples").as_int(), 2);
  EXPECT_EQ(s.actors[0].loc.line, 4);
  EXPECT_EQ(s.renderer_count(), 2);
  EXPECT_EQ(s.actors[2].name, "renderer-1");
  EXPECT_EQ(s.actors[2].inputs, std::vector<int>{0});
  EXPECT_EQ(s.lighting, 0);
}

TEST_F(ScriptTest, SetOverridesParamsWithTheDefaultsType) {
  ScriptOptions o;
  o.set = {{"renderers", "3"}, {"light_samples", "8"}};
  o.output = "other.exr";
  auto r = evaluate_script(write("farm.lua", kCornell), o);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->renderer_count(), 3);
  EXPECT_EQ(r->actors[0].params.at("light_samples").as_int(), 8);
  EXPECT_EQ(r->image.output, "other.exr");
}

TEST_F(ScriptTest, SetErrorsNameTheParam) {
  ScriptOptions o;
  o.set = {{"renderers", "many"}};
  EXPECT_EQ(error_of(kCornell, o), "farm.lua:5: --set renderers=many: param 'renderers' is a number");
  o.set = {{"renderer", "2"}};
  EXPECT_EQ(error_of(kCornell, o), "farm.lua: --set renderer=2: the script has no param 'renderer'");
}

TEST_F(ScriptTest, SyntaxErrorNamesFileAndLine) {
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal x = = 3\n"), "farm.lua:2: unexpected symbol near '='");
}

TEST_F(ScriptTest, AScriptsTextEvaluatesAsItsFileWould) {
  auto from_file = evaluate_script(write("farm.lua", kCornell));
  auto from_text = evaluate_script_text((dir / "farm.lua").string(), kCornell);
  ASSERT_TRUE(from_file.ok() && from_text.ok());
  ASSERT_EQ(from_text->actors.size(), from_file->actors.size());
  for (size_t i = 0; i < from_file->actors.size(); ++i) {
    EXPECT_EQ(from_text->actors[i].name, from_file->actors[i].name);
    EXPECT_EQ(from_text->actors[i].loc.line, from_file->actors[i].loc.line);
  }
  auto bad = evaluate_script_text("text.lua", "scene { builtin = \"cornell\" }\nlocal x = = 3\n");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message, "text.lua:2: unexpected symbol near '='");
}

TEST_F(ScriptTest, TheSamplerIsIndependentOrSobol) {
  auto plain = evaluate_script(write("farm.lua", kCornell));
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain->image.sampler, "sobol") << "the default";
  auto chosen = evaluate_script(write("farm.lua", "scene { builtin = \"cornell\" }\nimage { sampler = \"independent\" }\n"
                                                  "renderers { count = 1, lighting = lightop \"direct\" {} }\n"));
  ASSERT_TRUE(chosen.ok()) << chosen.error().message;
  EXPECT_EQ(chosen->image.sampler, "independent");
  EXPECT_EQ(ImageSpec::from_value(chosen->image.to_value())->sampler, "independent") << "it travels in CONFIG";
  EXPECT_EQ(error_of("image { sampler = \"halton\" }\n"),
            "farm.lua:1: image: parameter 'sampler' must be one of independent, sobol, got 'halton'");
}

// pool { } is the script's word for a set of replicas; multiplexer { } is the same function under its older name.
TEST_F(ScriptTest, PoolAndMultiplexerDeclareTheSamePool) {
  auto farm_with = [&](const std::string& word) {
    return evaluate_script_text((dir / "farm.lua").string(),
                                "scene { builtin = \"cornell\" }\n"
                                "local d = " + word + " { lightop \"direct\" {}, replicas = 3, strategy = \"round_robin\" }\n"
                                "renderers { lighting = d }\n");
  };
  auto pool = farm_with("pool"), mux = farm_with("multiplexer");
  ASSERT_TRUE(pool.ok()) << pool.error().message;
  ASSERT_TRUE(mux.ok()) << mux.error().message;
  ASSERT_EQ(pool->actors.size(), mux->actors.size());
  for (size_t i = 0; i < pool->actors.size(); ++i) {
    EXPECT_EQ(pool->actors[i].name, mux->actors[i].name);
    EXPECT_EQ(pool->actors[i].kind, mux->actors[i].kind);
    EXPECT_EQ(pool->actors[i].params, mux->actors[i].params);
  }
  EXPECT_EQ(pool->actors.size(), 5u);  // direct.0-2, the pool, a renderer
}

TEST_F(ScriptTest, PoolsOfPoolsCannotMultiplyIntoAHugeFarm) {
  // Found by fuzzing: three nested pools of 64 would be 262,144 actors, and building them took seconds.
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\n"
                     "local d = multiplexer { lightop \"direct\" {}, replicas = 64 }\n"
                     "d = multiplexer { d, replicas = 64 }\n"
                     "d = multiplexer { d, replicas = 64 }\n"),
            "farm.lua:3: multiplexer: this pool would make the farm 4161 actors (at most 4096)");
}

TEST_F(ScriptTest, UnknownKindNamesLineAndKnownKinds) {
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\n\nlocal p = lightop \"photon\" { }\n"),
            "farm.lua:3: unknown LightOp kind 'photon' (known kinds: " + lightop_kind_list() + ")");
}

// material "Name" { ... } changes a named material of the scene; errors at the line for what cannot be.
TEST_F(ScriptTest, MaterialChangesNameTheirLineWhenWrong) {
  auto spec = evaluate_script(write("m.lua", "scene { builtin = \"cornell\" }\nmaterial \"light\" { emission = {34, 24, 8} }\n"
                                    "material \"red\" { kd = {0.5, 0, 0}, ks = {0.2, 0, 0}, ns = 40, type = \"glossy\" }\n"
                                    "renderers { count = 1, lighting = lightop \"direct\" {} }\n"));
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  ASSERT_EQ(spec->scene.materials.size(), 2u);
  EXPECT_EQ(spec->scene.materials[0].find("name")->as_string(), "light");
  EXPECT_EQ(spec->scene.materials[1].find("type")->as_string(), "glossy");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\n\nmaterial \"lamp\" { emission = {1, 1, 1} }\n"),
            "farm.lua:3: material 'lamp' is not in the scene (its materials: white, red, green, light)");
  EXPECT_EQ(error_of("material \"light\" { emission = {1, 1, 1} }\nscene { builtin = \"cornell\" }\n"),
            "farm.lua:1: material \"light\" needs scene { ... } before it");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nmaterial \"red\" { kd = {0.9, 0, 0}, ks = {0.5, 0, 0} }\n"),
            "farm.lua:2: material 'red': kd + ks + mirror exceeds 1 in some channel, so the surface would create energy");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nmaterial \"red\" { kd = {2, 0, 0} }\n"),
            "farm.lua:2: material 'red': kd must be between 0 and 1 in each channel");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nmaterial \"red\" { glow = 1 }\n").rfind(
                "farm.lua:2: material 'red': unknown parameter 'glow'", 0),
            0u);
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nmaterial \"red\" { ns = 1 }\nmaterial \"red\" { ns = 2 }\n"),
            "farm.lua:3: material 'red' is changed twice");
}

TEST_F(ScriptTest, ShapesAddGeometryWithTheirOwnMaterialAndNameTheirLineWhenWrong) {
  auto spec = evaluate_script(write("s.lua", "scene { builtin = \"cornell\" }\n"
                                    "shape \"ball\" { sphere = {278, 120, 250}, radius = 110 }\n"
                                    "shape \"ground\" { plane = {0, 0, 0}, material = \"white\" }\n"
                                    "shape \"lamp\" { sphere = {100, 400, 250}, radius = 20, emission = {5, 5, 5}, kd = {0, 0, 0} }\n"
                                    "material \"ball\" { ks = {0.1, 0.1, 0.1}, ns = 30, type = \"glossy\" }\n"
                                    "renderers { count = 1, lighting = lightop \"pathtrace\" {} }\n"));
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  ASSERT_EQ(spec->scene.shapes.size(), 3u);
  EXPECT_EQ(spec->scene.shapes[1].find("material")->as_string(), "white");
  ASSERT_EQ(spec->scene.materials.size(), 2u) << "the lamp's own parameters, then the script's change of the ball";
  auto scene = Scene::load(spec->scene);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  int glossy = 0, lamps = 0;
  for (const Material& m : scene->materials()) {
    glossy += m.name == "ball" && m.type == Material::Type::glossy;
    lamps += m.name == "lamp" && m.emissive();
  }
  EXPECT_EQ(glossy, 1);
  EXPECT_EQ(lamps, 1) << "a shape may glow";
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nshape \"b\" { sphere = {0, 0, 0}, radius = 1, kd = {1, 0, 0} }\n"
                     "material \"b\" { ns = 3 }\n"),
            "farm.lua:3: material 'b' is changed twice");
  EXPECT_EQ(error_of("shape \"ball\" { sphere = {0, 0, 0}, radius = 1 }\nscene { builtin = \"cornell\" }\n"),
            "farm.lua:1: shape \"ball\" needs scene { ... } before it");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\n\nshape \"red\" { plane = {0, 0, 0} }\n"),
            "farm.lua:3: shape 'red': the scene already has a material 'red'; name the shape otherwise, or give "
            "material = \"red\"");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nshape \"b\" { sphere = {0, 0, 0}, radius = 1 }\n"
                     "shape \"b\" { sphere = {0, 0, 0}, radius = 2 }\n"),
            "farm.lua:3: shape 'b' is declared twice");
}

TEST_F(ScriptTest, BadParametersNameLineAndParameter) {
  EXPECT_EQ(error_of("local d = lightop \"direct\" { light_sample = 4 }\n"),
            "farm.lua:1: lightop 'direct': unknown parameter 'light_sample' (known: learned_cell, learned_samples, "
            "learned_share, learned_stride, light_point, light_samples, light_sampling, mis, mis_reach, reuse, seed)");
  EXPECT_EQ(error_of("local d = lightop \"direct\" { light_samples = -1 }\n"),
            "farm.lua:1: lightop 'direct': parameter 'light_samples' must be in [1, 1048576], got -1");
  EXPECT_EQ(error_of("image { width = 0 }\n"), "farm.lua:1: image: parameter 'width' must be in [1, 16384], got 0");
  EXPECT_EQ(error_of("image { width = 8 }\nimage { width = 9 }\n"), "farm.lua:2: image is declared twice");
  EXPECT_EQ(error_of("camera { fov = 30 }\ncamera { fov = 40 }\n"), "farm.lua:2: camera is declared twice");
  EXPECT_EQ(error_of("camera { eye = {1, 1, 1}, at = {1, 1, 1} }\n"), "farm.lua:1: camera: eye and at are the same point");
  EXPECT_EQ(error_of("\nimage { tonemap = \"filmic\" }\n").rfind("farm.lua:2: image: parameter 'tonemap' must be one of", 0), 0u)
      << error_of("\nimage { tonemap = \"filmic\" }\n");
  EXPECT_EQ(error_of("image { exposure = 40 }\n"), "farm.lua:1: image: parameter 'exposure' must be in [-20, 20], got 40");
  EXPECT_EQ(error_of("image { spp = 8,\n shade_spp = 16 }\n"),
            "farm.lua:1: image: parameter 'shade_spp' must be in [1, 8], got 16");
  EXPECT_EQ(error_of("image { spp = 8, adaptive_spp = 8 }\n"),
            "farm.lua:1: image: parameter 'adaptive_spp' must be 0 (off) or an integer in [9, 65536], got 8");
  EXPECT_EQ(error_of("image { spp = 8, shade_spp = 2, adaptive_spp = 8, time_limit = 60 }\n"),
            "farm.lua:1: image: time_limit renders passes of spp samples while the time lasts; adaptive_spp, which "
            "shades more of one pass's samples where they are noisy, cannot be combined with it");
  EXPECT_EQ(error_of("image { time_limit = -1 }\n"), "farm.lua:1: image: parameter 'time_limit' must be in [0, 1e+07], got -1");
  EXPECT_EQ(error_of("image { spp = 8, shade_spp = 1, adaptive_spp = 8 }\n"),
            "farm.lua:1: image: adaptive_spp needs shade_spp (or spp) of at least 2 (a pixel's spread needs two samples)");
  EXPECT_EQ(error_of("image { spp = 8, shade_spp = 2, adaptive_spp = 0, adaptive_threshold = 0.1 }\n"),
            "farm.lua:1: image: adaptive_threshold needs adaptive sampling, which adaptive_spp = 0 turns off");
  EXPECT_EQ(error_of("image { spp = 8, shade_spp = 2, adaptive_spp = 100000 }\n"),
            "farm.lua:1: image: parameter 'adaptive_spp' must be 0 (off) or an integer in [3, 65536], got 100000");
  EXPECT_EQ(error_of("image { spp = 1, adaptive_spp = 8 }\n"),
            "farm.lua:1: image: adaptive_spp needs shade_spp (or spp) of at least 2 (a pixel's spread needs two samples)");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlight { quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.5}, {0, 1, 0}}, "
                     "radiance = {1, 1, 1} }\n")
                .rfind("farm.lua:2: light: the quad is not planar (its 4th corner is 0.447214 off the plane", 0),
            0u);
  EXPECT_EQ(error_of("camera { eye = {0, 0, 0}, at = {0, 0, 0} }\n"), "farm.lua:1: camera: eye and at are the same point");
}

TEST_F(ScriptTest, WiringErrors) {
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nrenderers { lighting = 3 }\n"),
            "farm.lua:2: lighting must be a LightOp (made with lightop \"kind\" { ... }), got a number");
  EXPECT_EQ(error_of("local d = lightop \"direct\" {}\nlocal e = lightop \"direct\" { input = d }\n"),
            "farm.lua:2: lightop 'direct' takes 0 inputs, got 1");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\n"),
            "farm.lua: the script declares no renderers (add renderers { lighting = ... })");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal a = lightop \"direct\" {}\nlocal b = lightop \"direct\" {}\n"
                     "renderers { lighting = b }\n"),
            "farm.lua:2: lightop 'direct' is not connected to the renderers' lighting (nothing would ask it for light)");
}

TEST_F(ScriptTest, NetworkWiringErrorsNameTheLine) {
  // A missing input, too many inputs, and an input that is not a LightOp.
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal s = lightop \"specular\" {}\n"),
            "farm.lua:2: lightop 'specular' takes 1 input, got 0");
  EXPECT_EQ(error_of("local d = lightop \"direct\" {}\nlocal i = lightop \"irradiance\" { inputs = { d, d } }\n"),
            "farm.lua:2: lightop 'irradiance' takes 1 input, got 2");
  EXPECT_EQ(error_of("local c = lightop \"combine\" { inputs = { 1 } }\n"),
            "farm.lua:1: each of inputs must be a LightOp (made with lightop \"kind\" { ... }), got a number");
  EXPECT_EQ(error_of("local h = host \"x\" {}\nlocal c = lightop \"combine\" { input = h }\n"),
            "farm.lua:2: input must be a LightOp (made with lightop \"kind\" { ... }), got a userdata");
  // Handles exist only once declared, so a network cannot loop back on itself: naming an op before it exists
  // is naming nil, which Lua cannot tell from leaving the input out.
  EXPECT_EQ(error_of("local a = lightop \"combine\" { input = b }\nlocal b = lightop \"direct\" {}\n"),
            "farm.lua:1: lightop 'combine' takes at least 1 input, got 0");
}

TEST_F(ScriptTest, LightsAreCheckedAtTheirLine) {
  auto r = evaluate_script(write("farm.lua", std::string(kCornell) +
                                                 "light { point = {278, 400, 280}, intensity = {1000, 1000, 1000} }\n"
                                                 "light { sphere = {100, 100, 100}, radius = 20, radiance = {5, 5, 5} }\n"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->scene.lights.size(), 2u);
  EXPECT_EQ(error_of("light { point = {0, 0} , intensity = {1, 1, 1} }\n"), "farm.lua:1: light: point must be {x, y, z}");
  EXPECT_EQ(error_of("light { quad = {{0,0,0}, {1,0,0}, {1,1,0}}, radiance = {1, 1, 1} }\n"),
            "farm.lua:1: light: quad needs 4 corners");
  EXPECT_EQ(error_of("light { point = {0, 0, 0}, sphere = {0, 0, 0}, intensity = {1, 1, 1} }\n"),
            "farm.lua:1: light needs exactly one of quad, sphere or point");
  EXPECT_EQ(error_of("light { point = {0, 0, 0}, intensty = {1, 1, 1} }\n"),
            "farm.lua:1: light: unknown parameter 'intensty' (known: quad, sphere, radius, radiance, point, intensity, name)");
  EXPECT_EQ(error_of("light { point = {0, 0, 0}, intensity = {1, -1, 1} }\n"), "farm.lua:1: light: intensity must not be negative");
}

TEST_F(ScriptTest, EnvironmentAndSunAreCheckedAtTheirLine) {
  auto r = evaluate_script(write("farm.lua", std::string(kCornell) +
                                                 "environment { radiance = {0.2, 0.3, 0.5}, camera = false }\n"
                                                 "sun { direction = {1, 2, 0}, irradiance = {3, 3, 3}, angle = 1 }\n"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->scene.lights.size(), 2u);
  EXPECT_EQ(r->scene.lights[0].find("environment")->find("camera")->as_bool(), false);
  EXPECT_EQ(r->scene.lights[1].find("sun")->find("angle")->as_double(), 1.0);
  EXPECT_EQ(error_of("environment { map = \"sky.exr\" }\n"),
            "farm.lua:1: environment map '" + (dir / "sky.exr").string() + "' not found");
  EXPECT_EQ(error_of("environment { map = \"sky.exr\", radiance = {1, 1, 1} }\n"),
            "farm.lua:1: environment needs exactly one of map = \"sky.exr\" or radiance = {r, g, b}");
  EXPECT_EQ(error_of("environment { radiance = {1, 1, 1} }\nenvironment { radiance = {1, 1, 1} }\n"),
            "farm.lua:2: environment is declared twice");
  EXPECT_EQ(error_of("sun { irradiance = {1, 1, 1} }\n"), "farm.lua:1: sun needs a direction = {x, y, z} (towards the sun)");
  EXPECT_EQ(error_of("sun { direction = {0, 0, 0}, irradiance = {1, 1, 1} }\n"),
            "farm.lua:1: sun: direction must not be {0, 0, 0}");
  EXPECT_NE(error_of("environment { radiance = {1, 1, 1}, rotaton = 3 }\n").find("farm.lua:1: "), std::string::npos);
  EXPECT_NE(error_of("environment { radiance = {1, 1, 1}, rotaton = 3 }\n").find("rotaton"), std::string::npos);
}

TEST_F(ScriptTest, MissingSceneFileIsNamedRelativeToTheScript) {
  auto m = error_of("scene { file = \"room.obj\" }\n");
  EXPECT_EQ(m, "farm.lua:1: scene file '" + (dir / "room.obj").string() + "' not found");
}

TEST_F(ScriptTest, ScriptsCannotReachFilesOrPrograms) {
  EXPECT_EQ(error_of("io.open('/etc/passwd')\n"), "farm.lua:1: attempt to index a nil value (global 'io')");
  EXPECT_EQ(error_of("os.execute('true')\n"), "farm.lua:1: attempt to index a nil value (global 'os')");
}

TEST_F(ScriptTest, FarmSettingsAndHosts) {
  auto r = evaluate_script(write("farm.lua", std::string(kCornell) + "farm { heartbeat_timeout = 2.5 }\n"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_DOUBLE_EQ(r->heartbeat_timeout, 2.5);
  EXPECT_EQ(error_of("farm { heartbeat = 3 }\n"),
            "farm.lua:1: farm: unknown parameter 'heartbeat' (known: director_address, heartbeat_timeout, host_agents, "
            "light_paths, monitor, request_timeout, security)");
  EXPECT_EQ(r->light_paths, "check") << "paths counted twice are errors, paths left out warnings, by default";
  auto partial = evaluate_script(write("farm.lua", std::string(kCornell) + "farm { light_paths = \"partial\" }\n"));
  ASSERT_TRUE(partial.ok()) << partial.error().message;
  EXPECT_EQ(partial->light_paths, "partial");
  EXPECT_EQ(error_of("farm { light_paths = \"some\" }\n"),
            "farm.lua:1: farm: parameter 'light_paths' must be one of check, complete, partial, off, got 'some'");
  auto own = evaluate_script(write("farm.lua", std::string(kCornell) + "farm { host_agents = false }\n"));
  ASSERT_TRUE(own.ok()) << own.error().message;
  EXPECT_FALSE(own->host_agents);
  EXPECT_TRUE(r->host_agents) << "host agents are the default";
  auto watched = evaluate_script(write("farm.lua", std::string(kCornell) + "farm { monitor = \"127.0.0.1:8080\" }\n"));
  ASSERT_TRUE(watched.ok()) << watched.error().message;
  EXPECT_EQ(watched->monitor, "127.0.0.1:8080");
  EXPECT_EQ(error_of("local h = host \"gpu1\" { launcher = \"ssh\" }\n"),
            "farm.lua:1: host 'gpu1': an ssh host needs address = \"...\" (where its actors listen and ssh reaches it)");
  EXPECT_EQ(error_of("local h = host \"gpu1\" { launcher = \"slurm\" }\n"),
            "farm.lua:1: host 'gpu1': a slurm host needs address = \"...\" (where its actors listen)");
  if (!std::getenv("SLURM_JOB_NODELIST") && !std::getenv("SLURM_NODELIST")) {
    EXPECT_EQ(error_of("local hs = slurm_hosts()\n"),
              "farm.lua:1: slurm_hosts(): not inside a Slurm allocation (SLURM_JOB_NODELIST is not set; run the farm "
              "under salloc or sbatch)");
  }
  EXPECT_EQ(error_of("local h = host \"gpu1\" { launcher = \"ssh\", address = \"10.0.0.1\", ssh_config = \"nope\" }\n"),
            "farm.lua:1: host 'gpu1': ssh_config '" + (dir / "nope").string() + "' not found");
  EXPECT_EQ(error_of("local h = host \"gpu1\" { address = \"10.0.0.1\" }\n"
                     "local d = lightop \"direct\" { host = { h, h } }\n"),
            "farm.lua:2: one actor runs on one host; a list of hosts is for multiplexer, renderers and radiosity");
  EXPECT_EQ(error_of("local d = lightop \"direct\" { host = \"gpu1\" }\n"),
            "farm.lua:1: host 'gpu1' is not declared (declare it with host \"gpu1\" { ... })");
  auto ok = evaluate_script(write("farm.lua", std::string("local h = host \"here\" { launcher = \"local\" }\n") +
                                                  "scene { builtin = \"cornell\" }\n"
                                                  "renderers { lighting = lightop \"direct\" { host = h } }\n"));
  ASSERT_TRUE(ok.ok()) << ok.error().message;
  EXPECT_EQ(ok->actors[0].host, "here");
}

TEST_F(ScriptTest, HostListsSpreadReplicasRenderersAndRingNodesRoundRobin) {
  auto r = evaluate_script(write("farm.lua", std::string(
      "local a = host \"a\" { launcher = \"ssh\", address = \"10.0.0.1\", user = \"render\", port = 2222 }\n"
      "local b = host \"b\" { launcher = \"ssh\", address = \"10.0.0.2\" }\n"
      "scene { builtin = \"cornell\" }\n"
      "local d = multiplexer { lightop \"direct\" {}, replicas = 3, host = { a, b } }\n"
      "renderers { count = 3, lighting = d, host = { b, \"local\" } }\n")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  std::map<std::string, std::string> where;
  for (const auto& actor : r->actors) where[actor.name] = actor.host;
  EXPECT_EQ(where, (std::map<std::string, std::string>{{"direct", "a"}, {"direct.0", "a"}, {"direct.1", "b"},
                                                        {"direct.2", "a"}, {"renderer-0", "b"}, {"renderer-1", "local"},
                                                        {"renderer-2", "b"}}));
  EXPECT_TRUE(r->has_remote_hosts());
  ASSERT_EQ(r->hosts.size(), 2u);
  EXPECT_EQ(r->hosts[0].user, "render");
  EXPECT_EQ(r->hosts[0].port, 2222);
  const std::string dot = to_dot(*r);
  EXPECT_NE(dot.find("subgraph \"cluster_a\""), std::string::npos);
  EXPECT_NE(dot.find("subgraph \"cluster_b\""), std::string::npos);
}

TEST_F(ScriptTest, MissingScriptIsAnError) {
  auto r = evaluate_script((dir / "nope.lua").string());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "script '" + (dir / "nope.lua").string() + "' not found");
}

TEST_F(ScriptTest, DotShowsTheNetwork) {
  auto r = evaluate_script(write("farm.lua", kCornell));
  ASSERT_TRUE(r.ok());
  std::string dot = to_dot(*r);
  EXPECT_NE(dot.find("digraph farm"), std::string::npos);
  EXPECT_NE(dot.find("\"direct\" -> \"renderers\""), std::string::npos);
  EXPECT_NE(dot.find("renderer × 2"), std::string::npos);
}

}  // namespace lf

namespace lf {

TEST_F(ScriptTest, RadiosityDeclaresItsRingNodesAndReturnsTheLightOp) {
  auto path = write("farm.lua", "scene { builtin = \"cornell\" }\n"
                                "local r = radiosity { rings = 2, ring_length = 3, balance = \"static\" }\n"
                                "renderers { lighting = lightop \"combine\" { inputs = { r, lightop \"direct\" {} } } }\n");
  auto spec = evaluate_script(path, {});
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  std::vector<std::string> nodes;
  for (const auto& a : spec->actors)
    if (a.kind == "radiosity_node") {
      nodes.push_back(a.name);
      EXPECT_EQ(a.inputs.size(), 5u) << a.name;  // every other node
      EXPECT_EQ(a.params.at("balance").as_string(), "static");
    }
  EXPECT_EQ(nodes, (std::vector<std::string>{"radiosity.0.0", "radiosity.0.1", "radiosity.0.2", "radiosity.1.0",
                                             "radiosity.1.1", "radiosity.1.2"}));
  const std::string dot = to_dot(*spec);
  EXPECT_NE(dot.find("\"radiosity.1.2\" -> \"radiosity.1.0\";"), std::string::npos) << dot;  // round the ring
  EXPECT_NE(dot.find("\"radiosity.0.1\" -> \"radiosity.1.1\" [style=dashed"), std::string::npos) << dot;

  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal a = radiosity {}\nlocal b = radiosity {}\n"),
            "farm.lua:3: radiosity is declared twice (a farm has one radiosity ring)");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal d = lightop \"direct\" {}\nlocal a = radiosity { input = d }\n"),
            "farm.lua:3: radiosity takes no inputs (it solves the scene itself)");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nlocal a = radiosity { balance = \"perfect\" }\n").substr(0, 50),
            "farm.lua:2: radiosity: parameter 'balance' must be");
}

}  // namespace lf

namespace lf {
namespace {

// A script describes a farm and ends: an endless loop and a table that keeps growing are errors at their line,
// within the budgets (small ones here, so the test is quick).
TEST_F(ScriptTest, ScriptsHaveAnInstructionAndAMemoryBudget) {
  ScriptOptions small;
  small.instruction_budget = 5'000'000;
  small.memory_budget = 8u << 20;
  auto loop = evaluate_script(write("farm.lua", "scene { builtin = \"cornell\" }\nlocal n = 0\nwhile true do n = n + 1 end\n"), small);
  ASSERT_FALSE(loop.ok());
  EXPECT_EQ(loop.error().message, (dir / "farm.lua").string() +
                                      ":3: the script ran for more than 5 million Lua instructions (an endless loop?); "
                                      "a farm script describes a farm and ends");
  auto bomb = evaluate_script(write("farm.lua", "scene { builtin = \"cornell\" }\nlocal t = {}\nwhile true do\n"
                                                "  t[#t + 1] = string.rep(\"x\", 1000) .. #t\nend\n"),
                              small);
  ASSERT_FALSE(bomb.ok());
  EXPECT_EQ(bomb.error().message,
            (dir / "farm.lua").string() + ":4: the script used more than 8 MiB of memory (a table that keeps growing?)");
  // Real scripts are far inside the default budgets.
  EXPECT_TRUE(evaluate_script(std::string(LIGHTFARM_SOURCE_DIR) + "/examples/cornell_glass_radiosity.lua").ok());
}

// The network `lightfarm scene` suggests for a scene's lobes counts every light path on them once.
TEST_F(ScriptTest, TheSuggestedNetworksAreComplete) {
  const Lobes sets[] = {Lobes::of({Lobe::diffuse}), Lobes::of({Lobe::diffuse, Lobe::glossy}),
                        Lobes::of({Lobe::diffuse, Lobe::specular}), Lobes::all(), Lobes::of({Lobe::glossy}),
                        Lobes::of({Lobe::glossy, Lobe::specular})};
  for (const Lobes& lobes : sets)
    for (const NetworkChoices& choices : {NetworkChoices{true, 1, false}, NetworkChoices{false, 1, false},
                                          NetworkChoices{true, 2, true}, NetworkChoices{false, 3, true}}) {
      const std::string network = complete_network_for(lobes, choices);
      EXPECT_EQ(network.find("multiplexer") != std::string::npos, choices.cores > 1) << network;
      EXPECT_EQ(network.find("learned") != std::string::npos,
                choices.many_lights && choices.worth_caching && lobes.contains(Lobe::diffuse)) << network;
      auto r = evaluate_script(write("farm.lua", "scene { builtin = \"cornell\" }\n" + network));
      ASSERT_TRUE(r.ok()) << r.error().message;
      SceneLobes scene;
      scene.lobes = lobes;
      scene.emits = true;
      for (int l = 0; l < kLobeCount; ++l)
        if (lobes.has[l]) scene.materials[l] = {"m"};
      const LightPathReport report = check_light_paths(*r, scene);
      EXPECT_TRUE(report.errors.empty() && report.warnings.empty()) << network;
    }
}

// A job: frames { } with a camera function or camera { keys }, output patterns, --frames, and their mistakes.
// A job over a scene file whose camera is animated: frame n is the file's view at n / fps seconds (Blender's
// export: frame f at f / fps), over camera { }'s other keys; animation = false holds the camera at rest; a camera
// function or keys that would move it too must say which.
TEST_F(ScriptTest, AJobFollowsTheSceneFilesCameraAnimation) {
  const std::string file = std::string(LIGHTFARM_SOURCE_DIR) + "/render/scene/testdata/camera_walk.gltf";
  const std::string head = "scene { file = \"" + file + "\" }\nimage { output = \"t.####.png\" }\n";
  const std::string net = "local direct = lightop \"direct\" { }\nrenderers { count = 1, lighting = direct }\n";
  auto r = evaluate_script(write("farm.lua", head + "camera { gltf = \"Camera\", fov = 30 }\nframes { first = 1, last = 24 }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames.size(), 24u);
  EXPECT_NEAR(r->frames[0].camera.eye[1], 2, 1e-4);
  EXPECT_NEAR(r->frames[11].camera.eye[0], 3.739295, 1e-4) << "frame 12 is Blender's frame 12";
  EXPECT_NEAR(r->frames[11].camera.eye[2], 8.130353, 1e-4);
  EXPECT_NEAR(r->frames[23].camera.eye[0], 8, 1e-4);
  EXPECT_EQ(r->frames[11].camera.fov, 30) << "the camera table's other keys stand";
  r = evaluate_script(write("farm.lua", head + "camera { gltf = \"Camera\", fps = 12 }\nframes { first = 1, last = 12 }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_NEAR(r->frames[11].camera.eye[0], 8, 1e-4) << "at 12 fps frame 12 is the animation's end (1 s)";
  r = evaluate_script(write("farm.lua", head + "camera { gltf = \"Camera\", animation = false }\nframes { first = 1, last = 3 }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->frames[2].camera.eye, r->camera.eye) << "held at rest";
  EXPECT_EQ(error_of(head + "camera { gltf = \"Camera\" }\nframes { first = 1, last = 3, camera = function(f) return { fov = f } end }\n" + net),
            "farm.lua:4: camera: the scene file animates camera 'Camera', and frames { camera } moves it too: give the "
            "camera animation = false to follow the function");
  EXPECT_EQ(error_of(head + "camera { fps = 24 }\n" + net),
            "farm.lua:3: camera: fps is for a camera the scene file animates (gltf = ...)");
}

TEST_F(ScriptTest, FramesMakeAJob) {
  const std::string net = "local direct = lightop \"direct\" { }\nrenderers { count = 1, lighting = direct }\n";
  const std::string head = "scene { builtin = \"cornell\" }\nimage { output = \"t.####.png\" }\n";
  auto r = evaluate_script(write("farm.lua", head + "camera { fov = 30 }\n"
                                 "frames { first = 2, last = 8, step = 3, camera = function(f) return { eye = {f, 0, -800} } end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames.size(), 3u);
  EXPECT_EQ(r->frames[2].number, 8);
  EXPECT_EQ(r->frames[2].output, "t.0008.png");
  EXPECT_EQ(r->frames[2].camera.eye, (std::array<double, 3>{8, 0, -800}));
  EXPECT_EQ(r->frames[2].camera.fov, 30) << "the camera table's other keys stand";
  ScriptOptions o;
  o.frames = {5};
  r = evaluate_script(write("farm.lua", head + "camera { keys = { {frame = 1, eye = {0, 0, -800}}, {frame = 9, eye = {80, 0, -800}} } }\n"
                                 "frames { first = 1, last = 9 }\n" + net), o);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames.size(), 9u);
  EXPECT_TRUE(r->frames[4].selected);
  EXPECT_FALSE(r->frames[3].selected);
  EXPECT_NEAR(r->frames[4].camera.eye[0], 40, 1e-9);
  EXPECT_TRUE(r->job.declared);
  // Without frames { }: one frame, no job.
  r = evaluate_script(write("farm.lua", kCornell));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->frames.empty());

  EXPECT_EQ(error_of(head + "frames { first = 1, last = 3 }\nframes { }\n" + net), "farm.lua:4: frames is declared twice");
  EXPECT_EQ(error_of(head + "frames { first = 3, last = 1 }\n" + net), "farm.lua:3: frames: last (1) comes before first (3)");
  EXPECT_EQ(error_of(head + "frames { last = 3, camera = 5 }\n" + net), "farm.lua:3: frames: camera must be a function of the frame number");
  EXPECT_EQ(error_of(head + "frames { last = 3, camera = function(f) return f end }\n" + net),
            "farm.lua:3: frames: the camera function returned a number for frame 1, not a camera table");
  EXPECT_EQ(error_of(head + "frames { last = 3, camera = function(f) return { eye = {0, 0, 0}, at = {0, 0, 0} } end }\n" + net),
            "farm.lua:3: frames: the camera function's table for frame 1: camera: eye and at are the same point");

  // frames { materials }: each frame's changes, read as material { } reads them, in name order.
  r = evaluate_script(write("farm.lua", head + "frames { last = 3, materials = function(f)\n"
                                 "  if f == 1 then return {} end\n"
                                 "  return { white = { kd = {0.1 * f, 0.1, 0.1} }, light = { emission = {f, f, f} } }\n"
                                 "end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames.size(), 3u);
  EXPECT_TRUE(r->frames[0].materials.empty());
  ASSERT_EQ(r->frames[2].materials.size(), 2u);
  EXPECT_EQ(r->frames[2].materials[0].find("name")->as_string(), "light");
  EXPECT_EQ(r->frames[2].materials[0].find("emission")->as_array()[0].as_double(), 3);
  EXPECT_EQ(r->frames[2].materials[1].find("name")->as_string(), "white");
  // A script light by its name.
  r = evaluate_script(write("farm.lua", head + "light { name = \"lamp\", sphere = {0, 500, 0}, radius = 20, radiance = {1, 1, 1} }\n"
                                 "frames { last = 2, materials = function(f) return { lamp = { emission = {f, f, f} } } end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->frames[1].materials[0].find("name")->as_string(), "lamp");
  // frames { lights }: a named point light, as the index-th of the script's point lights; it is no material.
  r = evaluate_script(write("farm.lua", head + "light { point = {0, 400, 0}, intensity = {1, 1, 1} }\n"
                                 "light { name = \"bulb\", point = {0, 500, 0}, intensity = {1, 1, 1} }\n"
                                 "frames { last = 2, lights = function(f) return { bulb = { point = {f, 500, 0} } } end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames[1].materials.size(), 1u);
  EXPECT_EQ(r->frames[1].materials[0].find("name")->as_string(), "bulb");
  EXPECT_EQ(r->frames[1].materials[0].find("light")->find("index")->as_int(), 1);
  EXPECT_EQ(r->frames[1].materials[0].find("light")->find("of")->as_int(), 2);
  EXPECT_EQ(r->frames[1].materials[0].find("light")->find("point")->as_array()[0].as_double(), 2);
  EXPECT_EQ(r->frames[1].materials[0].find("light")->find("intensity"), nullptr);
  EXPECT_EQ(error_of(head + "light { name = \"bulb\", point = {0, 500, 0}, intensity = {1, 1, 1} }\n"
                     "frames { last = 2, materials = function(f) return { bulb = { emission = {f, f, f} } } end }\n" + net),
            "farm.lua:4: material 'bulb' is not in the scene (its materials: white, red, green, light)");
  EXPECT_EQ(error_of(head + "light { name = \"bulb\", point = {0, 500, 0}, intensity = {1, 1, 1} }\n"
                     "frames { last = 2, lights = function(f) return { bulb = { intensity = {-1, 0, 0} } } end }\n" + net),
            "farm.lua:4: frames: the lights function's table for frame 1, point light 'bulb': intensity must be between 0 "
            "and 1e9 in each channel");
  EXPECT_EQ(error_of(head + "light { name = \"bulb\", point = {0, 500, 0}, intensity = {1, 1, 1} }\n"
                     "frames { last = 2, lights = function(f) return { bulb = { radiance = {1, 1, 1} } } end }\n" + net),
            "farm.lua:4: frames: the lights function's table for frame 1, point light 'bulb' gives neither point nor intensity");
  EXPECT_EQ(error_of(head + "light { name = \"white\", sphere = {0, 500, 0}, radius = 20, radiance = {1, 1, 1} }\n" + net),
            "farm.lua:3: light: name 'white' is a material of the scene already");
  EXPECT_EQ(error_of(head + "light { name = \"a\", sphere = {0, 500, 0}, radius = 20, radiance = {1, 1, 1} }\n"
                     "light { name = \"a\", sphere = {0, 400, 0}, radius = 20, radiance = {1, 1, 1} }\n" + net),
            "farm.lua:4: light: name 'a' is given twice");
  // frames { sun }: each frame's sun, read as sun { } reads it, after that frame's materials.
  r = evaluate_script(write("farm.lua", head + "sun { direction = {0, 1, 0}, irradiance = {1, 1, 1} }\n"
                                 "frames { last = 2, materials = function(f) return { light = { emission = {f, f, f} } } end,\n"
                                 "  sun = function(f) return { direction = {f, 1, 0}, irradiance = {2, 2, 2} } end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames[1].materials.size(), 2u);
  EXPECT_EQ(r->frames[1].materials[0].find("name")->as_string(), "light");
  EXPECT_EQ(r->frames[1].materials[1].find("name")->as_string(), "sun");
  EXPECT_EQ(r->frames[1].materials[1].find("sun")->find("direction")->as_array()[0].as_double(), 2);
  EXPECT_EQ(error_of(head + "frames { last = 3, sun = function(f) return { irradiance = {1, 1, 1} } end }\n" + net),
            "farm.lua:3: frames: frame 1: sun needs a direction = {x, y, z} (towards the sun)");
  EXPECT_EQ(error_of(head + "frames { last = 3, sun = function(f) return f end }\n" + net),
            "farm.lua:3: frames: the sun function returned a number for frame 1, not a sun table");
  // frames { environment }: the keys a frame gives, after the sun.
  r = evaluate_script(write("farm.lua", head + "environment { radiance = {1, 1, 1} }\n"
                                 "frames { last = 2, environment = function(f) return { rotation = 30 * f, intensity = f } end }\n" + net));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->frames[1].materials.size(), 1u);
  EXPECT_EQ(r->frames[1].materials[0].find("name")->as_string(), "environment");
  EXPECT_EQ(r->frames[1].materials[0].find("environment")->find("rotation")->as_double(), 60);
  EXPECT_EQ(r->frames[1].materials[0].find("environment")->find("intensity")->as_double(), 2);
  EXPECT_EQ(r->frames[1].materials[0].find("environment")->find("radiance"), nullptr);
  EXPECT_EQ(error_of(head + "frames { last = 3, environment = function(f) return { map = \"sky.exr\" } end }\n" + net),
            "farm.lua:3: frames: frame 1: environment: a frame cannot change the map (it is shipped with the scene once): "
            "declare it with environment { map = ... } and change its intensity or rotation");
  EXPECT_EQ(error_of(head + "frames { last = 3, environment = function(f) return {} end }\n" + net),
            "farm.lua:3: frames: frame 1: environment: a frame's table gives its intensity, rotation or radiance");
  EXPECT_EQ(error_of(head + "frames { last = 3, environment = function(f) return { rotation = 400 } end }\n" + net).substr(0, 36),
            "farm.lua:3: frames: frame 1: environ");
  EXPECT_EQ(error_of(head + "frames { last = 3, materials = 5 }\n" + net),
            "farm.lua:3: frames: materials must be a function of the frame number");
  EXPECT_EQ(error_of(head + "frames { last = 3, materials = function(f) return f end }\n" + net),
            "farm.lua:3: frames: the materials function returned a number for frame 1, not a table of materials by name");
  EXPECT_EQ(error_of(head + "frames { last = 3, materials = function(f) return { glass = { kd = {1, 1, 1} } } end }\n" + net),
            "farm.lua:3: material 'glass' is not in the scene (its materials: white, red, green, light)");
  EXPECT_EQ(error_of(head + "frames { last = 3, materials = function(f) return { white = { kd = {f, 0, 0} } } end }\n" + net),
            "farm.lua:3: material 'white': kd must be between 0 and 1 in each channel");
  EXPECT_EQ(error_of(head + "frames { last = 3, materials = function(f) return { white = { shine = 1 } } end }\n" + net)
                .substr(0, 50),
            "farm.lua:3: frames: the materials function's table");
  EXPECT_EQ(error_of("scene { builtin = \"cornell\" }\nimage { output = \"t.png\" }\nframes { last = 3 }\n" + net),
            "farm.lua:3: image: output 't.png' has no #### where the frame number goes, so every frame of the job's 3 "
            "would write the same file (e.g. \"walk.####.png\")");
  EXPECT_EQ(error_of(head + "camera { keys = { {frame = 1}, {frame = 2, eye = {1, 0, -800}} } }\n" + net),
            "farm.lua:3: camera: keys need frames { first = ..., last = ... }, the frames to render");
  EXPECT_EQ(error_of(head + "camera { keys = 3 }\n" + net),
            "farm.lua:3: camera: keys must be a list of tables, each a frame and camera keys ({frame = 1, eye = ..., at = ...})");
  o.frames = {4};
  EXPECT_EQ(error_of(head + "frames { last = 3 }\n" + net, o),
            "farm.lua:3: --frames: frame 4 is not one of the script's frames (1-3)");
  EXPECT_EQ(error_of(kCornell, o), "farm.lua: --frames: the script declares no frames { } to choose from");
}

}  // namespace
}  // namespace lf
