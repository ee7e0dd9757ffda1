// Lights learned where the camera looks (render/lights/light_selection.hpp): the pre-pass finds which lights a point can
// see, the mixture picks lights with the probabilities it reports (and that MIS is given), direct light through it
// still matches the closed form, with less noise than the tree alone when most lights are hidden.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

#include "render/tracing/camera.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

using test::form_factor;

constexpr int kLamps = 48;
constexpr float kWall = 8.5f;  // the wall's plane: lamps beyond it light nothing the camera sees

// A long white floor (x from 0 to 24) under a row of small lamps at height 2, facing down, every 0.5 units, and a
// wall at x = 8.5 up to the lamps' height: from the floor before the wall only the 17 lamps before it can be seen.
// The 31 behind it, in the next room, are 8 times as bright, so the tree, which knows nothing of walls, sends them
// most of its samples. A point light before the wall too. The camera looks down at the floor before the wall.
struct WalledCorridor {
  Scene scene;
  std::vector<std::vector<Vec3>> seen_lamps;
  std::vector<size_t> hidden;  // lights behind the wall (Scene's numbering)
  Camera camera{CameraSpec{{4, 5, 4}, {4, 0, 0}, {0, 1, 0}, 60}, 64, 48};
  WalledCorridor() {
    const auto floor = scene.add_material({"floor", {1, 1, 1}, {}});
    const auto lamp = scene.add_material({"lamp", {0, 0, 0}, {5, 5, 5}});
    const auto bright = scene.add_material({"bright lamp", {0, 0, 0}, {40, 40, 40}});
    scene.add_quad({0, 0, -4}, {0, 0, 4}, {24, 0, 4}, {24, 0, -4}, floor);
    scene.add_quad({kWall, 0, -20}, {kWall, 2, -20}, {kWall, 2, 20}, {kWall, 0, 20}, floor);
    for (int i = 0; i < kLamps; ++i) {
      const float x0 = 0.2f + 0.5f * static_cast<float>(i), x1 = x0 + 0.1f;
      const Vec3 a{x0, 2, -0.05f}, b{x1, 2, -0.05f}, c{x1, 2, 0.05f}, d{x0, 2, 0.05f};
      scene.add_quad(a, b, c, d, x1 < kWall ? lamp : bright);
      if (x1 < kWall) seen_lamps.push_back({a, b, c, d});
    }
    scene.add_point_light({3, 1.5f, 1}, {2, 2, 2});
    EXPECT_TRUE(scene.finalize("walled corridor").ok());
    for (size_t e = 0; e < scene.emitters().size(); ++e)
      if (scene.vertex(scene.emitters()[e], 0).x > kWall) hidden.push_back(e);
  }
  SceneContext context(const RayTracer& tracer) const {
    SceneContext ctx{&scene, &tracer};
    ctx.camera = &camera;
    ctx.width = 64;
    ctx.height = 48;
    return ctx;
  }
};

LightSelection learn(const WalledCorridor& c, const RayTracer& tracer, LightSelectionOptions o = {}) {
  LightSelection selection;
  run_to_completion(LightSelection::build(c.context(tracer), o, selection));
  return selection;
}

TEST(LightSelection, CellsLearnWhichLightsTheirPointsSee) {
  WalledCorridor c;
  RayTracer tracer(c.scene);
  const LightSelection selection = learn(c, tracer);
  ASSERT_GT(selection.cell_count(), 10u);
  // Some of the tree's pre-pass samples went through the wall (0.16 of them: the cells behind the wall see the
  // bright lamps, and cells far from it get few of their samples).
  EXPECT_GT(static_cast<double>(selection.blocked_rays()) / static_cast<double>(selection.shadow_rays()), 0.1);
  for (const Vec3 x : {Vec3{1.1f, 0, 0.3f}, Vec3{4.2f, 0, -0.6f}, Vec3{7.3f, 0, 0.2f}}) {
    const int32_t cell = selection.cell_of(x, {0, 1, 0});
    ASSERT_GE(cell, 0) << "no cell at x = " << x.x;
    double seen = 0, behind = 0;
    for (size_t l = 0; l < c.scene.emitters().size() + 1; ++l) {
      const bool is_hidden = std::find(c.hidden.begin(), c.hidden.end(), l) != c.hidden.end();
      (is_hidden ? behind : seen) += selection.probability(cell, l);
    }
    EXPECT_NEAR(seen, 1.0, 1e-5) << "x = " << x.x;
    EXPECT_EQ(behind, 0.0) << "x = " << x.x;
    // The same cell for the other side of the floor's plane is another cell (none: the camera never saw it).
    EXPECT_EQ(selection.cell_of(x, {0, -1, 0}), -1);
  }
  // A pure function of the scene, the camera and the options.
  const LightSelection again = learn(c, tracer);
  EXPECT_EQ(again.cell_count(), selection.cell_count());
  EXPECT_EQ(again.entry_count(), selection.entry_count());
  EXPECT_EQ(again.shadow_rays(), selection.shadow_rays());
}

