#include "transport/client.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/time.h>

#include <algorithm>
#include <atomic>
#include <chrono>

namespace lf::wire {

// Several nodes in one process over inproc:// (CZMQ's habit): a router plays the server.
class ClientTest : public ::testing::Test {
 protected:
  Socket server{Socket::Kind::router};
  std::string endpoint;
  void SetUp() override {
    static int n = 0;
    auto e = server.bind("inproc://client-test-" + std::to_string(n++));
    ASSERT_TRUE(e.ok()) << e.error().message;
    endpoint = *e;
  }
  // Collects what the server receives until `want` messages arrived (then a short grace for extras) or 5 s passed.
  std::vector<Incoming> server_receive(size_t want = 1) {
    std::vector<Incoming> got;
    Poller p;
    p.add(server);
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (std::chrono::steady_clock::now() < deadline) {
      p.wait(5);
      while (auto in = server.receive()) got.push_back(std::move(*in));
      if (got.size() >= want) {
        // Anything sent beyond `want` would already be queued: drain it too, so window checks see it.
        p.wait(20);
        while (auto in = server.receive()) got.push_back(std::move(*in));
        break;
      }
    }
    return got;
  }
  // Runs the client's reply handling until `done()` or 5 s passed.
  template <class Done>
  void wait_client(RequestClient& c, Done done) {
    Poller p;
    p.add(c.socket());
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (!done() && std::chrono::steady_clock::now() < deadline) {
      p.wait(5);
      c.on_readable();
    }
  }
};

TEST_F(ClientTest, WindowBoundsOutstandingAndRepliesMatchById) {
  RequestClient client("renderer-0", "direct", 3);
  ASSERT_TRUE(client.connect(endpoint).ok());
  std::vector<int64_t> answered;
  for (int i = 0; i < 10; ++i)
    client.request(Op::shade, Value::Map{{"i", i}}, [&, i](Result<Message> r) {
      ASSERT_TRUE(r.ok());
      EXPECT_EQ(r->body.find("echo")->as_int(), i);
      answered.push_back(i);
    });
  EXPECT_EQ(client.outstanding(), 3u);
  EXPECT_EQ(client.queued(), 7u);

  int served = 0;
  while (served < 10) {
    auto got = server_receive();
    ASSERT_FALSE(got.empty()) << "server starved after " << served;
    EXPECT_LE(got.size(), 3u);  // never more than the window in flight
    // Answer in reverse order: callbacks must still find their own requests.
    std::reverse(got.begin(), got.end());
    for (auto& in : got) {
      ASSERT_TRUE(in.message.ok());
      EXPECT_EQ(in.peer, "renderer-0");
      Message reply = make_reply("direct", in.message->header.id,
                                 Value::Map{{"echo", in.message->body.find("i")->as_int()}}, 5);
      ASSERT_TRUE(server.send_to(in.peer, reply));
      ++served;
    }
    const size_t expected = static_cast<size_t>(served);
    wait_client(client, [&] { return answered.size() == expected; });
  }
  EXPECT_EQ(answered.size(), 10u);
  EXPECT_EQ(client.outstanding(), 0u);
  EXPECT_EQ(client.peer_queue(), 5u);
}

TEST_F(ClientTest, ErrorRepliesReachTheCallbackAndStrayRepliesAreDropped) {
  RequestClient client("renderer-0", "direct", 2);
  ASSERT_TRUE(client.connect(endpoint).ok());
  std::string error;
  ErrorCode code = ErrorCode::failed;
  client.request(Op::shade, Value::Map{}, [&](Result<Message> r) {
    ASSERT_FALSE(r.ok());
    error = r.error().message;
    code = r.error().code;
  });
  auto got = server_receive();
  ASSERT_EQ(got.size(), 1u);
  uint64_t id = got[0].message->header.id;
  ASSERT_TRUE(server.send_to(got[0].peer, make_error_reply("direct", id, ErrorCode::bad_request, "no points")));
  // A second answer to the same id, and one to an id never sent: both dropped, not delivered twice.
  ASSERT_TRUE(server.send_to(got[0].peer, make_reply("direct", id, Value::Map{})));
  ASSERT_TRUE(server.send_to(got[0].peer, make_reply("direct", 999, Value::Map{})));
  wait_client(client, [&] { return client.dropped_replies() == 2; });
  EXPECT_EQ(error, "direct: no points");
  EXPECT_EQ(code, ErrorCode::bad_request);
  EXPECT_EQ(client.dropped_replies(), 2u);
}

TEST_F(ClientTest, RouterRejectsMalformedFramesAsErrors) {
  Socket dealer(Socket::Kind::dealer, "hostile");
  ASSERT_TRUE(dealer.connect(endpoint).ok());
  ASSERT_TRUE(dealer.send_raw({"just one frame"}));
  ASSERT_TRUE(dealer.send_raw({"\x81\xa1v\x01", "\x80", "extra"}));
  ASSERT_TRUE(dealer.send_raw({"garbage", "\x80"}));
  auto got = server_receive(3);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].message.error().message, "expected 2 frames (header, body), got 1");
  EXPECT_EQ(got[1].message.error().message, "expected 2 frames (header, body), got 3");
  EXPECT_FALSE(got[2].message.ok());
  EXPECT_EQ(got[2].peer, "hostile");
}

