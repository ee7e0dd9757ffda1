// Path-space accounting of whole networks, without Lua or a scene file: what each op counts, composed along the
// graph, against the lobes a scene has.
#include "farm/light_path_check.hpp"

#include <gtest/gtest.h>

#include "farm/builders.hpp"

namespace lf {
namespace {

int add(FarmSpec& s, const std::string& name, const std::string& kind, std::vector<int> inputs = {}, Value::Map params = {}) {
  const int line = static_cast<int>(s.actors.size()) + 1;
  return add_actor(s, ActorSpec{.name = name, .kind = kind, .params = std::move(params), .inputs = std::move(inputs),
                                .loc = {"farm.lua", line}});
}

SceneLobes lobes(std::initializer_list<Lobe> l) {
  SceneLobes s;
  s.lobes = Lobes::of(l);
  s.emits = true;
  for (Lobe x : l) s.materials[static_cast<int>(x)] = {std::string("m") + kLobeLetters[static_cast<int>(x)]};
  return s;
}

bool mentions(const std::vector<std::string>& lines, const std::string& text) {
  for (const auto& l : lines)
    if (l.find(text) != std::string::npos) return true;
  return false;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

// direct + a cache over a path tracer + glossy over the same + specular over the landing light: every path once.
FarmSpec complete_network() {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  const int paths = add(s, "paths", "pathtrace");
  const int indirect = add(s, "indirect", "irradiance", {paths});
  const int shiny = add(s, "shiny", "glossy", {paths});
  const int landing = add(s, "landing", "combine", {direct, indirect, shiny});
  const int chains = add(s, "chains", "specular", {landing});
  s.lighting = add(s, "lighting", "combine", {direct, indirect, shiny, chains});
  return s;
}

TEST(LightPathCheck, ACompleteNetworkPassesOnEveryLobe) {
  const FarmSpec s = complete_network();
  const auto report = check_light_paths(s, lobes({Lobe::diffuse, Lobe::glossy, Lobe::specular}));
  EXPECT_TRUE(report.errors.empty()) << joined(report.errors);
  EXPECT_TRUE(report.warnings.empty()) << joined(report.warnings);
}

TEST(LightPathCheck, DirectAloneLeavesOutIndirectLightAsAWarning) {
  FarmSpec s;
  s.lighting = add(s, "direct", "direct");
  auto report = check_light_paths(s, lobes({Lobe::diffuse, Lobe::glossy}));
  EXPECT_TRUE(report.errors.empty()) << joined(report.errors);
  ASSERT_EQ(report.warnings.size(), 2u) << joined(report.warnings);
  EXPECT_EQ(report.warnings[0], "farm.lua:1: the lighting network leaves out indirect light reflected by diffuse surfaces "
                                "(LDD, LGD, LDDD, and 59 more), on 'mD': no op computes it; a `irradiance (a cache over "
                                "the light leaving what it sees) or pathtrace` op would (farm { light_paths = \"partial\" } "
                                "says a network computes part of the light on purpose)");
  EXPECT_TRUE(mentions(report.warnings, "indirect light reflected by glossy lobes (LDG, LGG,")) << joined(report.warnings);
  // On a diffuse-only scene the glossy gap is not there.
  report = check_light_paths(s, lobes({Lobe::diffuse}));
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_TRUE(mentions(report.warnings, "(LDD, LDDD, LDDDD, and 2 more)")) << joined(report.warnings);
  // "complete" makes it an error; "partial" says it is meant; "off" checks nothing.
  s.light_paths = "complete";
  report = check_light_paths(s, lobes({Lobe::diffuse}));
  EXPECT_EQ(report.errors.size(), 1u);
  EXPECT_TRUE(report.warnings.empty());
  s.light_paths = "partial";
  report = check_light_paths(s, lobes({Lobe::diffuse}));
  EXPECT_TRUE(report.errors.empty() && report.warnings.empty());
}

// Lost Empire's network before glossy lobes had an op: on a scene whose materials have one, the L ... G paths are
// missing, and the check says which op supplies them.
TEST(LightPathCheck, ANetworkWithoutGlossyNamesTheMissingOp) {
  FarmSpec s = complete_network();
  s.actors[static_cast<size_t>(s.lighting)].inputs = {s.find("direct"), s.find("indirect"), s.find("chains")};
  s.actors[static_cast<size_t>(s.find("landing"))].inputs = {s.find("direct"), s.find("indirect")};
  auto report = check_light_paths(s, lobes({Lobe::diffuse, Lobe::specular}));
  EXPECT_TRUE(report.warnings.empty()) << joined(report.warnings);  // nothing glossy in the scene: complete
  report = check_light_paths(s, lobes({Lobe::diffuse, Lobe::glossy, Lobe::specular}));
  // Glossy points' indirect light, and the same seen in mirrors (chains that land on a glossy point).
  ASSERT_EQ(report.warnings.size(), 2u) << joined(report.warnings);
  EXPECT_TRUE(mentions(report.warnings, "leaves out light seen in mirrors and glass (LDGS, LGGS, LSGS,")) << report.warnings[0];
  EXPECT_TRUE(mentions(report.warnings, "leaves out indirect light reflected by glossy lobes (LDG, LGG, LSG,")) << report.warnings[1];
  EXPECT_TRUE(mentions(report.warnings, "on 'mG'")) << report.warnings[1];
  EXPECT_TRUE(mentions(report.warnings, "a `glossy")) << report.warnings[1];
}

// cornell_glass.lua as it was: its indirect cache saw `through` (light along mirror chains, L S+) and the renderers
// also got the caustic photon map (L S+ D): the caustics were counted twice, and the third bounce left out.
TEST(LightPathCheck, TwoInputsCarryingTheSameLightAreAnErrorAtTheirCombine) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  const int caustics = add(s, "caustics", "photonmap");
  const int through = add(s, "through", "specular", {direct});
  const int first = add(s, "first", "combine", {direct, through});
  const int bounce1 = add(s, "bounce1", "irradiance", {first});
  const int lit1 = add(s, "lit1", "combine", {direct, through, caustics, bounce1});
  const int indirect = add(s, "indirect", "irradiance", {lit1});
  const int landing = add(s, "landing", "combine", {direct, caustics, indirect});
  const int specular = add(s, "specular", "specular", {landing});
  s.lighting = add(s, "lighting", "combine", {direct, specular, caustics, indirect});
  const auto report = check_light_paths(s, lobes({Lobe::diffuse, Lobe::specular}));
  // Said once, where it begins (the ops above inherit it): lit1 gets L S D from both the photon map and the cache
  // over `first`.
  ASSERT_EQ(report.errors.size(), 1u) << joined(report.errors);
  EXPECT_EQ(report.errors[0], "farm.lua:6: 'lit1' counts light twice (LSD, LSSD, LSSSD, LSSSSD, and 1 more): its inputs "
                              "'caustics', 'bounce1' each compute LSD; each light path must come from one input only "
                              "(docs/lua-api.md, \"Light paths\")");
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_TRUE(mentions(report.warnings, "leaves out indirect light reflected by diffuse surfaces (LDDDD,")) << joined(report.warnings);
}

TEST(LightPathCheck, EmissionAnsweredToTheRenderersIsAnError) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  const int glow = add(s, "glow", "emission");
  s.lighting = add(s, "lighting", "combine", {direct, glow});
  const auto report = check_light_paths(s, lobes({Lobe::diffuse}));
  EXPECT_TRUE(mentions(report.errors, "farm.lua:3: 'lighting' answers with the shaded point's own emission (L)"))
      << joined(report.errors);
}

TEST(LightPathCheck, APoolCountsAsItsReplicaAndPlugInsAreNotChecked) {
  FarmSpec s;
  const int direct = add(s, "direct", "direct");
  PoolSpec pool;
  pool.op = direct;
  pool.replicas = 2;
  auto mux = replicate(s, pool);
  ASSERT_TRUE(mux.ok());
  s.lighting = *mux;
  auto report = check_light_paths(s, lobes({Lobe::diffuse}));
  EXPECT_TRUE(mentions(report.warnings, "leaves out indirect light reflected by diffuse surfaces")) << joined(report.warnings);

  FarmSpec p;
  const int d = add(p, "direct", "direct");
  const int tint = add(p, "tint", "exec", {d});
  p.actors[static_cast<size_t>(tint)].runtime["cmd"] = Value::Array{Value("python3")};
  p.lighting = tint;
  report = check_light_paths(p, lobes({Lobe::diffuse}));
  EXPECT_TRUE(report.errors.empty());
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_EQ(report.warnings[0], "farm.lua:2: the lighting network's light paths are not checked: 'tint' (exec) does not "
                                "say which light paths it returns");
}

// A cache the scene leaves nothing to serve is a warning at its line: the directional cache or an irradiance cache
// on a scene of mirrors and glass alone. With a diffuse lobe somewhere (glossy materials' too), nothing is said.
TEST(LightPathCheck, ACacheWithNothingToCacheIsAWarning) {
  FarmSpec s;
  s.light_paths = "partial";
  s.lighting = add(s, "paths", "pathtrace", {}, {{"directional_cache", true}});
  auto report = check_light_paths(s, lobes({Lobe::specular}));
  ASSERT_EQ(report.warnings.size(), 1u) << joined(report.warnings);
  EXPECT_TRUE(mentions(report.warnings, "farm.lua:1: 'paths' has directional_cache = true, but no material of the "
                                        "scene has a Lambert lobe"));
  EXPECT_TRUE(check_light_paths(s, lobes({Lobe::diffuse, Lobe::glossy})).warnings.empty());
  // Diffuse lobes that are all metal_rough materials' (glTF): the directional cache answers none of their rays.
  SceneLobes gltf = lobes({Lobe::diffuse, Lobe::glossy});
  gltf.elevation_weighted = gltf.materials[static_cast<int>(Lobe::diffuse)];
  EXPECT_TRUE(mentions(check_light_paths(s, gltf).warnings, "has directional_cache = true, but no material of the "
                                                             "scene has a Lambert lobe"));

  FarmSpec cache;
  cache.light_paths = "partial";
  cache.lighting = add(cache, "indirect", "irradiance", {add(cache, "direct", "direct")});
  report = check_light_paths(cache, lobes({Lobe::specular}));
  EXPECT_TRUE(mentions(report.warnings, "farm.lua:2: 'indirect' caches diffuse light, but no material of the scene "
                                        "reflects diffusely")) << joined(report.warnings);
  EXPECT_TRUE(check_light_paths(cache, lobes({Lobe::diffuse})).warnings.empty());
  // An irradiance cache serves metal_rough materials' diffuse lobes; a radiosity solution takes them for black.
  EXPECT_TRUE(check_light_paths(cache, gltf).warnings.empty()) << joined(check_light_paths(cache, gltf).warnings);
  FarmSpec ring;
  ring.light_paths = "partial";
  ring.lighting = add(ring, "solution", "radiosity");
  report = check_light_paths(ring, gltf);
  ASSERT_EQ(report.warnings.size(), 1u) << joined(report.warnings);
  EXPECT_TRUE(mentions(report.warnings, "farm.lua:1: 'solution' takes metal_rough materials for black ('mD')"));
  EXPECT_TRUE(check_light_paths(ring, lobes({Lobe::diffuse})).warnings.empty());
}

TEST(LightPathCheck, GraphArrowsSayWhatTheyCarry) {
  const FarmSpec s = complete_network();
  const auto carried = light_path_summaries(s);
  EXPECT_EQ(carried[static_cast<size_t>(s.find("direct"))], "L(D|G)");
  EXPECT_EQ(carried[static_cast<size_t>(s.find("indirect"))], "L(D|G|S)+D");
  EXPECT_EQ(carried[static_cast<size_t>(s.find("shiny"))], "L(D|G|S)+G");
  EXPECT_EQ(carried[static_cast<size_t>(s.find("lighting"))], "L(D|G|S)+");
  const std::string dot = to_dot(s);
  EXPECT_NE(dot.find("\"paths\" -> \"indirect\" [label=\"L(D|G|S)+\"]"), std::string::npos) << dot;
}

}  // namespace
}  // namespace lf