// A pool's replicas learn a third of the cells each and exchange them: each ends with exactly what one process
// learning alone has.
TEST(LightSelection, ReplicasShareTheLearningAndEachHoldsWhatOneProcessLearns) {
  WalledCorridor c;
  RayTracer tracer(c.scene);
  const LightSelection alone = learn(c, tracer);
  constexpr int kReplicas = 3;
  test::Board board(kReplicas);
  std::vector<std::unique_ptr<test::BoardExchange>> exchanges;
  std::vector<LightSelection> learned(kReplicas);
  std::vector<uint64_t> learned_cells(kReplicas);  // how many cells each replica said it learns
  std::vector<Task> builds;
  for (int r = 0; r < kReplicas; ++r)
    exchanges.push_back(std::make_unique<test::BoardExchange>(board, static_cast<size_t>(r)));
  for (int r = 0; r < kReplicas; ++r) {
    SceneContext ctx = c.context(tracer);
    ctx.replica_index = r;
    ctx.replica_count = kReplicas;
    ctx.exchange = exchanges[static_cast<size_t>(r)].get();
    ctx.progress = [&learned_cells, r](const char*, uint64_t, uint64_t total) { learned_cells[static_cast<size_t>(r)] = total; };
    builds.push_back(LightSelection::build(ctx, {}, learned[static_cast<size_t>(r)]));
  }
  for (auto& b : builds) {
    ASSERT_TRUE(b.done());
    b.rethrow_if_failed();
  }
  const size_t lights = c.scene.emitters().size() + 1;
  for (int r = 0; r < kReplicas; ++r) {
    const LightSelection& s = learned[static_cast<size_t>(r)];
    EXPECT_LE(learned_cells[static_cast<size_t>(r)], (alone.cell_count() + kReplicas - 1) / kReplicas);
    ASSERT_EQ(s.cell_count(), alone.cell_count());
    EXPECT_EQ(s.entry_count(), alone.entry_count());
    EXPECT_EQ(s.shadow_rays(), alone.shadow_rays());
    EXPECT_EQ(s.blocked_rays(), alone.blocked_rays());
    for (int32_t cell = 0; cell < static_cast<int32_t>(s.cell_count()); ++cell)
      for (size_t l = 0; l < lights; ++l)
        ASSERT_EQ(s.probability(cell, l), alone.probability(cell, l)) << "replica " << r << ", cell " << cell;
  }
}