TEST_F(ClientTest, BindingAPortInUseIsAClearError) {
  Socket a(Socket::Kind::router), b(Socket::Kind::router);
  auto ea = a.bind("tcp://127.0.0.1:*");
  ASSERT_TRUE(ea.ok());
  auto eb = b.bind(*ea);
  ASSERT_FALSE(eb.ok());
  EXPECT_NE(eb.error().message.find("Address already in use"), std::string::npos) << eb.error().message;
}

// Actors take signals while they send and receive (SIGCONT after Ctrl-Z/fg, a host agent's SIGCHLD). A signal that
// interrupts ZeroMQ mid-message must cost nothing: every message arrives whole, once, in order, both ways.
namespace {
std::atomic<int> g_ticks{0};
void count_tick(int) { g_ticks.fetch_add(1, std::memory_order_relaxed); }

// SIGALRM every 50 us while it lives, with a handler installed without SA_RESTART like the actors' own, so that
// system calls return EINTR; the previous handler and a stopped timer come back however the test ends.
class SignalStorm {
 public:
  SignalStorm() {
    struct sigaction tick {};
    tick.sa_handler = count_tick;
    sigemptyset(&tick.sa_mask);
    tick.sa_flags = 0;
    ::sigaction(SIGALRM, &tick, &before_);
    itimerval every{{0, 50}, {0, 50}};
    ::setitimer(ITIMER_REAL, &every, nullptr);
  }
  ~SignalStorm() {
    itimerval off{};
    ::setitimer(ITIMER_REAL, &off, nullptr);
    ::sigaction(SIGALRM, &before_, nullptr);
  }

 private:
  struct sigaction before_ {};
};
}  // namespace

TEST_F(ClientTest, MessagesSurviveASignalStorm) {
  Socket router(Socket::Kind::router);
  auto bound = router.bind("tcp://127.0.0.1:*");
  ASSERT_TRUE(bound.ok()) << bound.error().message;
  Socket dealer(Socket::Kind::dealer, "stormy");
  ASSERT_TRUE(dealer.connect(*bound).ok());
  const int ticks_before = g_ticks.load();
  SignalStorm storm;

  constexpr uint64_t kMessages = 10000;
  const std::string payload(300, 'x');
  uint64_t sent = 0, at_router = 0, at_dealer = 0, bad = 0, out_of_order = 0, failed_sends = 0;
  Poller poll;
  poll.add(router);
  poll.add(dealer);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (at_dealer < kMessages && std::chrono::steady_clock::now() < deadline) {
    for (int i = 0; i < 50 && sent < kMessages; ++i, ++sent)
      if (!dealer.send(make_request("stormy", Op::shade, Value::Map{{"p", payload}}, sent))) ++failed_sends;
    poll.wait(1);
    while (auto in = router.receive()) {
      if (!in->message || in->peer != "stormy") {
        ++bad;
        continue;
      }
      if (in->message->header.id != at_router) ++out_of_order;
      ++at_router;
      if (!router.send_to(in->peer, make_reply("server", in->message->header.id, Value::Map{{"L", payload}})))
        ++failed_sends;
    }
    while (auto in = dealer.receive()) {
      if (!in->message) {
        ++bad;
        continue;
      }
      if (in->message->header.id != at_dealer) ++out_of_order;
      ++at_dealer;
    }
  }
  EXPECT_GT(g_ticks.load() - ticks_before, 100);  // the storm happened
  EXPECT_EQ(failed_sends, 0u);
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(at_router, kMessages);
  EXPECT_EQ(at_dealer, kMessages);
}

}  // namespace lf::wire
