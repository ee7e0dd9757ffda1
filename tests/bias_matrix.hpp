#pragma once
// The bias matrix: small scenes of every material kind, and how a network's image is compared with a converged
// path tracer's. Shared by tests/unbiased.test.cpp (48x48, in ctest) and bench/bias_bench.cpp (full size).
#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "render/images/image.hpp"

namespace lf::bias {

struct Scene {
  const char* name;
  std::string lines;  // scene, lights, materials, camera
};

// Diffuse (the Cornell box), mirror and glass (cornell_glass), glossy (McGuire's CornellBox-Glossy: a glossy sphere
// and box), glossy everywhere (its walls, floor and ceiling given a Phong lobe from the script), a floor both
// diffuse and a mirror, glTF's metal-roughness model on every surface, and rough glass.
// `mcguire`: the folder holding CornellBox-Glossy.obj.
inline std::vector<Scene> scenes(const std::string& mcguire) {
  const std::string cornell_camera = "camera { eye = {278, 273, -800}, at = {278, 273, 0}, fov = 39.3 }\n";
  const std::string glossy = "scene { file = \"" + mcguire + "CornellBox-Glossy.obj\" }\n"
                             "light { quad = {{-0.2, 1.57, 0.2}, {-0.2, 1.57, -0.2}, {0.2, 1.57, -0.2}, {0.2, 1.57, 0.2}}, "
                             "radiance = {17, 12, 4} }\n"
                             "camera { eye = {0, 1, 3.6}, at = {0, 1, 0}, fov = 38 }\n";
  std::string shiny_walls = glossy;
  for (const char* wall : {"leftWall", "rightWall", "floor", "ceiling", "backWall"})
    shiny_walls += std::string("material \"") + wall + "\" { type = \"glossy\", ks = {0.2, 0.2, 0.2}, ns = 40 }\n";
  // A floor that is diffuse and a mirror at once (MTL illum 3 with Kd): direct light and the caches take its Kd, the
  // specular op its mirror term, a photon map follows that term too.
  const std::string mirror_floor = glossy + "material \"floor\" { kd = {0.4, 0.4, 0.4}, mirror = {0.4, 0.4, 0.4} }\n";
  // glTF's microfacet model everywhere, as a glTF exporter writes a room: a rough gold sphere (much of its light
  // scattered more than once between microfacets), a blue dielectric box, a shiny grey floor and walls and ceiling
  // of their own colours under a rough coat. The caches light the bases and the gold's multiply scattered light.
  std::string microfacet = glossy +
                           "material \"sphere\" { metallic = 1, roughness = 0.8, base_color = {0.95, 0.8, 0.5} }\n"
                           "material \"shortBox\" { metallic = 0, roughness = 0.5, base_color = {0.2, 0.4, 0.8} }\n"
                           "material \"floor\" { metallic = 0, roughness = 0.2, base_color = {0.7, 0.7, 0.7} }\n";
  for (const char* wall : {"leftWall", "rightWall", "ceiling", "backWall"})
    microfacet += std::string("material \"") + wall + "\" { metallic = 0, roughness = 0.6 }\n";
  // Rough glass (glTF's transmission): a clear sphere and a tinted, rougher box, light reaching the floor through
  // both (L G+ D) and the walls seen through them.
  const std::string rough_glass =
      glossy +
      "material \"sphere\" { transmission = 1, roughness = 0.3, base_color = {0.95, 0.95, 0.95} }\n"
      "material \"shortBox\" { transmission = 1, roughness = 0.6, base_color = {0.7, 0.85, 1.0} }\n";
  return {{"cornell", "scene { builtin = \"cornell\" }\n" + cornell_camera},
          {"cornell_glass", "scene { builtin = \"cornell_glass\" }\n" + cornell_camera},
          {"glossy", glossy},
          {"glossy_walls", shiny_walls},
          {"mirror_floor", mirror_floor},
          {"microfacet", microfacet},
          {"rough_glass", rough_glass}};
}

// A shipped network that says it computes all the light, and what it is run with besides the frame's size.
struct Network {
  const char* example;
  std::vector<std::string> sets;
};
inline std::vector<Network> networks() {
  return {{"pathtrace.lua", {"spp=256"}},
          {"cornell_glass.lua", {"spp=64", "photons=200000", "prepass=4000"}},
          {"lost_empire.lua", {"lighting=network", "spp=64", "exposure=0"}}};
}

// The example's text with its scene, material and camera statements replaced by the scene's; empty when the
// example has no scene statement to replace.
inline std::string with_scene(const std::string& example_path, const Scene& scene) {
  std::ifstream in(example_path);
  std::stringstream text;
  text << in.rdbuf();
  std::string out, line;
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
  return placed ? out : std::string();
}

struct Agreement {
  double mean;        // image / reference, over the pixels that do not see the light
  double block_rmse;  // over 8x8-pixel block means, relative to the reference's mean
};

// Pixels whose reference exceeds 1 in any channel see the light: the same emission in both, left out.
inline Agreement agreement(const Image& image, const Image& reference) {
  auto unlit = [&](size_t i) {
    return std::max({reference.pixels[i].x, reference.pixels[i].y, reference.pixels[i].z}) <= 1.0f;
  };
  double a = 0, b = 0;
  for (size_t i = 0; i < reference.pixels.size(); ++i)
    if (unlit(i)) a += average(image.pixels[i]), b += average(reference.pixels[i]);
  double se = 0;
  int blocks = 0;
  for (int by = 0; by + 8 <= reference.height; by += 8)
    for (int bx = 0; bx + 8 <= reference.width; bx += 8, ++blocks) {
      double x = 0, y = 0;
      for (int py = by; py < by + 8; ++py)
        for (int px = bx; px < bx + 8; ++px) {
          const size_t i = static_cast<size_t>(py) * static_cast<size_t>(reference.width) + static_cast<size_t>(px);
          if (unlit(i)) x += average(image.pixels[i]), y += average(reference.pixels[i]);
        }
      se += (x - y) * (x - y) / (64.0 * 64.0);
    }
  return {a / b, std::sqrt(se / blocks) / (b / static_cast<double>(reference.pixels.size()))};
}

}  // namespace lf::bias