// Over a job's frames: extended to a second view, a selection learns the cells new to the second view, and those the
// second view sees with enough more points or around another centre (LightSelection::learns_again), as that view
// alone would; it keeps every other cell the first
// view learned as it was; the same view again learns nothing. Its bytes, restored, give the same answers; bytes it
// cannot use are refused and leave it as it was.
TEST(LightSelection, ACarriedSelectionKeepsItsCellsAndLearnsOnlyWhatTheNewViewAdds) {
  WalledCorridor c;
  RayTracer tracer(c.scene);
  const Camera moved{CameraSpec{{7, 5, 4}, {7, 0, 0}, {0, 1, 0}, 60}, 64, 48};
  const SceneContext first_view = c.context(tracer);
  SceneContext second_view = c.context(tracer);
  second_view.camera = &moved;
  LightSelection carried;
  run_to_completion(LightSelection::build(first_view, {}, carried));
  const LightSelection first = carried;
  const std::string first_state = carried.state();
  run_to_completion(carried.extend(second_view, {}));
  LightSelection second_alone;
  run_to_completion(LightSelection::build(second_view, {}, second_alone));
  ASSERT_GT(carried.cell_count(), first.cell_count());
  const size_t lights = c.scene.emitters().size() + c.scene.point_lights().size();
  auto same_cell = [&](const LightSelection& a, int32_t ca, const LightSelection& b, int32_t cb) {
    for (size_t l = 0; l < lights; ++l)
      if (a.probability(ca, l) != b.probability(cb, l)) return false;
    return true;
  };
  // Floor points and the wall's face towards the cameras.
  std::vector<std::pair<Vec3, Vec3>> points;
  for (float x = 0.05f; x < 16; x += 0.1f)
    for (float z = -3.9f; z < 4; z += 0.2f) points.push_back({{x, 0, z}, {0, 1, 0}});
  for (float y = 0.05f; y < 2; y += 0.1f)
    for (float z = -3.9f; z < 4; z += 0.2f) points.push_back({{kWall, y, z}, {-1, 0, 0}});
  int kept = 0, added = 0, relearned = 0, moved_only = 0, shared_but_learned_otherwise = 0;
  for (const auto& [x, n] : points) {
    const int32_t cell = carried.cell_of(x, n), before = first.cell_of(x, n), alone = second_alone.cell_of(x, n);
    if (before >= 0 && alone >= 0 &&
        LightSelection::learns_again(second_alone.cell_points(alone), second_alone.cell_centre(alone),
                                     first.cell_points(before), first.cell_centre(before), first.inverse_cell_size())) {
      ASSERT_GE(cell, static_cast<int32_t>(first.cell_count()))
          << "a cell seen with enough more points, or around another centre, is learned again";
      ASSERT_TRUE(same_cell(carried, cell, second_alone, alone));
      ++relearned;
      // Learned again for its centre alone: as many points as before, or fewer.
      moved_only += second_alone.cell_points(alone) < LightSelection::kRelearnPoints * first.cell_points(before);
    } else if (before >= 0) {
      ASSERT_EQ(cell, before) << "a learned cell moved";
      ASSERT_TRUE(same_cell(carried, cell, first, before)) << "a learned cell changed at " << x.x << ", " << x.z;
      ++kept;
      if (alone >= 0 && !same_cell(first, before, second_alone, alone)) ++shared_but_learned_otherwise;
    } else if (alone >= 0) {
      ASSERT_GE(cell, static_cast<int32_t>(first.cell_count()));
      ASSERT_TRUE(same_cell(carried, cell, second_alone, alone)) << "a new cell is not the view's at " << x.x;
      ++added;
    } else {
      ASSERT_EQ(cell, -1);
    }
  }
  EXPECT_GT(kept, 100);
  EXPECT_GT(added, 100);
  EXPECT_GT(relearned, 10);
  EXPECT_GT(moved_only, 0) << "no cell was learned again for where the view sees it";
  EXPECT_GT(shared_but_learned_otherwise, 0) << "the shared cells show nothing about whose points they keep";
  // The same view again: nothing left to learn.
  const uint64_t rays = carried.shadow_rays();
  const size_t cells = carried.cell_count();
  run_to_completion(carried.extend(second_view, {}));
  EXPECT_EQ(carried.shadow_rays(), rays);
  EXPECT_EQ(carried.cell_count(), cells);

  // As bytes: a later view's begin with the earlier's; restored on a selection of the first view, the same answers.
  const std::string state = carried.state();
  EXPECT_EQ(state.compare(0, first_state.size(), first_state), 0);
  LightSelection restored;
  run_to_completion(LightSelection::build(first_view, {}, restored));
  restored.restore(state, c.scene);
  EXPECT_EQ(restored.state(), state);
  EXPECT_EQ(restored.shadow_rays(), carried.shadow_rays());
  for (const auto& [x, n] : points) {
    const int32_t cell = carried.cell_of(x, n);
    ASSERT_EQ(restored.cell_of(x, n), cell);
    if (cell >= 0) {
      ASSERT_TRUE(same_cell(restored, cell, carried, cell));
    }
  }
  // Refusals leave the selection as it was.
  std::string unknown_light = state;
  const uint32_t far_light = static_cast<uint32_t>(lights) + 5;
  // The first cell's first light: after tag, options, counts, key, points, centre, environment and count.
  std::memcpy(unknown_light.data() + 71, &far_light, 4);
  for (const std::string& bad : {std::string("no selection"), state.substr(0, state.size() - 3), unknown_light}) {
    EXPECT_THROW(restored.restore(bad, c.scene, "direct"), LightOpError);
    EXPECT_EQ(restored.state(), state);
  }
  LightSelection other_share;
  LightSelectionOptions o;
  o.share = 0.3f;
  run_to_completion(LightSelection::build(first_view, o, other_share));
  try {
    other_share.restore(state, c.scene, "direct");
    FAIL() << "no error";
  } catch (const LightOpError& e) {
    EXPECT_NE(std::string(e.what()).find("direct: the kept learned lights were learned with other settings"), std::string::npos)
        << e.what();
  }
}

