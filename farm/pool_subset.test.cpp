#include "farm/pool_subset.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace lf {
namespace {

TEST(PoolSubset, DerivedFromClientsReplicasAndWindow) {
  EXPECT_EQ(pool_subset(-1, 64, 192, 4), 8);   // twice the window
  EXPECT_EQ(pool_subset(-1, 64, 3, 4), 22);    // every replica needs a client: 64 / 3, rounded up
  EXPECT_EQ(pool_subset(-1, 6, 192, 4), 6);    // never more than there are
  EXPECT_EQ(pool_subset(-1, 64, 1, 4), 64);    // a lone client uses them all
  EXPECT_EQ(pool_subset(0, 64, 192, 4), 64);   // 0: all
  EXPECT_EQ(pool_subset(3, 64, 192, 4), 3);    // as asked
  EXPECT_EQ(pool_subset(99, 64, 192, 4), 64);
}

TEST(PoolSubset, EachClientsOrderHoldsEveryReplicaOnce) {
  for (int64_t client : {0, 1, 7, 191}) {
    auto order = pool_order(64, 8, client);
    ASSERT_EQ(order.size(), 64u);
    EXPECT_EQ(std::set<int64_t>(order.begin(), order.end()).size(), 64u);
  }
  const auto all = pool_order(5, 0, 3);
  EXPECT_EQ(all, (std::vector<int64_t>{0, 1, 2, 3, 4}));
}

// The subsets of all clients deal their connections evenly: every replica has clients x subset / replicas of them,
// rounded down or up, for pools that divide evenly and pools that do not.
TEST(PoolSubset, SubsetsCoverEveryReplicaEvenly) {
  struct Case { int64_t replicas, clients, window; };
  for (const Case c : {Case{64, 192, 4}, Case{64, 3, 4}, Case{10, 7, 1}, Case{13, 40, 2}, Case{100, 100, 4}}) {
    const int64_t k = pool_subset(-1, c.replicas, c.clients, c.window);
    std::vector<int64_t> clients_of(static_cast<size_t>(c.replicas), 0);
    for (int64_t client = 0; client < c.clients; ++client) {
      const auto order = pool_order(c.replicas, k, client);
      for (int64_t i = 0; i < k; ++i) ++clients_of[static_cast<size_t>(order[static_cast<size_t>(i)])];
    }
    const auto [lo, hi] = std::minmax_element(clients_of.begin(), clients_of.end());
    SCOPED_TRACE(testing::Message() << c.replicas << " replicas, " << c.clients << " clients, subset " << k);
    EXPECT_GE(*lo, 1);
    EXPECT_LE(*hi - *lo, 1);
    EXPECT_EQ(*lo, c.clients * k / c.replicas);
  }
}

TEST(PoolSubset, ReplicasOnTheClientsHostAreAddedAfterItsSubset) {
  // Replicas 0-7; 1, 5 and 6 share the client's host; the client was dealt 4 and 5.
  std::vector<bool> near(8, false);
  near[1] = near[5] = near[6] = true;
  auto order = pool_order(8, 2, 2);
  ASSERT_EQ(order, (std::vector<int64_t>{4, 5, 6, 7, 0, 1, 2, 3}));
  EXPECT_EQ(add_near_replicas(order, 2, near), 4);  // 5 was dealt; 6 and 1 are added, at most 2 of them
  EXPECT_EQ(order, (std::vector<int64_t>{4, 5, 6, 1, 7, 0, 2, 3}));
  auto all_near = pool_order(8, 2, 0);
  EXPECT_EQ(add_near_replicas(all_near, 2, std::vector<bool>(8, true)), 4);  // one host: twice the subset
  auto whole = pool_order(3, 2, 0);
  EXPECT_EQ(add_near_replicas(whole, 2, std::vector<bool>(3, true)), 0) << "every replica: connect all";
  auto none = pool_order(8, 0, 0);
  EXPECT_EQ(add_near_replicas(none, 0, near), 0);
}

}  // namespace
}  // namespace lf
