// PoolClient over inproc:// without processes: the test plays the replicas (router sockets that hold what reaches
// them) and answers by hand. Then a whole actor runtime whose input is a pool (CONFIG inputs[0].pool): its requests
// reach the replicas directly, a PEER_DOWN moves a lost replica's work to the other, and STATS say who got what.
#include "actors/runtime/pool_client.hpp"

#include <gtest/gtest.h>

#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/lean_points.hpp"
#include "actors/runtime/inproc_actor.hpp"

namespace lf {
namespace {

using wire::MsgType;

struct Held {
  std::string peer;
  uint64_t id;
  size_t n;
  float first_k;  // the first point's k, to tell pieces apart
};

ShadingPoints points(size_t n, size_t first_k = 0) {
  ShadingPoints pts;
  for (size_t i = 0; i < n; ++i) pts.push_back({1, 1, 1}, {0, 1, 0}, {0, 1, 0}, 0, first_k + i);
  return pts;
}

class Replicas {
 public:
  explicit Replicas(size_t count) {
    static int n = 0;
    ++n;
    for (size_t r = 0; r < count; ++r) {
      sockets.push_back(std::make_unique<wire::Socket>(wire::Socket::Kind::router));
      endpoints.push_back(*sockets.back()->bind("inproc://pool-replica-" + std::to_string(n) + "-" + std::to_string(r)));
    }
  }
  // Everything that reached replica r within `seconds`, while `poll` keeps the client reading.
  std::vector<Held> drain(size_t r, const std::function<void()>& poll, double seconds = 0.2) {
    std::vector<Held> got;
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      poll();
      auto in = sockets[r]->receive();
      if (!in) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        continue;
      }
      EXPECT_TRUE(in->message.ok());
      auto decoded = read_shade_request(in->message->body, 1);
      EXPECT_TRUE(decoded.ok());
      got.push_back({in->peer, in->message->header.id, decoded->size(), decoded->size() ? float(decoded->key[0]) : -1.f});
    }
    return got;
  }
  // Answers with L = (k, r, 0) for each point, so the caller can check every point came back in its place.
  void answer(size_t r, const Held& h) {
    std::vector<RGB> L;
    for (size_t i = 0; i < h.n; ++i) L.push_back({h.first_k + float(i), float(r), 0});
    sockets[r]->send_to(h.peer, wire::make_reply("replica-" + std::to_string(r), h.id, encode_radiance(L)));
  }
  std::vector<std::unique_ptr<wire::Socket>> sockets;
  std::vector<std::string> endpoints;
};

class PoolClientTest : public ::testing::Test {
 protected:
  void make(size_t count, PoolOptions options, size_t replica_window = 4, std::vector<int64_t> parts = {}) {
    replicas = std::make_unique<Replicas>(count);
    std::vector<PoolClient::Replica> list;
    for (size_t r = 0; r < count; ++r) {
      connections.push_back(std::make_unique<wire::RequestClient>("client", "replica-" + std::to_string(r), replica_window));
      ASSERT_TRUE(connections.back()->connect(replicas->endpoints[r]).ok());
      list.push_back({"replica-" + std::to_string(r), connections.back().get(), false, r < parts.size() ? parts[r] : -1});
    }
    pool = std::make_unique<PoolClient>("pool", std::move(list), options);
  }
  void poll() {
    for (auto& c : connections) c->on_readable();
  }
  std::vector<Held> drain(size_t r) { return replicas->drain(r, [this] { poll(); }); }
  // Sends `count` requests of `n` points (of scene part `part`, -1: none); answers land in results[i].
  void send(size_t count, size_t n, int64_t part = -1) {
    for (size_t i = 0; i < count; ++i) {
      const size_t slot = results.size();
      results.emplace_back();
      pool->request(
          wire::Op::shade, encode_shade_request(points(n, 1000 * slot), 0, n),
          [this, slot, n](Result<wire::Message> reply) {
            ASSERT_TRUE(reply.ok()) << reply.error().message;
            auto L = decode_radiance(reply->body, n);
            ASSERT_TRUE(L.ok());
            results[slot] = *L;
          },
          part);
    }
  }

  std::unique_ptr<Replicas> replicas;
  std::vector<std::unique_ptr<wire::RequestClient>> connections;
  std::unique_ptr<PoolClient> pool;
  std::vector<std::vector<RGB>> results;
};