TEST(LightSelection, PicksFollowTheMixtureItReportsAndMisIsGivenTheSame) {
  WalledCorridor c;
  RayTracer tracer(c.scene);
  const LightSelection selection = learn(c, tracer);
  const Vec3 x{3.1f, 0, 0.3f}, n{0, 1, 0};
  const int32_t cell = selection.cell_of(x, n);
  ASSERT_GE(cell, 0);
  const size_t lights = c.scene.emitters().size() + 1;
  auto mixture = [&](size_t l) {
    return selection.share() * selection.probability(cell, l) +
           (1 - selection.share()) * c.scene.light_tree().probability(x, n, l);
  };
  double total = 0;
  for (size_t l = 0; l < lights; ++l) total += mixture(l);
  EXPECT_NEAR(total, 1.0, 1e-4);
  std::map<size_t, int> counts;
  Rng rng(5, 9);
  const int picks = 400000;
  for (int i = 0; i < picks; ++i) {
    size_t light = 0;
    float p = 0;
    ASSERT_TRUE(pick_light(c.scene, x, n, rng.uniform(), &selection, light, p, nullptr));
    ASSERT_NEAR(p, mixture(light), 1e-6f * std::max(1.0f, p));
    if (light < c.scene.emitters().size()) {
      // What a BSDF ray that hits this light is weighed against.
      const uint32_t tri = c.scene.emitters()[light];
      ASSERT_NEAR(light_pdf_area_at(c.scene, tri, x, n, LightPoint::area, 0, 0, &selection) * c.scene.area(tri), p,
                  1e-5f * p);
    }
    ++counts[light];
  }
  for (size_t l = 0; l < lights; ++l) {
    const double expected = mixture(l) * picks;
    EXPECT_NEAR(counts[l], expected, 5 * std::sqrt(expected) + 2) << "light " << l;
  }
}

std::vector<RGB> shade_direct(const WalledCorridor& c, const ShadingPoints& pts, const std::string& sampling,
                              int samples, bool with_camera = true) {
  RayTracer tracer(c.scene);
  return test::shade_direct(with_camera ? c.context(tracer) : SceneContext{&c.scene, &tracer}, pts, sampling, samples);
}

// Floor points before the wall: what the lamps before it give (white floor: L = sum Le F) plus the point light's
// I cos / d^2 / pi. Learned lights converge to it as the tree does, and with few samples are much less noisy.
TEST(LightSelection, DirectLightMatchesTheClosedFormWithLessNoiseThanTheTreeAlone) {
  WalledCorridor c;
  std::vector<Vec3> xs;
  for (int i = 0; i < 24; ++i) xs.push_back({0.3f + 0.33f * static_cast<float>(i), 0, 0.4f});
  auto expected = [&](Vec3 x) {
    double f = 0;
    for (const auto& lamp : c.seen_lamps) f += form_factor(x, {0, 1, 0}, lamp);
    const Vec3 d = Vec3{3, 1.5f, 1} - x;
    const double d2 = dot(d, d), cosine = d.y / std::sqrt(d2);
    return 5 * f + 2 * cosine / d2 / kPi;
  };
  ShadingPoints pts;
  for (size_t i = 0; i < xs.size(); ++i) pts.push_back(xs[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0));
  for (const char* sampling : {"tree", "learned"}) {
    const auto out = shade_direct(c, pts, sampling, 20000);
    for (size_t i = 0; i < xs.size(); ++i)
      EXPECT_NEAR(out[i].x, expected(xs[i]), 0.02 * expected(xs[i])) << sampling << " at x = " << xs[i].x;
  }
  // With 16 samples, over 16 seeds of each point: the relative RMS error (measured: tree 0.141, learned 0.064).
  auto rms_error = [&](const char* sampling) {
    double se = 0;
    int n = 0;
    for (uint32_t seed = 0; seed < 16; ++seed) {
      ShadingPoints few;
      for (size_t i = 0; i < xs.size(); ++i) few.push_back(xs[i], {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, seed));
      const auto out = shade_direct(c, few, sampling, 16);
      for (size_t i = 0; i < xs.size(); ++i, ++n) {
        const double e = out[i].x / expected(xs[i]) - 1;
        se += e * e;
      }
    }
    return std::sqrt(se / n);
  };
  const double tree = rms_error("tree"), learned = rms_error("learned");
  EXPECT_LT(learned, 0.6 * tree) << "tree " << tree << ", learned " << learned;
}

