// The connection table an actor builds from CONFIG: rows in CONFIG's order by group, pools over their replicas'
// rows, PEER_MOVED replacing one row's connection, and a connection that cannot be made failing CONFIG.
#include "actors/runtime/connections.hpp"

#include <gtest/gtest.h>

namespace lf {
namespace {

struct ConnectionsTest : ::testing::Test {
  std::vector<std::string> connected;  // NAME@ENDPOINT, as the connector was asked
  std::string refuse;                  // a name the connector cannot reach
  Connections table{[this](const std::string& name, const std::string& endpoint, const std::string&,
                           size_t window) -> Result<std::unique_ptr<wire::RequestClient>> {
    if (name == refuse) return make_error("cannot reach '" + name + "'");
    connected.push_back(name + "@" + endpoint);
    auto client = std::make_unique<wire::RequestClient>("me", name, window);
    if (auto st = client->connect(endpoint); !st) return st.error();
    return client;
  }};

  static InputSpec input(std::string name, int64_t window = 4, int64_t part = -1) {
    InputSpec in;
    in.name = name;
    in.endpoint = "inproc://" + name;
    in.window = window;
    in.part = part;
    in.lean = true;
    return in;
  }

  // One single input, a pool of two (one holding part 1), two geometry parts, one pool peer.
  ActorConfig config() {
    ActorConfig c;
    c.inputs.push_back(input("direct", 6));
    InputSpec pool;
    pool.name = "cache";
    pool.strategy = "least_loaded";
    pool.window = 8;
    pool.replicas = {input("cache.0"), input("cache.1", 4, 1)};
    c.inputs.push_back(pool);
    c.geometry = {input("part.0"), input("part.1")};
    c.pool = PoolPlace{};
    c.pool->peers = {input("sum.1")};
    return c;
  }
};

TEST_F(ConnectionsTest, RowsFollowConfigAndGroupsKeepTheirOrder) {
  ASSERT_TRUE(table.connect_config(config(), "tcp://127.0.0.1:*").ok());
  EXPECT_EQ(connected, (std::vector<std::string>{"direct@inproc://direct", "cache.0@inproc://cache.0",
                                                 "cache.1@inproc://cache.1", "part.0@inproc://part.0",
                                                 "part.1@inproc://part.1", "sum.1@inproc://sum.1"}));
  EXPECT_TRUE(table.take_changed());
  EXPECT_FALSE(table.take_changed());
  ASSERT_EQ(table.lighting().size(), 2u);
  EXPECT_EQ(table.lighting()[0].row, 0u);
  EXPECT_EQ(table.rows()[0].window, 6u);
  EXPECT_FALSE(table.lighting()[0].pool);
  ASSERT_TRUE(table.lighting()[1].pool);
  EXPECT_TRUE(table.lighting()[1].holds_parts);
  EXPECT_TRUE(table.lighting()[1].lean);
  EXPECT_EQ(table.count(Connections::Group::lighting), 3u);
  EXPECT_EQ(table.count(Connections::Group::geometry), 2u);
  EXPECT_EQ(table.in_group(Connections::Group::geometry, 1).name, "part.1");
  EXPECT_EQ(table.count(Connections::Group::pool_peer), 1u);
  EXPECT_EQ(table.in_group(Connections::Group::pool_peer, 0).name, "sum.1");
}

TEST_F(ConnectionsTest, PeerMovedReplacesOneRowAndKeepsItsWindow) {
  ASSERT_TRUE(table.connect_config(config(), "tcp://127.0.0.1:*").ok());
  table.take_changed();
  const wire::RequestClient* before = table.rows()[0].client.get();
  auto moved = table.reconnect("direct", "inproc://direct-again", "");
  ASSERT_TRUE(moved.ok() && *moved);
  EXPECT_NE(table.rows()[0].client.get(), before);
  EXPECT_EQ(table.rows()[0].window, 6u);
  EXPECT_EQ(connected.back(), "direct@inproc://direct-again");
  EXPECT_TRUE(table.take_changed()) << "the poller must be made again around the new socket";
  auto unknown = table.reconnect("nobody", "inproc://x", "");
  ASSERT_TRUE(unknown.ok());
  EXPECT_FALSE(*unknown) << "not an input: nothing to reconnect";
  EXPECT_EQ(connected.back(), "direct@inproc://direct-again");
}

// A pool with a subset connects to that many replicas; a lost one is replaced by the next spare in CONFIG's order,
// a lost spare is only forgotten, and a partitioned pool ignores the subset (its points need their part's holder).
TEST_F(ConnectionsTest, APoolConnectsItsSubsetAndASpareForEachLoss) {
  ActorConfig c;
  InputSpec pool;
  pool.name = "direct";
  pool.strategy = "least_loaded";
  pool.subset = 2;
  pool.replicas = {input("direct.3"), input("direct.4"), input("direct.0"), input("direct.1"), input("direct.2")};
  c.inputs.push_back(pool);
  ASSERT_TRUE(table.connect_config(c, "tcp://127.0.0.1:*").ok());
  EXPECT_EQ(connected, (std::vector<std::string>{"direct.3@inproc://direct.3", "direct.4@inproc://direct.4"}));
  Connections::LightingInput& in = table.lighting()[0];
  EXPECT_EQ(in.pool->live(), 2u);
  ASSERT_EQ(in.spares.size(), 3u);
  table.take_changed();

  EXPECT_EQ(table.replica_lost("direct.1"), &in) << "a spare";
  EXPECT_EQ(connected.size(), 2u);
  EXPECT_EQ(in.spares.size(), 2u);

  EXPECT_EQ(table.replica_lost("direct.4"), &in);
  EXPECT_EQ(connected.back(), "direct.0@inproc://direct.0");
  EXPECT_EQ(in.pool->live(), 2u);
  EXPECT_TRUE(table.take_changed()) << "the poller must be made again around the spare's socket";

  refuse = "direct.2";  // the last spare cannot be reached: the pool goes on with one
  EXPECT_EQ(table.replica_lost("direct.3"), &in);
  EXPECT_EQ(in.pool->live(), 1u);
  EXPECT_TRUE(in.spares.empty());
  EXPECT_EQ(table.replica_lost("nobody"), nullptr);

  Connections parted{[](const std::string& name, const std::string& endpoint, const std::string&, size_t window)
                         -> Result<std::unique_ptr<wire::RequestClient>> {
    auto client = std::make_unique<wire::RequestClient>("me", name, window);
    if (auto st = client->connect(endpoint); !st) return st.error();
    return client;
  }};
  c.inputs[0].replicas[1].part = 0;
  ASSERT_TRUE(parted.connect_config(c, "tcp://127.0.0.1:*").ok());
  EXPECT_EQ(parted.lighting()[0].pool->live(), 5u);
}

TEST_F(ConnectionsTest, AnInputThatCannotBeReachedFailsConfig) {
  refuse = "part.1";
  auto st = table.connect_config(config(), "tcp://127.0.0.1:*");
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message, "cannot reach 'part.1'");
}

}  // namespace
}  // namespace lf
