// The built-in scenes: the Cornell box (with and without its glass sphere and mirror) and a furnished room.
#include "render/scene/scene.hpp"

namespace lf {

// The Cornell box as published by the Cornell Program of Computer Graphics (measured geometry, millimetres),
// with the usual RGB approximations of its measured reflectances and light.
// `glass`: the Cornell box with a glass sphere where the short block stood and a mirror for the tall block, for
// caustics on the floor.
static Scene cornell_box(bool glass) {
  Scene s;
  auto white = s.add_material({"white", {0.725f, 0.71f, 0.68f}, {}});
  auto red = s.add_material({"red", {0.63f, 0.065f, 0.05f}, {}});
  auto green = s.add_material({"green", {0.14f, 0.45f, 0.091f}, {}});
  auto light = s.add_material({"light", {0.78f, 0.78f, 0.78f}, {17.0f, 12.0f, 4.0f}});

  s.add_quad({552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}, white);                     // floor
  // The ceiling has a hole where the light sits (as the real box does): a light just below an unbroken ceiling
  // z-fights with it at camera distance in float precision.
  auto ceiling = [&](float x0, float x1, float z0, float z1) {
    s.add_quad({x1, 548.8f, z0}, {x1, 548.8f, z1}, {x0, 548.8f, z1}, {x0, 548.8f, z0}, white);
  };
  ceiling(0, 556.0f, 0, 227.0f);
  ceiling(0, 556.0f, 332.0f, 559.2f);
  ceiling(0, 213.0f, 227.0f, 332.0f);
  ceiling(343.0f, 556.0f, 227.0f, 332.0f);
  s.add_quad({549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}, white);  // back
  s.add_quad({0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}, green);                      // right
  s.add_quad({552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}, red);    // left
  // The light hangs 0.1 mm below the ceiling so the two never share a plane; it faces down.
  s.add_quad({343.0f, 548.7f, 227.0f}, {343.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 332.0f},
             {213.0f, 548.7f, 227.0f}, light);

  const float short_block[5][4][3] = {
      {{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}},
      {{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}},
      {{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}},
      {{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}},
      {{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}};
  const float tall_block[5][4][3] = {
      {{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}},
      {{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}},
      {{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}},
      {{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}},
      {{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}};
  const uint32_t tall_material =
      glass ? s.add_material(material_from_mtl("mirror", {}, {0.95f, 0.95f, 0.95f}, {}, 0, 1, 3)) : white;
  for (const auto* block : {short_block, tall_block}) {
    if (glass && block == short_block) continue;
    for (int f = 0; f < 5; ++f) {
      auto v = [&](int i) { return Vec3{block[f][i][0], block[f][i][1], block[f][i][2]}; };
      s.add_quad(v(0), v(1), v(2), v(3), block == tall_block ? tall_material : white);
    }
  }
  if (glass) {
    const uint32_t sphere = s.add_material(material_from_mtl("glass", {}, {}, {}, 0, 1.5f, 7));
    s.add_sphere({185.0f, 90.0f, 169.0f}, 90.0f, 4, sphere);
  }
  return s;
}

// A furnished room (metres, 6 x 3 x 5) for radiosity: walls, floor and ceiling facing in, a ceiling panel light,
// a table and two chairs, a sofa and a cabinet as boxes. Only quads, so that radiosity meshes it as authored.
static Scene furnished_room() {
  Scene s;
  const auto wall = s.add_material({"wall", {0.75f, 0.73f, 0.70f}, {}});
  const auto blue_wall = s.add_material({"blue wall", {0.30f, 0.42f, 0.65f}, {}});
  const auto floor = s.add_material({"floor", {0.55f, 0.42f, 0.30f}, {}});
  const auto wood = s.add_material({"wood", {0.45f, 0.30f, 0.18f}, {}});
  const auto fabric = s.add_material({"fabric", {0.65f, 0.12f, 0.10f}, {}});
  const auto light = s.add_material({"panel", {0.8f, 0.8f, 0.8f}, {12.0f, 11.0f, 9.0f}});
  auto face = [&](Vec3 o, Vec3 u, Vec3 v, uint32_t m) { s.add_quad(o, o + u, o + u + v, o + v, m); };
  // Outward faces of an axis-aligned box; boxes standing on the floor leave out their bottom.
  auto box = [&](Vec3 lo, Vec3 hi, uint32_t m) {
    const Vec3 d = hi - lo;
    face({hi.x, lo.y, lo.z}, {0, d.y, 0}, {0, 0, d.z}, m);
    face(lo, {0, 0, d.z}, {0, d.y, 0}, m);
    face({lo.x, hi.y, lo.z}, {0, 0, d.z}, {d.x, 0, 0}, m);
    if (lo.y > 0) face(lo, {d.x, 0, 0}, {0, 0, d.z}, m);
    face({lo.x, lo.y, hi.z}, {d.x, 0, 0}, {0, d.y, 0}, m);
    face(lo, {0, d.y, 0}, {d.x, 0, 0}, m);
  };
  face({0, 0, 0}, {0, 0, 5}, {6, 0, 0}, floor);
  face({0, 3, 0}, {6, 0, 0}, {0, 0, 5}, wall);
  face({0, 0, 0}, {0, 3, 0}, {0, 0, 5}, wall);
  face({6, 0, 0}, {0, 0, 5}, {0, 3, 0}, blue_wall);
  face({0, 0, 0}, {6, 0, 0}, {0, 3, 0}, wall);
  face({0, 0, 5}, {0, 3, 0}, {6, 0, 0}, wall);
  face({2.4f, 2.99f, 2.0f}, {1.2f, 0, 0}, {0, 0, 1.0f}, light);
  auto table = [&](float x, float z, float w, float d, float h) {
    box({x, h - 0.05f, z}, {x + w, h, z + d}, wood);
    for (float lx : {x + 0.03f, x + w - 0.09f})
      for (float lz : {z + 0.03f, z + d - 0.09f}) box({lx, 0, lz}, {lx + 0.06f, h - 0.05f, lz + 0.06f}, wood);
  };
  table(1.8f, 1.6f, 1.8f, 1.0f, 0.75f);
  for (float x : {2.0f, 3.0f}) {
    table(x, 2.9f, 0.45f, 0.45f, 0.47f);                         // seat on legs
    box({x, 0.47f, 3.3f}, {x + 0.45f, 1.0f, 3.35f}, wood);       // backrest
  }
  box({0.05f, 0, 1.2f}, {0.95f, 0.45f, 3.6f}, fabric);           // sofa
  box({0.05f, 0.45f, 1.2f}, {0.30f, 0.90f, 3.6f}, fabric);
  box({0.30f, 0.45f, 1.2f}, {0.95f, 0.65f, 1.4f}, fabric);
  box({0.30f, 0.45f, 3.4f}, {0.95f, 0.65f, 3.6f}, fabric);
  box({5.45f, 0, 0.8f}, {5.95f, 1.9f, 2.4f}, wood);              // cabinet
  box({4.2f, 0, 4.3f}, {5.6f, 0.5f, 4.9f}, wood);                // chest
  return s;
}

const std::vector<std::string>& Scene::builtin_names() {
  static const std::vector<std::string> names{"cornell", "cornell_glass", "room"};
  return names;
}

Result<Scene> Scene::builtin(const std::string& name) {
  auto s = builtin_unlit(name);
  if (!s) return s;
  if (auto st = s->finalize("built-in scene '" + name + "'"); !st) return st.error();
  return s;
}

Result<Scene> Scene::builtin_unlit(const std::string& name) {
  Scene s;
  if (name == "cornell" || name == "cornell_glass") {
    s = cornell_box(name == "cornell_glass");
  } else if (name == "room") {
    s = furnished_room();
  } else {
    std::string known;
    for (const auto& n : builtin_names()) known += (known.empty() ? "" : ", ") + n;
    return make_error("unknown built-in scene '" + name + "' (built-in scenes: " + known + ")");
  }
  return s;
}

}  // namespace lf