TEST(LightSelection, NeedsACameraAndSaysSo) {
  WalledCorridor c;
  ShadingPoints pts;
  pts.push_back({1, 0, 0}, {0, 1, 0}, {0, 1, 0}, 0, sample_key(0, 0));
  try {
    shade_direct(c, pts, "learned", 1, /*with_camera=*/false);
    FAIL() << "no error";
  } catch (const LightOpError& e) {
    EXPECT_NE(std::string(e.what()).find("light_sampling = \"learned\" needs the farm's camera"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lf

namespace lf {
namespace {

// Under a sky, a floor half covered by a roof with a lamp beneath it: under the roof the sky reaches few points and
// the lamp most, in the open the sky gives nearly everything. The cells learn the environment's share of their
// samples accordingly (mixed half and half with the default half), and direct light through the learned shares is
// what the default shares give.
TEST(LightSelection, CellsLearnHowMuchOfTheirLightIsTheSky) {
  Scene scene;
  const auto floor = scene.add_material({"floor", {0.8f, 0.8f, 0.8f}, {}});
  const auto lamp = scene.add_material({"lamp", {}, {200, 200, 200}});
  scene.add_quad({0, 0, -10}, {0, 0, 10}, {12, 0, 10}, {12, 0, -10}, floor);
  scene.add_quad({-1, 1, -10}, {4, 1, -10}, {4, 1, 10}, {-1, 1, 10}, floor);  // the roof, facing down
  scene.add_quad({1.9f, 0.95f, -0.1f}, {2.1f, 0.95f, -0.1f}, {2.1f, 0.95f, 0.1f}, {1.9f, 0.95f, 0.1f}, lamp);
  scene.set_environment(Environment(RGB{1, 1, 1}));
  ASSERT_TRUE(scene.finalize("half roofed").ok());
  ASSERT_FLOAT_EQ(scene.environment_share(), 0.5f);
  const Camera camera{CameraSpec{{-0.5f, 0.6f, 0}, {8, 0, 0}, {0, 1, 0}, 60}, 64, 48};
  RayTracer tracer(scene);
  SceneContext ctx{&scene, &tracer};
  ctx.camera = &camera;
  ctx.width = 64;
  ctx.height = 48;
  LightSelection selection;
  run_to_completion(LightSelection::build(ctx, {}, selection));
  const Vec3 up{0, 1, 0}, roofed{2, 0, 0}, open{7, 0, 0};
  ASSERT_GE(selection.cell_of(roofed, up), 0);
  ASSERT_GE(selection.cell_of(open, up), 0);
  const float under = environment_share_at(scene, roofed, up, &selection);
  const float outside = environment_share_at(scene, open, up, &selection);
  EXPECT_LT(under, 0.4f) << "under the roof the lamp gives most";
  EXPECT_GT(outside, 0.6f) << "in the open the sky gives most";
  EXPECT_LT(environment_share_at(scene, roofed, up, nullptr), 0.51f);
  // Unbiased either way: direct light at the two points, learned against the tree's default shares.
  ShadingPoints pts;
  for (int i = 0; i < 2; ++i) pts.push_back(i ? open : roofed, up, up, floor, sample_key(static_cast<uint64_t>(i), 0), 0);
  const auto learned = test::shade_direct(ctx, pts, "learned", 8192);
  const auto tree = test::shade_direct(ctx, pts, "tree", 8192);
  for (size_t i = 0; i < 2; ++i) EXPECT_NEAR(learned[i].x / tree[i].x, 1.0, 0.03) << "point " << i;
}

}  // namespace
}  // namespace lf
