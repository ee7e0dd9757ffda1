// Every shipped network that says it computes all the light (light_paths not "partial") against a converged path
// tracer, on a matrix of small scenes: diffuse (the Cornell box), mirror and glass (cornell_glass), glossy (McGuire's
// CornellBox-Glossy: a glossy sphere and box) and glossy everywhere (its walls, floor and ceiling given a Phong lobe
// from the script), and a floor both diffuse and a mirror. Each network is the example's own text with the scene and camera lines swapped for the test's.
// A network that leaves a light path out or counts one twice is darker or brighter on average: the mean is held to
// 1 %, which a missing third bounce (~3 %) or a missing glossy bounce (~5-11 %) fails.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "render/images/image.hpp"
#include "tests/farm_harness.hpp"

namespace lf::test {
namespace {

const std::string kSource = LIGHTFARM_SOURCE_DIR;
const std::string kShared = kSource + "/../shared/scenes/cornell_box_mcguire/";
constexpr int kSize = 48;

struct TestScene {
  const char* name;
  std::string lines;  // scene, lights, materials, camera
};

std::vector<TestScene> scenes() {
  const std::string cornell_camera = "camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }\n";
  const std::string glossy = "scene { file = \"" + kShared + "CornellBox-Glossy.obj\" }\n"
                             "light { quad = {{-0.2, 1.57, 0.2}, {-0.2, 1.57, -0.2}, {0.2, 1.57, -0.2}, {0.2, 1.57, 0.2}}, "
                             "radiance = {17, 12, 4} }\n"
                             "camera { eye = {0, 1, 3.6}, at = {0, 1, 0}, fov = 38 }\n";
  std::string shiny_walls = glossy;
  for (const char* wall : {"leftWall", "rightWall", "floor", "ceiling", "backWall"})
    shiny_walls += std::string("material \"") + wall + "\" { type = \"glossy\", ks = {0.2, 0.2, 0.2}, ns = 40 }\n";
  // A floor that is diffuse and a mirror at once (MTL illum 3 with Kd): direct light and the caches take its Kd, the
  // specular op its mirror term, a photon map follows that term too.
  const std::string mirror_floor = glossy + "material \"floor\" { kd = {0.4, 0.4, 0.4}, mirror = {0.4, 0.4, 0.4} }\n";
  return {{"cornell", "scene { builtin = \"cornell\" }\n" + cornell_camera},
          {"cornell_glass", "scene { builtin = \"cornell_glass\" }\n" + cornell_camera},
          {"glossy", glossy},
          {"glossy_walls", shiny_walls},
          {"mirror_floor", mirror_floor}};
}

// The example's text with its scene, material and camera statements replaced by the scene's.
std::string with_scene(const std::string& example, const TestScene& scene) {
  std::ifstream in(kSource + "/examples/" + example);
  std::stringstream text;
  text << in.rdbuf();
  std::string out;
  std::string line;
  bool placed = false;
  static const std::regex replaced(R"(^(scene|camera|material)\s*[\{"].*)");
  while (std::getline(text, line)) {
    if (std::regex_match(line, replaced)) {
      if (!placed) out += scene.lines;
      placed = true;
      continue;
    }
    out += line + "\n";
  }
  EXPECT_TRUE(placed) << example << " has no scene line to replace";
  return out;
}

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

struct Agreement {
  double mean;        // network / reference, over the pixels that do not see the light
  double block_rmse;  // over 8x8-pixel block means, relative to the reference's mean
};

Agreement compare(const Image& image, const Image& reference) {
  auto lit = [&](size_t i) { return std::max({reference.pixels[i].x, reference.pixels[i].y, reference.pixels[i].z}) <= 1.0f; };
  double a = 0, b = 0;
  for (size_t i = 0; i < reference.pixels.size(); ++i)
    if (lit(i)) a += average(image.pixels[i]), b += average(reference.pixels[i]);
  double se = 0;
  int blocks = 0;
  for (int by = 0; by < kSize; by += 8)
    for (int bx = 0; bx < kSize; bx += 8, ++blocks) {
      double x = 0, y = 0;
      for (int py = by; py < by + 8; ++py)
        for (int px = bx; px < bx + 8; ++px) {
          const size_t i = static_cast<size_t>(py * kSize + px);
          if (lit(i)) x += average(image.pixels[i]), y += average(reference.pixels[i]);
        }
      se += (x - y) * (x - y) / (64.0 * 64.0);
    }
  return {a / b, std::sqrt(se / blocks) / (b / static_cast<double>(reference.pixels.size()))};
}

TEST_F(Unbiased, EveryCompleteNetworkMatchesThePathTracerOnEveryMaterial) {
  if (!fs::exists(kShared + "CornellBox-Glossy.obj")) GTEST_SKIP() << "no " << kShared;
  const std::string size = std::to_string(kSize);
  const std::vector<std::string> frame{"width=" + size, "height=" + size};
  struct Network {
    const char* example;
    std::vector<std::string> sets;
  };
  const std::vector<Network> networks{
      {"pathtrace.lua", {"spp=256"}},
      {"cornell_glass.lua", {"spp=64", "photons=200000", "prepass=4000"}},
      {"lost_empire.lua", {"lighting=network", "spp=64", "exposure=0"}},
  };
  for (const TestScene& scene : scenes()) {
    std::vector<std::string> ref_sets = frame;
    ref_sets.push_back("spp=4096");
    const Image reference = render(write(std::string(scene.name) + "_ref.lua", with_scene("pathtrace.lua", scene)),
                                   ref_sets, std::string(scene.name) + "_ref.exr");
    for (const Network& n : networks) {
      std::vector<std::string> sets = frame;
      sets.insert(sets.end(), n.sets.begin(), n.sets.end());
      const std::string tag = std::string(scene.name) + "_" + std::string(n.example).substr(0, std::string(n.example).find('.'));
      const Image image = render(write(tag + ".lua", with_scene(n.example, scene)), sets, tag + ".exr");
      const Agreement g = compare(image, reference);
      std::printf("%-14s %-18s mean %.4f  block RMSE %.4f\n", scene.name, n.example, g.mean, g.block_rmse);
      // Measured 0.9997-1.0054 (all twelve), block RMSE at most 0.028. While caches served the points they barely
      // missed from records valid under 2a and 4a (the old default, irradiance { relax = 4 }), the networks with
      // caches were 1.0-1.3 % bright: such points lie near what occludes them, where records farther off are
      // brighter.
      EXPECT_NEAR(g.mean, 1.0, 0.01) << tag;
      EXPECT_LT(g.block_rmse, 0.06) << tag;
    }
  }
}

}  // namespace
}  // namespace lf::test