TEST_F(PoolClientTest, TheClientsWindowBoundsItsRequestsAcrossThePool) {
  PoolOptions o;
  o.strategy = Scheduler::Strategy::round_robin;
  o.window = 3;
  make(2, o);
  send(10, 5);
  auto held0 = drain(0), held1 = drain(1);
  EXPECT_EQ(held0.size() + held1.size(), 3u);  // the client's window, not 2 replicas x 4
  EXPECT_EQ(pool->in_progress(), 10u);
  // One answer lets exactly one more request start.
  replicas->answer(0, held0[0]);
  auto more = drain(0), more1 = drain(1);
  EXPECT_EQ(more.size() + more1.size(), 1u);
  EXPECT_EQ(results[0].size(), 5u);
  EXPECT_EQ(results[0][2].x, 2.0f);
}

// partition { colocate = true }: a request of one part's points goes whole (never split) to a replica holding that
// part; once none lives, to the others, and so do the pieces the lost one held.
TEST_F(PoolClientTest, APartsPointsGoWholeToAReplicaHoldingThatPart) {
  PoolOptions o;
  o.strategy = Scheduler::Strategy::round_robin;
  o.split = 4;
  make(3, o, 4, {0, 1, 1});
  send(2, 10, 1);
  send(1, 10, 0);
  auto held0 = drain(0), held1 = drain(1), held2 = drain(2);
  ASSERT_EQ(held0.size(), 1u);
  EXPECT_EQ(held0[0].n, 10u);
  EXPECT_EQ(held0[0].first_k, 2000.f);  // the part-0 request
  ASSERT_EQ(held1.size() + held2.size(), 2u);  // the part-1 requests, least loaded first: one each
  EXPECT_EQ(held1.size(), 1u);
  for (const auto& h : held1) EXPECT_EQ(h.n, 10u);
  for (const auto& h : held2) EXPECT_EQ(h.n, 10u);
  // Replica 0 is lost: its piece, and the next part-0 request, go to the others.
  EXPECT_TRUE(pool->lost("replica-0"));
  send(1, 6, 0);
  auto again1 = drain(1), again2 = drain(2);
  EXPECT_EQ(again1.size() + again2.size(), 2u);
  EXPECT_TRUE(drain(0).empty());
}

