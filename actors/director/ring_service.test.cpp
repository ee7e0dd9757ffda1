// The ring service driven message by message: it answers only when every node reported, picks the most powerful
// candidate (ties to the lower patch), refuses a node on the wrong iteration, stops at max_iterations, and
// publishes the gathered solution on the exchange.
#include "actors/director/ring_service.hpp"

#include <gtest/gtest.h>

#include "actors/codecs/ring_codec.hpp"
#include "actors/director/service_test_support.hpp"
#include "farm/builders.hpp"
#include "radiosity/ply.hpp"
#include "render/scene/scene.hpp"

namespace lf {
namespace {

using test::RecordingOutbox;
using wire::Op;

struct RingFixture : ::testing::Test {
  FarmSpec spec;
  radiosity::RingConfig config;
  ExchangeService exchange;
  std::unique_ptr<RingService> ring;
  std::unique_ptr<Scene> scene;
  RecordingOutbox out;

  void SetUp() override {
    Value::Map params{{"rings", 1}, {"ring_length", 2}, {"patch_size", 140.0}, {"max_iterations", 2}};
    config = radiosity::read_ring_config(ParamTable(params, "radiosity"));
    ASSERT_TRUE(expand_ring(spec, config, params, "radiosity", {}, {}).ok());
    ring = std::make_unique<RingService>(spec, exchange, true, false);
    auto loaded = Scene::builtin("cornell");
    ASSERT_TRUE(loaded.ok());
    scene = std::make_unique<Scene>(std::move(*loaded));
    ASSERT_TRUE(ring->prepare(*scene).ok());
  }

  Value report(int64_t iteration, uint32_t patch, double power, uint32_t epoch = 0,
               std::optional<std::vector<radiosity::Element>> checkpoint = std::nullopt) {
    ring::ShooterReport r;
    r.epoch = epoch;
    r.checkpoint = std::move(checkpoint);
    r.iteration = iteration;
    r.unshot_power = 10;
    r.emitted_power = 100;
    r.candidate = radiosity::Candidate{patch, power, RGB{1, 1, 1}};
    return ring::encode_shooter_report(r);
  }
};

TEST_F(RingFixture, AnswersAllNodesOnceAllReportedWithTheBestCandidate) {
  EXPECT_TRUE(ring->active());
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 11, report(-1, 3, 2.0), out).ok());
  EXPECT_TRUE(out.take().empty());
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 12, report(-1, 1, 2.0), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  for (const auto& s : sent) {
    auto choice = ring::decode_shooter_choice(s.body, 1000);
    ASSERT_TRUE(choice.ok());
    ASSERT_TRUE(choice->has_value());
    EXPECT_EQ((*choice)->patch, 1u);  // equal power: the lower patch, whoever reported it
    EXPECT_EQ((*choice)->iteration, 0);
  }
  EXPECT_EQ(sent[0].id + sent[1].id, 23u);
}

TEST_F(RingFixture, ANodeOnTheWrongIterationOrAMalformedReportStopsTheFarm) {
  auto st = ring->on_request("radiosity.0.0", Op::ring_shooter, 1, report(4, 1, 1.0), out);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message, "ring node 'radiosity.0.0' reported iteration 4 while the ring is on -1");
  Value bad = report(-1, 1, 1.0);
  bad.as_map()["candidate"] = Value::Map{{"patch", 1}};
  st = ring->on_request("radiosity.0.1", Op::ring_shooter, 2, bad, out);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message, "ring node 'radiosity.0.1' sent a malformed candidate");
  EXPECT_FALSE(ring->on_request("intruder", Op::ring_shooter, 3, report(-1, 1, 1.0), out).ok());
}

