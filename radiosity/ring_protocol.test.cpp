// The ring-node protocol without processes: N protocols exchange their actions through an in-process network that
// delivers them in a random (seeded) order, with this test as the director. Whatever the order and the layout, the
// ring gives the serial solver's shooters and radiosities; and each state refuses what does not belong in it.
#include "radiosity/ring_protocol.hpp"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "render/scene/scene.hpp"

namespace lf::radiosity {
namespace {

using Clock = std::chrono::steady_clock;

struct Outcome {
  std::vector<uint32_t> shooters;
  std::map<uint32_t, std::vector<RGB>> radiosity;  // per patch, its leaf elements in creation order
  uint64_t lent = 0;
};

RingConfig config_of(Value::Map params) { return read_ring_config(ParamTable(std::move(params), "radiosity")); }

Outcome run(const Scene& scene, const RingConfig& config, unsigned seed) {
  auto plan = plan_ring(scene, config);
  EXPECT_TRUE(plan.ok());
  const int n = config.layout.nodes();
  std::vector<std::unique_ptr<RingNode>> nodes;
  std::vector<std::unique_ptr<RingNodeProtocol>> protocols;
  for (int i = 0; i < n; ++i) {
    nodes.push_back(std::make_unique<RingNode>(plan->mesh, plan->bsp, config.layout, i, plan->patches_of(i),
                                               config.solver, config.ring));
    protocols.push_back(std::make_unique<RingNodeProtocol>(*nodes.back(), plan->mesh, config));
  }
  struct Message {
    int from;
    RingAction action;
    std::optional<PollReply> poll_reply;  // set: the answer to `from`'s poll, on its way back
  };
  std::vector<Message> network;
  std::mt19937 rng(seed);
  auto post = [&](int from, std::vector<RingAction> actions) {
    for (auto& a : actions) network.push_back({from, std::move(a), std::nullopt});
  };
  std::map<int, ShooterReport> reports;
  Outcome out;
  int64_t iteration = -1;
  std::vector<int> results;
  auto now = Clock::now();
  for (int i = 0; i < n; ++i) post(i, protocols[static_cast<size_t>(i)]->start());
  for (int turn = 0; turn < 2000000 && static_cast<int>(results.size()) < n; ++turn) {
    now += std::chrono::milliseconds(1);
    if (!network.empty()) {
      const size_t pick = std::uniform_int_distribution<size_t>(0, network.size() - 1)(rng);
      Message m = std::move(network[pick]);
      network.erase(network.begin() + static_cast<ptrdiff_t>(pick));
      RingNodeProtocol& sender = *protocols[static_cast<size_t>(m.from)];
      switch (m.action.kind) {
        case RingAction::Kind::send:
          EXPECT_TRUE(protocols[static_cast<size_t>(m.action.to)]->on_packet(m.action.hop, std::move(m.action.packet),
                                                                             m.action.home).ok());
          break;
        case RingAction::Kind::poll:
          if (m.poll_reply) {
            sender.on_poll_reply(m.action.poll_ring, m.action.poll, std::move(*m.poll_reply), now);
          } else {
            m.poll_reply = protocols[static_cast<size_t>(m.action.to)]->on_poll(m.action.poll);
            out.lent += m.poll_reply->lent.size();
            network.push_back(std::move(m));
          }
          break;
        case RingAction::Kind::ask_shooter: {
          EXPECT_EQ(m.action.report.iteration, iteration);
          reports[m.from] = m.action.report;
          if (static_cast<int>(reports.size()) < n) break;
          // The director: the most powerful candidate, ties to the lower patch; done on convergence.
          Candidate best;
          double unshot = 0, emitted = 0;
          for (auto& [i, r] : reports) {
            unshot += r.unshot_power;
            emitted = r.emitted_power;
            if (r.candidate && r.candidate->beats(best)) best = *r.candidate;
          }
          reports.clear();
          std::optional<ShooterChoice> choice;
          if (!(unshot / emitted < config.solver.converge || best.patch == UINT32_MAX ||
                iteration + 1 >= config.solver.max_iterations)) {
            choice = ShooterChoice{++iteration, best.patch, best.unshot};
            out.shooters.push_back(best.patch);
          }
          for (int i = 0; i < n; ++i) {
            auto actions = protocols[static_cast<size_t>(i)]->on_shooter(choice);
            EXPECT_TRUE(actions.ok());
            post(i, std::move(*actions));
          }
          break;
        }
        case RingAction::Kind::send_result:
          results.push_back(m.from);
          sender.on_result_taken();
          break;
      }
    }
    // Every node makes progress, in a shuffled order.
    std::vector<int> order(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
    std::shuffle(order.begin(), order.end(), rng);
    for (int i : order) post(i, protocols[static_cast<size_t>(i)]->step(now));
  }
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(protocols[static_cast<size_t>(i)]->state(), RingNodeProtocol::State::done) << "node " << i;
    for (const auto& e : nodes[static_cast<size_t>(i)]->part().elements())
      if (e.leaf) out.radiosity[e.patch].push_back(e.radiosity);
  }
  return out;
}

TEST(RingProtocol, AnyDeliveryOrderGivesTheSerialSolversAnswer) {
  auto scene = Scene::builtin("cornell");
  ASSERT_TRUE(scene.ok());
  for (const char* balance : {"none", "static+dynamic"}) {
    for (auto [rings, length] : {std::pair{1, 1}, std::pair{1, 3}, std::pair{2, 2}}) {
      const RingConfig config = config_of(Value::Map{{"rings", rings}, {"ring_length", length}, {"balance", balance},
                                                     {"patch_size", 140.0}, {"max_iterations", 12},
                                                     {"subdivide", 0.15}, {"samples_per_packet", 8}});
      auto plan = plan_ring(*scene, config);
      ASSERT_TRUE(plan.ok());
      const SceneVisibility vis(plan->mesh);
      const auto serial = solve_serial(plan->mesh, config.solver, std::cref(vis));
      std::vector<uint32_t> shooters;
      for (const auto& it : serial.iterations) shooters.push_back(it.shooter);
      std::map<uint32_t, std::vector<RGB>> expected;
      for (const auto& e : serial.elements)
        if (e.leaf) expected[e.patch].push_back(e.radiosity);
      for (unsigned seed : {1u, 2u}) {
        const Outcome ring = run(*scene, config, seed);
        SCOPED_TRACE(std::to_string(rings) + "x" + std::to_string(length) + " " + balance + " seed " +
                     std::to_string(seed));
        EXPECT_EQ(ring.shooters, shooters);
        // With two rings and dynamic balancing, idle nodes do borrow: the lending path is part of what agrees.
        if (rings == 2 && std::string(balance) == "static+dynamic") {
          EXPECT_GT(ring.lent, 0u);
        }
        ASSERT_EQ(ring.radiosity.size(), expected.size());
        for (const auto& [patch, values] : expected) {
          ASSERT_EQ(ring.radiosity.at(patch).size(), values.size()) << "patch " << patch;
          for (size_t i = 0; i < values.size(); ++i)
            for (int c = 0; c < 3; ++c)
              ASSERT_NEAR(ring.radiosity.at(patch)[i][c], values[i][c], 1e-4 * std::max(1.0f, values[i][c]));
        }
      }
    }
  }
}

TEST(RingProtocol, EachStateRefusesWhatDoesNotBelongInIt) {
  auto scene = Scene::builtin("cornell");
  const RingConfig config = config_of(Value::Map{{"rings", 1}, {"ring_length", 2}, {"patch_size", 140.0}});
  auto plan = plan_ring(*scene, config);
  RingNode node(plan->mesh, plan->bsp, config.layout, 0, plan->patches_of(0), config.solver, config.ring);
  RingNodeProtocol p(node, plan->mesh, config);
  EXPECT_EQ(p.state(), RingNodeProtocol::State::configured);
  // A shooter before the node asked for one.
  EXPECT_EQ(p.on_shooter(ShooterChoice{0, 1, RGB{1, 1, 1}}).error().message,
            "a shooter arrived while the node was configured");
  auto asked = p.start();
  ASSERT_EQ(asked.size(), 1u);
  EXPECT_EQ(asked[0].kind, RingAction::Kind::ask_shooter);
  EXPECT_EQ(asked[0].report.iteration, -1);
  EXPECT_EQ(p.state(), RingNodeProtocol::State::awaiting);
  EXPECT_TRUE(p.start().empty());  // started once
  // A packet two shooters ahead is refused; one ahead waits in the inbox.
  SamplePacket early;
  early.iteration = 2;
  EXPECT_EQ(p.on_packet(Hop::visit, early, 1).error().message, "a packet of iteration 2 while this node is on 0");
  EXPECT_EQ(p.on_shooter(ShooterChoice{0, 100000, RGB{1, 1, 1}}).error().message,
            "the director chose a patch the mesh does not have");
  ASSERT_TRUE(p.on_shooter(ShooterChoice{0, 1, RGB{1, 1, 1}}).ok());
  EXPECT_EQ(p.state(), RingNodeProtocol::State::shooting);
  // Asked while busy, it lends; its ring's idle list stays empty.
  const PollReply lent = p.on_poll(PollRequest{0, {}});
  EXPECT_FALSE(lent.finished);
  const PollReply stale = p.on_poll(PollRequest{5, {}});
  EXPECT_TRUE(stale.lent.empty());
  EXPECT_FALSE(stale.finished);
  ASSERT_TRUE(p.on_shooter(std::nullopt).error().message.find("shooting") != std::string::npos);
}

}  // namespace
}  // namespace lf::radiosity