TEST_F(PoolClientTest, ASplitRequestComesBackWholeInItsOrder) {
  PoolOptions o;
  o.strategy = Scheduler::Strategy::round_robin;
  o.split = 4;
  make(3, o);
  send(1, 10);  // 3 pieces: 3, 3, 4 points
  std::vector<std::vector<Held>> held{drain(0), drain(1), drain(2)};
  for (size_t r = 0; r < 3; ++r) ASSERT_EQ(held[r].size(), 1u) << "replica " << r;
  EXPECT_EQ(held[0][0].n + held[1][0].n + held[2][0].n, 10u);
  for (size_t r : {2u, 0u, 1u}) replicas->answer(r, held[r][0]);  // out of order
  for (int i = 0; i < 50 && results[0].empty(); ++i) {
    poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(results[0].size(), 10u);
  for (size_t i = 0; i < 10; ++i) EXPECT_EQ(results[0][i].x, float(i)) << "point " << i;
}

// A request whose reply is folded by pixel is cut only between pixels, and its pieces' sums come back in order.
TEST_F(PoolClientTest, ASplitFoldedRequestIsCutBetweenPixelsAndGathersOneValueAPixel) {
  PoolOptions o;
  o.strategy = Scheduler::Strategy::round_robin;
  o.split = 4;
  make(3, o);
  // 4 samples a pixel; pixel 1 lost a sample (it missed). Even cuts (3, 6) would split pixels 0 and 1.
  const std::vector<uint32_t> samples{0, 1, 2, 3, 4, 5, 6, 8, 9, 10};
  Value body = encode_shade_request(points(samples.size()), 0, samples.size());
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{3}, int64_t{1}, int64_t{4}};
  body.as_map()["s"] = u32_to_bytes(std::span<const uint32_t>(samples));
  body.as_map()["fold"] = true;
  std::vector<RGB> result;
  pool->request(wire::Op::shade, std::move(body), [&](Result<wire::Message> reply) {
    ASSERT_TRUE(reply.ok()) << reply.error().message;
    auto L = decode_radiance(reply->body, 3);
    ASSERT_TRUE(L.ok()) << L.error().message;
    result = *L;
  });
  // Each replica answers its piece folded: one value a pixel, (first sample of the pixel, replica, points).
  std::vector<size_t> first_sample_of_piece;
  for (int i = 0; i < 100 && first_sample_of_piece.size() < 3; ++i) {
    poll();
    for (size_t r = 0; r < 3; ++r) {
      auto in = replicas->sockets[r]->receive();
      if (!in) continue;
      ASSERT_TRUE(in->message.ok());
      auto fold = decode_pixel_fold(in->message->body);
      ASSERT_TRUE(fold.ok() && fold->has_value());
      const auto& s = (*fold)->samples;
      ASSERT_EQ((*fold)->runs(), 1u) << "a piece of one whole pixel, from sample " << s[0];
      first_sample_of_piece.push_back(s[0]);
      const std::vector<RGB> L{{float(s[0]), float(r), float(s.size())}};
      replicas->sockets[r]->send_to(in->peer, wire::make_reply("replica", in->message->header.id, encode_radiance(L)));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  for (int i = 0; i < 50 && result.empty(); ++i) {
    poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(result.size(), 3u);
  EXPECT_EQ(result[0].x, 0.0f);
  EXPECT_EQ(result[0].z, 4.0f);
  EXPECT_EQ(result[1].x, 4.0f);
  EXPECT_EQ(result[1].z, 3.0f);
  EXPECT_EQ(result[2].x, 8.0f);
  EXPECT_EQ(result[2].z, 3.0f);
}

TEST_F(PoolClientTest, ALostReplicasWorkGoesToTheOthersAndItsLateAnswersAreDropped) {
  PoolOptions o;
  o.strategy = Scheduler::Strategy::round_robin;
  make(2, o);
  send(4, 3);
  auto held0 = drain(0), held1 = drain(1);
  ASSERT_EQ(held0.size(), 2u);
  ASSERT_EQ(held1.size(), 2u);
  EXPECT_TRUE(pool->lost("replica-1"));
  EXPECT_FALSE(pool->lost("somebody-else"));
  EXPECT_EQ(pool->live(), 1u);
  auto again = drain(0);
  EXPECT_EQ(again.size(), 2u);  // replica 1's two requests, sent again
  replicas->answer(1, held1[0]);  // too late: must not count
  for (const auto& h : held0) replicas->answer(0, h);
  for (const auto& h : again) replicas->answer(0, h);
  for (int i = 0; i < 50; ++i) poll();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  poll();
  for (size_t i = 0; i < 4; ++i) {
    ASSERT_EQ(results[i].size(), 3u) << "request " << i;
    EXPECT_EQ(results[i][0].y, 0.0f) << "request " << i << " was answered by the lost replica";
  }
  const Value stats = pool->stats();
  const auto& list = stats.find("replicas")->as_array();
  EXPECT_TRUE(list[1].find("lost")->as_bool());
  EXPECT_EQ(list[0].find("packets")->as_int(), 4);
}

TEST_F(PoolClientTest, ASpareAddedAfterTheLastReplicaIsLostTakesItsWork) {
  PoolOptions o;
  make(2, o);
  // The pool starts with replica 0 alone; replica 1 is the spare its owner connects once replica 0 is lost.
  pool = std::make_unique<PoolClient>("pool", std::vector<PoolClient::Replica>{{"replica-0", connections[0].get()}}, o);
  send(2, 3);
  ASSERT_EQ(drain(0).size(), 2u);
  EXPECT_TRUE(pool->lost("replica-0"));
  EXPECT_EQ(pool->live(), 0u);
  EXPECT_TRUE(drain(1).empty());
  pool->add({"replica-1", connections[1].get()});
  EXPECT_EQ(pool->live(), 1u);
  auto moved = drain(1);
  ASSERT_EQ(moved.size(), 2u) << "the stranded requests go to the spare";
  for (const auto& h : moved) replicas->answer(1, h);
  for (int i = 0; i < 50 && (results[0].empty() || results[1].empty()); ++i) {
    poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  for (size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(results[i].size(), 3u) << "request " << i;
    EXPECT_EQ(results[i][0].y, 1.0f) << "request " << i;
  }
  const Value stats = pool->stats();
  const auto& list = stats.find("replicas")->as_array();
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[1].find("packets")->as_int(), 2);
}

TEST_F(PoolClientTest, AReplicasErrorReachesTheCallerOnce) {
  PoolOptions o;
  make(1, o);
  int calls = 0;
  std::string message;
  pool->request(wire::Op::shade, encode_shade_request(points(2), 0, 2), [&](Result<wire::Message> reply) {
    ++calls;
    if (!reply) message = reply.error().message;
  });
  auto held = drain(0);
  ASSERT_EQ(held.size(), 1u);
  replicas->sockets[0]->send_to(held[0].peer, wire::make_error_reply("replica-0", held[0].id, ErrorCode::shade_failed, "bad batch"));
  for (int i = 0; i < 50 && calls == 0; ++i) {
    poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ(calls, 1);
  EXPECT_NE(message.find("bad batch"), std::string::npos) << message;
  EXPECT_EQ(pool->in_progress(), 0u);
}

// An actor that, once rendering, asks its one input for `requests` batches and then says READY render.
class AskingActor final : public Actor {
 public:
  Status configure(const ActorConfig&, Runtime& rt) override {
    pooled = rt.input_is_pool(0);
    return Ok{};
  }
  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase != wire::Phase::render) return rt.phase_done(phase);
    for (int i = 0; i < 6; ++i)
      rt.ask_input(0, wire::Op::shade, encode_shade_request(points(2, 10 * i), 0, 2), [this, &rt](Result<wire::Message> r) {
        if (!r) return rt.fail(r.error().message);
        if (++answered == 6) rt.phase_done(wire::Phase::render);
      });
  }
  void on_request(const std::string& peer, wire::Op, wire::Message& m, Runtime& rt) override {
    rt.reply_unknown_op(peer, m, "nothing");
  }
  bool pooled = false;
  int answered = 0;
};

TEST(PoolInputTest, AnActorAsksAPoolsReplicasDirectlyAndMovesOnWhenOneIsLost) {
  Replicas replicas(2);
  AskingActor* asking = nullptr;
  test::InprocActor actor("direct", "client", [&] {
    auto a = std::make_unique<AskingActor>();
    asking = a.get();
    return a;
  });
  actor.next(MsgType::hello);
  ActorConfig config;
  InputSpec pool{"lighting", "", 6, ""};
  pool.strategy = "round_robin";
  for (size_t r = 0; r < 2; ++r) pool.replicas.push_back({"lighting." + std::to_string(r), replicas.endpoints[r], 4, ""});
  config.inputs.push_back(pool);
  // The CONFIG travels as bytes and back, as from a real director.
  auto round_trip = ActorConfig::from_value(config.to_value());
  ASSERT_TRUE(round_trip.ok()) << round_trip.error().message;
  ASSERT_TRUE(round_trip->inputs[0].is_pool());
  actor.send(wire::make(MsgType::config, "director", round_trip->to_value()));
  ASSERT_EQ(wire::phase_of(actor.next(MsgType::ready).header), wire::Phase::configure);
  EXPECT_TRUE(asking->pooled);
  actor.send(wire::make_phase("director", wire::Phase::render));
  auto none = [] {};
  auto held0 = replicas.drain(0, none), held1 = replicas.drain(1, none);
  EXPECT_EQ(held0.size(), 3u);
  EXPECT_EQ(held1.size(), 3u);
  actor.send(wire::make(MsgType::peer_down, "director", Value::Map{{"name", "lighting.1"}}));
  for (const auto& h : held0) replicas.answer(0, h);
  auto again = replicas.drain(0, none, 0.5);
  EXPECT_EQ(again.size(), 3u);
  for (const auto& h : again) replicas.answer(0, h);
  ASSERT_EQ(wire::phase_of(actor.next(MsgType::ready).header), wire::Phase::render);
  actor.send(wire::make_phase("director", wire::Phase::finish));
  const wire::Message stats = actor.next(MsgType::stats);
  const Value* pools = stats.body.find("pools");
  ASSERT_TRUE(pools && pools->is_array() && pools->as_array().size() == 1);
  const auto& list = pools->as_array()[0].find("replicas")->as_array();
  EXPECT_EQ(list[0].find("packets")->as_int(), 6);  // its 3 and the lost one's 3
  EXPECT_TRUE(list[1].find("lost")->as_bool());
  actor.next(MsgType::bye);
  EXPECT_EQ(actor.join(), 0);
}

}  // namespace
}  // namespace lf