TEST_F(RingFixture, StopsAtMaxIterationsThenPublishesTheGatheredSolution) {
  for (int64_t it = -1; it < 2; ++it) {
    ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 1, report(it, 2, 5.0), out).ok());
    ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 2, report(it, 4, 1.0), out).ok());
    auto sent = out.take();
    ASSERT_EQ(sent.size(), 2u);
    auto choice = ring::decode_shooter_choice(sent[0].body, 1000);
    ASSERT_TRUE(choice.ok());
    EXPECT_EQ(choice->has_value(), it < 1) << "iteration " << it;  // max_iterations = 2
  }
  // Node 0 sends every element (one per patch), node 1 none; fetching the solution waits until both did.
  auto plan = radiosity::plan_ring(*scene, config);
  ASSERT_TRUE(plan.ok());
  const radiosity::Mesh& plan_mesh = plan->mesh;
  std::vector<radiosity::Element> all;
  for (uint32_t p = 0; p < plan_mesh.patches.size(); ++p) {
    radiosity::Element e;
    e.patch = p;
    e.polygon = plan_mesh.patches[p].polygon;
    e.radiosity = plan_mesh.patches[p].emission;
    all.push_back(e);
  }
  ASSERT_TRUE(exchange.on_request("radiosity", Op::fetch, 9, Value::Map{{"key", "radiosity"}}, out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_result, 3, ring::encode_result(all, 0), out).ok());
  EXPECT_EQ(out.take().size(), 1u);  // the node's acknowledgement only
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_result, 4, ring::encode_result({}, 0), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 2u);  // node 1's acknowledgement, then the waiting fetch
  EXPECT_EQ(sent[1].actor, "radiosity");
  std::vector<radiosity::Element> expected = all;
  radiosity::add_ambient(plan_mesh, expected);
  EXPECT_TRUE(sent[1].body.find("blob")->as_bytes().data == radiosity::vertex_field(plan_mesh, expected).to_bytes());
  EXPECT_TRUE(ring->solved());
}

// A node lost mid-solve: a new epoch begins at once (old reports and results are dropped unanswered); once the
// restarted node is back, every node gets ROLLBACK to the last checkpoint with its own elements; their reports of
// that iteration then bring the same choice as before. Once the solution is in, a lost node needs no restart.
TEST_F(RingFixture, ALostNodeRollsTheRingBackToTheLastCheckpoint) {
  auto element = [](uint32_t patch, float b) {
    radiosity::Element e;
    e.patch = patch;
    e.polygon.count = 4;
    e.radiosity = {b, b, b};
    e.depth = 1;
    return e;
  };
  auto choice_of = [](const test::Sent& s) { return **ring::decode_shooter_choice(s.body, 1000); };
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 1, report(-1, 2, 5.0), out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 2, report(-1, 4, 1.0), out).ok());
  ASSERT_EQ(out.take().size(), 2u);
  // The end of iteration 0, with checkpoints.
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 3, report(0, 3, 4.0, 0, std::vector{element(3, 0.5f)}), out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 4, report(0, 5, 1.0, 0, std::vector{element(5, 0.25f)}), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(choice_of(sent[0]).iteration, 1);
  EXPECT_EQ(choice_of(sent[0]).patch, 3u);

  EXPECT_TRUE(ring->needs_restart("radiosity.0.1"));
  EXPECT_FALSE(ring->needs_restart("renderer-0"));
  ASSERT_TRUE(ring->on_lost("radiosity.0.1", "was killed", out).ok());
  EXPECT_EQ(ring->epoch(), 1u);
  // Node 0 finishes iteration 1 in the old epoch; node 1's successor reports too early: both dropped, no error.
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 5, report(1, 7, 3.0), out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 6, report(-1, 4, 1.0), out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_result, 7, ring::encode_result({}, 0), out).ok());
  EXPECT_TRUE(out.take().empty());

  ASSERT_TRUE(ring->on_rejoined("radiosity.0.1", out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(sent[i].told, wire::MsgType::rollback);
    auto rollback = ring::decode_rollback(sent[i].body, 1000);
    ASSERT_TRUE(rollback.ok());
    EXPECT_EQ(rollback->epoch, 1u);
    EXPECT_EQ(rollback->iteration, 0);
    ASSERT_EQ(rollback->elements.size(), 1u);
    EXPECT_EQ(rollback->elements[0].patch, i == 0 ? 3u : 5u);  // each node its own
    EXPECT_EQ(rollback->elements[0].depth, 1);
  }
  // Iteration 0 reported again in epoch 1: the same next shooter as before the loss.
  ASSERT_TRUE(ring->on_request("radiosity.0.0", Op::ring_shooter, 8, report(0, 3, 4.0, 1), out).ok());
  ASSERT_TRUE(ring->on_request("radiosity.0.1", Op::ring_shooter, 9, report(0, 5, 1.0, 1), out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(choice_of(sent[1]).iteration, 1);
  EXPECT_EQ(choice_of(sent[1]).patch, 3u);
  const Value figures = ring->report();
  ASSERT_EQ(figures.find("recoveries")->as_array().size(), 1u);
  EXPECT_EQ(figures.find("recoveries")->as_array()[0].find("resumed_from_iteration")->as_int(), 0);
  EXPECT_EQ(figures.find("checkpoints")->as_int(), 1);
  EXPECT_EQ(figures.find("shooters")->as_array().size(), 2u);  // iterations 0 and 1, the latter chosen twice
}

}  // namespace
}  // namespace lf
