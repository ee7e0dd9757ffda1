// The exchange driven message by message: all-gather answers every replica with every part in replica order, only
// when all sent theirs; a lone actor gets its own part; fetch waits for what will be published.
#include "actors/director/exchange_service.hpp"

#include <gtest/gtest.h>

#include "actors/director/service_test_support.hpp"

namespace lf {
namespace {

using test::RecordingOutbox;
using wire::Op;

Value part(const std::string& bytes) { return Value::Map{{"part", Bytes{bytes}}}; }

TEST(ExchangeService, AllGatherAnswersEveryReplicaInReplicaOrderOnceAllSent) {
  ExchangeService x({{"photons", {"photons.0", "photons.1", "photons.2"}}});
  RecordingOutbox out;
  ASSERT_TRUE(x.on_request("photons.2", Op::all_gather, 7, part("c"), out).ok());
  ASSERT_TRUE(x.on_request("photons.0", Op::all_gather, 8, part("a"), out).ok());
  EXPECT_TRUE(out.take().empty());
  ASSERT_TRUE(x.on_request("photons.1", Op::all_gather, 9, part("b"), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 3u);
  std::map<std::string, uint64_t> ids;
  for (const auto& s : sent) {
    ids[s.actor] = s.id;
    const auto& parts = s.body.find("parts")->as_array();
    ASSERT_EQ(parts.size(), 3u);
    EXPECT_EQ(parts[0].as_bytes().data, "a");
    EXPECT_EQ(parts[1].as_bytes().data, "b");
    EXPECT_EQ(parts[2].as_bytes().data, "c");
  }
  EXPECT_EQ(ids, (std::map<std::string, uint64_t>{{"photons.0", 8}, {"photons.1", 9}, {"photons.2", 7}}));
}

// A replica that keeps its own part gets nil in its place and every other part; one that does not gets all.
TEST(ExchangeService, AReplicaThatKeepsItsPartGetsOnlyTheOthers) {
  ExchangeService x({{"photons", {"photons.0", "photons.1", "photons.2"}}});
  RecordingOutbox out;
  auto keeping = [](const std::string& bytes) { return map_of("part", Bytes{bytes}, "keep", true); };
  ASSERT_TRUE(x.on_request("photons.0", Op::all_gather, 1, keeping("a"), out).ok());
  ASSERT_TRUE(x.on_request("photons.1", Op::all_gather, 2, part("b"), out).ok());
  ASSERT_TRUE(x.on_request("photons.2", Op::all_gather, 3, keeping("c"), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 3u);
  std::map<std::string, std::vector<std::string>> got;
  for (const auto& s : sent)
    for (const auto& p : s.body.find("parts")->as_array()) got[s.actor].push_back(p.is_nil() ? "nil" : p.as_bytes().data);
  EXPECT_EQ(got["photons.0"], (std::vector<std::string>{"nil", "b", "c"}));
  EXPECT_EQ(got["photons.1"], (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(got["photons.2"], (std::vector<std::string>{"a", "b", "nil"}));
}

TEST(ExchangeService, ALoneActorGetsItsOwnPartAndABadOneIsRefused) {
  ExchangeService x({});
  RecordingOutbox out;
  ASSERT_TRUE(x.on_request("photons", Op::all_gather, 1, part("mine"), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].body.find("parts")->as_array().at(0).as_bytes().data, "mine");
  ASSERT_TRUE(x.on_request("photons", Op::all_gather, 2, Value::Map{}, out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].code, ErrorCode::bad_request);
}

TEST(ExchangeService, AReplicaLostWhileItsPoolSharesStopsTheFarm) {
  ExchangeService x({{"photons", {"photons.0", "photons.1"}}});
  RecordingOutbox out;
  ASSERT_TRUE(x.on_request("photons.0", Op::all_gather, 1, part("a"), out).ok());
  auto st = x.on_lost("photons.1", "was killed by signal 9", out);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message,
            "replica 'photons.1' was killed by signal 9 while 'photons' was sharing its setup; its share cannot be redone");
  // Lost before its pool began sharing: the first part sent finds out.
  ExchangeService y({{"photons", {"photons.0", "photons.1"}}});
  ASSERT_TRUE(y.on_lost("photons.1", "was killed", out).ok());
  auto late = y.on_request("photons.0", Op::all_gather, 2, part("a"), out);
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().message,
            "replica 'photons.1' of 'photons' was lost before the pool shared its setup; its share cannot be redone");
}

TEST(ExchangeService, FetchWaitsForWhatWillBePublishedAndRefusesTheRest) {
  ExchangeService x({});
  RecordingOutbox out;
  ASSERT_TRUE(x.on_request("op", Op::fetch, 1, Value::Map{{"key", "radiosity"}}, out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].code, ErrorCode::not_found);
  x.expect("radiosity");
  ASSERT_TRUE(x.on_request("op", Op::fetch, 2, Value::Map{{"key", "radiosity"}}, out).ok());
  ASSERT_TRUE(x.on_request("op2", Op::fetch, 3, Value::Map{{"key", "radiosity"}}, out).ok());
  EXPECT_TRUE(out.take().empty());
  x.publish("radiosity", "solution", out);
  sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  for (const auto& s : sent) EXPECT_EQ(s.body.find("blob")->as_bytes().data, "solution");
  // Published already: answered at once.
  ASSERT_TRUE(x.on_request("op3", Op::fetch, 4, Value::Map{{"key", "radiosity"}}, out).ok());
  EXPECT_EQ(out.take().size(), 1u);
}

}  // namespace
}  // namespace lf
