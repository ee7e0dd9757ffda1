// Strategies against scripted fake replicas: no processes, no sockets.
#include "actors/runtime/scheduler.hpp"

#include <gtest/gtest.h>

#include <map>

namespace lf {

using S = Scheduler::Strategy;

TEST(Scheduler, RoundRobinCycles) {
  Scheduler s(S::round_robin, 3, 4);
  std::vector<size_t> order;
  for (int i = 0; i < 6; ++i) {
    size_t r = *s.pick();
    s.sent(r, 10);
    s.answered(r, 0);
    order.push_back(r);
  }
  EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 0, 1, 2}));
}

// partition { colocate = true }: a packet of one part's points goes to the least loaded live replica holding that
// part, whatever the strategy, and to any replica once none of those lives.
TEST(Scheduler, APartsPacketGoesToAReplicaHoldingThatPart) {
  Scheduler s(S::round_robin, 4, 8);
  for (size_t r = 0; r < 4; ++r) s.set_group(r, static_cast<int64_t>(r % 2));  // replicas 0, 2 hold part 0; 1, 3 part 1
  EXPECT_EQ(*s.pick(1), 1u);
  s.sent(1, 10);
  EXPECT_EQ(*s.pick(1), 3u);  // replica 1 is busier now
  s.sent(3, 10);
  s.sent(3, 10);
  EXPECT_EQ(*s.pick(1), 1u);
  EXPECT_EQ(*s.pick(0), 0u);
  s.lost(1);
  s.lost(3);
  const auto any = s.pick(1);
  ASSERT_TRUE(any.has_value());
  EXPECT_TRUE(*any == 0u || *any == 2u);
}

TEST(Scheduler, LeastLoadedSendsToTheShortestQueue) {
  Scheduler s(S::least_loaded, 3, 8);
  // Replicas report queues 5, 0, 2 on their last replies.
  for (size_t r = 0; r < 3; ++r) s.sent(r, 1);
  s.answered(0, 5);
  s.answered(1, 0);
  s.answered(2, 2);
  EXPECT_EQ(*s.pick(), 1u);
  // Packets out count too: give replica 1 three packets; replica 2 (2 queued, 0 out) is now lighter.
  for (int i = 0; i < 3; ++i) s.sent(1, 1);
  EXPECT_EQ(*s.pick(), 2u);
}

TEST(Scheduler, LeastLoadedPrefersThisHostOnATieButNotWhenItIsBusier) {
  Scheduler s(S::least_loaded, 3, 8);
  s.set_remote(0, true);
  s.set_remote(2, true);
  // All idle: the replica on this host, whatever the rotation says.
  EXPECT_EQ(*s.pick(), 1u);
  s.sent(1, 1);
  // One packet out at the local replica against none remotely: a tie once the remote penalty counts; still local.
  EXPECT_EQ(*s.pick(), 1u);
  s.sent(1, 1);
  // Two out: a remote replica is now lighter.
  const size_t r = *s.pick();
  EXPECT_TRUE(r == 0 || r == 2) << r;
  // Every replica remote (or none): plain least-loaded rotation, as before.
  Scheduler all(S::least_loaded, 2, 8);
  all.set_remote(0, true);
  all.set_remote(1, true);
  EXPECT_EQ(*all.pick(), 0u);
  all.sent(0, 1);
  EXPECT_EQ(*all.pick(), 1u);
}

// Replica 1 finishes a packet every tick, replica 0 every fourth; one packet arrives per tick. Returns how many
// packets each replica got.
// The cap is large, so what differs is the strategy, not the cap.
static std::map<size_t, int> simulate_slow_replica(S strategy) {
  Scheduler s(strategy, 2, 1000);
  std::map<size_t, int> count;
  for (int tick = 1; tick <= 400; ++tick) {
    size_t r = *s.pick();
    s.sent(r, 1);
    ++count[r];
    if (s.out(1) > 0) s.answered(1, static_cast<uint32_t>(s.out(1) - 1));
    if (tick % 4 == 0 && s.out(0) > 0) s.answered(0, static_cast<uint32_t>(s.out(0) - 1));
  }
  return count;
}

TEST(Scheduler, LeastLoadedFollowsASlowReplicasBacklog) {
  auto least = simulate_slow_replica(S::least_loaded);
  auto rr = simulate_slow_replica(S::round_robin);
  EXPECT_GE(least[1], 2.5 * least[0]);  // the fast replica takes most of the work
  EXPECT_LE(rr[1], 1.5 * rr[0]);        // round robin ignores speed until the slow one's cap fills
}

TEST(Scheduler, AReplicaThatStopsAnsweringGetsNoNewWork) {
  for (S strategy : {S::round_robin, S::least_loaded, S::random}) {
    Scheduler s(strategy, 3, 2, 7);
    std::map<size_t, int> count;
    for (int i = 0; i < 300; ++i) {
      size_t r = *s.pick();
      s.sent(r, 1);
      ++count[r];
      if (r != 2) s.answered(r, 0);  // replica 2 never answers
    }
    EXPECT_LE(count[2], 2) << "strategy " << static_cast<int>(strategy);  // only until its cap filled
    EXPECT_GT(count[0], 50);
    EXPECT_GT(count[1], 50);
  }
}

TEST(Scheduler, LostReplicasAreNeverPickedAndTheLastLossLeavesNothing) {
  Scheduler s(S::round_robin, 2, 4);
  s.lost(0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(*s.pick(), 1u);
  s.lost(1);
  EXPECT_EQ(s.live(), 0u);
  EXPECT_FALSE(s.pick().has_value());
}

TEST(Scheduler, RandomIsSeededAndSpreads) {
  Scheduler a(S::random, 4, 100, 42), b(S::random, 4, 100, 42);
  std::map<size_t, int> count;
  for (int i = 0; i < 400; ++i) {
    size_t r = *a.pick();
    EXPECT_EQ(r, *b.pick());
    ++count[r];
  }
  for (size_t r = 0; r < 4; ++r) EXPECT_GT(count[r], 60);
}

}  // namespace lf
