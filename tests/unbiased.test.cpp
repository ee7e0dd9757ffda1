// Every shipped network that says it computes all the light (light_paths not "partial") against a converged path
// tracer, on the bias matrix (tests/bias_matrix.hpp: diffuse, mirror and glass, glossy, glossy everywhere, a floor
// both diffuse and a mirror). Each network is the example's own text with the scene and camera lines swapped for the
// test's; and the network `lightfarm scene` suggests for every lobe, pooled, its `direct` and `specular` at their
// defaults (MIS near the lights, 4 emission chains). A network that leaves a light path out or counts one twice is darker or brighter on average: the mean is
// held to 1 %, which a missing third bounce (~3 %) or a missing glossy bounce (~5-11 %) fails. bench/bias_bench runs
// the same matrix at full size.
#include <gtest/gtest.h>

#include "render/images/image.hpp"
#include "render/scene/scene_report.hpp"
#include "tests/bias_matrix.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kShared = kSource + "/../shared/scenes/cornell_box_mcguire/";
constexpr int kSize = 48;

class Unbiased : public FarmFixture {
 protected:
  Image render(const std::string& script, std::vector<std::string> sets, const std::string& out) {
    std::vector<std::string> args{"run", script, "--output", path(out), "--quiet"};
    for (const auto& s : sets) args.insert(args.end(), {"--set", s});
    auto r = run_lightfarm(args);
    EXPECT_EQ(r.status, 0) << out << ": " << r.err;
    EXPECT_EQ(r.err.find("leaves out"), std::string::npos) << out << ": " << r.err;
    expect_no_leftovers(r);
    auto img = read_image(path(out));
    return img.ok() ? *img : Image(kSize, kSize);
  }
};

TEST_F(Unbiased, EveryCompleteNetworkMatchesThePathTracerOnEveryMaterial) {
  if (!fs::exists(kShared + "CornellBox-Glossy.obj")) GTEST_SKIP() << "no " << kShared;
  const std::string size = std::to_string(kSize);
  const std::vector<std::string> frame{"width=" + size, "height=" + size};
  auto example = [&](const char* name, const bias::Scene& scene) {
    std::string text = bias::with_scene(kSource + "/examples/" + name, scene);
    EXPECT_FALSE(text.empty()) << name << " has no scene line to replace";
    return text;
  };
  for (const bias::Scene& scene : bias::scenes(kShared)) {
    std::vector<std::string> ref_sets = frame;
    ref_sets.push_back("spp=2048");
    const Image reference = render(write(std::string(scene.name) + "_ref.lua", example("pathtrace.lua", scene)),
                                   ref_sets, std::string(scene.name) + "_ref.exr");
    std::vector<bias::Network> networks = bias::networks();
    networks.push_back({"suggested", {"spp=64"}});
    for (const bias::Network& n : networks) {
      std::vector<std::string> sets = frame;
      sets.insert(sets.end(), n.sets.begin(), n.sets.end());
      const std::string tag = std::string(scene.name) + "_" + std::string(n.example).substr(0, std::string(n.example).find('.'));
      const std::string text =
          std::string(n.example) == "suggested"
              ? scene.lines + "image { width = param(\"width\", 48), height = param(\"height\", 48), spp = param(\"spp\", 64) }\n" +
                    complete_network_for(Lobes::all(), NetworkChoices{true, 2, false})
              : example(n.example, scene);
      const Image image = render(write(tag + ".lua", text), sets, tag + ".exr");
      const bias::Agreement g = bias::agreement(image, reference);
      std::printf("%-14s %-18s mean %.4f  block RMSE %.4f\n", scene.name, n.example, g.mean, g.block_rmse);
      // Measured against 2048-spp references 0.9959-1.0061 (all twenty-one), block RMSE at most 0.042 (4096 spp:
      // at most 0.028, 35 s more of CI; the reference's noise is in the block RMSE, hardly in the mean). While caches served the points they barely
      // missed from records valid under 2a and 4a (the old default, irradiance { relax = 4 }), the networks with
      // caches were 1.0-1.3 % bright: such points lie near what occludes them, where records farther off are
      // brighter.
      EXPECT_NEAR(g.mean, 1.0, 0.01) << tag;
      EXPECT_LT(g.block_rmse, 0.06) << tag;
    }
  }
}

// Rough glass as smooth as a pixel can tell (roughness 0.02) renders the smooth glass sphere of cornell_glass: the
// same caustic, the same box seen through it. A rough dielectric that reflected or refracted the wrong share, or bent
// light the wrong way, would differ by more than the noise.
TEST_F(Unbiased, NearlySmoothRoughGlassRendersAsGlass) {
  const std::string size = std::to_string(kSize);
  const std::vector<std::string> sets{"width=" + size, "height=" + size, "spp=2048"};
  const std::string camera = "camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }\n";
  const std::string base = bias::with_scene(kSource + "/examples/pathtrace.lua",
                                            {"glass", "scene { builtin = \"cornell_glass\" }\n" + camera});
  ASSERT_FALSE(base.empty());
  const Image glass = render(write("glass.lua", base), sets, "glass.exr");
  const std::string rough_text = base + "material \"glass\" { transmission = 1, roughness = 0.02, base_color = {1, 1, 1} }\n";
  const Image rough = render(write("rough.lua", rough_text), sets, "rough.exr");
  const bias::Agreement g = bias::agreement(rough, glass);
  std::printf("rough glass at 0.02 / glass: mean %.4f  block RMSE %.4f\n", g.mean, g.block_rmse);
  // Measured 0.9993 and 0.0018; at roughness 0.25 the view through the sphere blurs: 0.9951 and 0.0129.
  EXPECT_NEAR(g.mean, 1.0, 0.01);
  EXPECT_LT(g.block_rmse, 0.006);
}

}  // namespace
}  // namespace lf::test
