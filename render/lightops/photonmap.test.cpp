// photonmap against a closed form, and replicas against a single op.
#include <gtest/gtest.h>

#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/test_support.hpp"

namespace lf {
namespace {

// A floor mirror below a light sends a caustic onto a wall. The wall's caustic irradiance is what a *virtual*
// light — the real one mirrored in the floor — would give it, times the mirror's reflectance; `direct` computes
// that in a second scene with only the virtual light and no floor.
TEST(PhotonMap, FloorMirrorCausticMatchesTheMirroredLight) {
  const float ks = 0.9f, h = 1.0f;
  auto wall_scene = [&](bool mirrored) {
    Scene s;
    auto wall = s.add_material({"wall", {0.8f, 0.8f, 0.8f}, {}});
    auto light = s.add_material({"light", {}, {10, 10, 10}});
    s.add_quad({1, -3, -3}, {1, 3, -3}, {1, 3, 3}, {1, -3, 3}, wall);  // x = 1, facing -x
    if (!mirrored) {
      auto mirror = s.add_material(material_from_mtl("mirror", {}, {ks, ks, ks}, {}, 0, 1, 3));
      s.add_quad({-20, 0, -20}, {-20, 0, 20}, {0.99f, 0, 20}, {0.99f, 0, -20}, mirror);  // floor y = 0, up
      s.add_quad({-0.6f, h, -0.2f}, {-0.2f, h, -0.2f}, {-0.2f, h, 0.2f}, {-0.6f, h, 0.2f}, light);  // facing down
    } else {
      s.add_quad({-0.6f, -h, -0.2f}, {-0.6f, -h, 0.2f}, {-0.2f, -h, 0.2f}, {-0.2f, -h, -0.2f}, light);  // facing up
    }
    EXPECT_TRUE(s.finalize("caustic").ok());
    return s;
  };
  Scene real = wall_scene(false), virt = wall_scene(true);
  RayTracer real_tracer(real), virt_tracer(virt);
  ShadingPoints pts;
  for (int i = 0; i < 12; ++i)
    pts.push_back({1, 0.15f + 0.05f * (i % 4), -0.2f + 0.2f * (i / 4)}, {-1, 0, 0}, {-1, 0, 0}, 0, sample_key(i, 0), 0);

  LocalInputs none;
  auto d = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 100000}}, "d"));
  run_to_completion(d->setup(SceneContext{&virt, &virt_tracer}, none));
  std::vector<RGB> expected(pts.size());
  run_to_completion(d->shade(pts, expected, none));

  // Every estimate, and the precomputed irradiance at every 16th photon (Christensen), which a diffuse point takes
  // from its nearest such photon.
  for (int precompute : {0, 16}) {
    auto pm = create_lightop(*find_lightop_kind("photonmap"),
                             ParamTable(Value::Map{{"photons", 2000000}, {"k", 400}, {"max_radius", 0.3},
                                                   {"precompute", precompute}},
                                        "pm"));
    std::vector<std::pair<uint64_t, uint64_t>> reports;
    SceneContext ctx{&real, &real_tracer};
    ctx.progress = [&](const char* what, uint64_t done, uint64_t total) {
      EXPECT_STREQ(what, "shooting photons");
      reports.emplace_back(done, total);
    };
    run_to_completion(pm->setup(ctx, none));
    // Shooting said how far it was, in order, up to every photon.
    ASSERT_GE(reports.size(), 2u);
    for (size_t r = 1; r < reports.size(); ++r) EXPECT_GE(reports[r].first, reports[r - 1].first);
    EXPECT_EQ(reports.back(), (std::pair<uint64_t, uint64_t>{2000000, 2000000}));
    std::vector<RGB> caustic(pts.size());
    run_to_completion(pm->shade(pts, caustic, none));
    double sum = 0, ref = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      ASSERT_GT(expected[i].y, 0.0f);
      // One density estimate: k = 400 photons.
      EXPECT_NEAR(caustic[i].y / (ks * expected[i].y), 1.0, 0.2) << i << ", precompute " << precompute;
      sum += caustic[i].y;
      ref += ks * expected[i].y;
    }
    EXPECT_NEAR(sum / ref, 1.0, 0.05) << "precompute " << precompute;  // averaged over the points
    // Its figures: a balanced kd-tree of buckets of at most 16 photons has at least log2(stored / 16) + 1 levels;
    // every estimate's radius is at most max_radius.
    const Value st = pm->stats();
    const double stored = static_cast<double>(st.find("photons_stored")->as_int());
    EXPECT_GE(st.find("kd_depth")->as_int(), static_cast<int64_t>(std::ceil(std::log2(stored / 16))) + 1);
    EXPECT_LE(st.find("kd_depth")->as_int(), 64);
    EXPECT_GE(st.find("estimates")->as_int(), static_cast<int64_t>(pts.size()) / 2);
    EXPECT_GT(st.find("mean_radius")->as_double(), 0.0);
    EXPECT_LE(st.find("mean_radius")->as_double(), 0.3 + 1e-6);
  }
}

using test::Board;
using test::BoardExchange;

TEST(PhotonMap, ReplicasSharingTheirSharesAnswerLikeOneMap) {
  auto scene = Scene::builtin("cornell_glass");
  RayTracer tracer(*scene);
  ShadingPoints pts;
  for (int i = 0; i < 100; ++i)
    pts.push_back({120.0f + 1.3f * i, 0, 100.0f + 1.7f * i}, {0, 1, 0}, {0, 1, 0}, 0, sample_key(i, 0), 0);
  const Value::Map params{{"photons", 200000}};
  LocalInputs none;

  auto single = create_lightop(*find_lightop_kind("photonmap"), ParamTable(params, "pm"));
  run_to_completion(single->setup(SceneContext{&*scene, &tracer}, none));
  std::vector<RGB> one(pts.size());
  run_to_completion(single->shade(pts, one, none));

  Board board(3);
  std::vector<std::unique_ptr<LightOp>> replicas;
  std::vector<std::unique_ptr<BoardExchange>> exchanges;
  std::vector<Task> setups;
  for (int r = 0; r < 3; ++r) {
    replicas.push_back(create_lightop(*find_lightop_kind("photonmap"), ParamTable(params, "pm")));
    exchanges.push_back(std::make_unique<BoardExchange>(board, static_cast<size_t>(r)));
    setups.push_back(replicas.back()->setup(SceneContext{&*scene, &tracer, r, 3, exchanges.back().get()}, none));
  }
  for (auto& t : setups) {
    ASSERT_TRUE(t.done());
    t.rethrow_if_failed();
  }
  double caustic = 0;
  for (auto& rep : replicas) {
    std::vector<RGB> out(pts.size());
    run_to_completion(rep->shade(pts, out, none));
    EXPECT_TRUE(out == one) << "a replica's answer differs from the single map's";
  }
  for (const RGB& l : one) caustic += l.y;
  EXPECT_GT(caustic, 0.0) << "the floor near the glass sphere receives caustic light";
}

}  // namespace
}  // namespace lf
