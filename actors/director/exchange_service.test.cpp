// The exchange driven message by message: fetch waits for what will be published and refuses what never will be.
#include "actors/director/exchange_service.hpp"

#include <gtest/gtest.h>

#include "actors/director/service_test_support.hpp"

namespace lf {
namespace {

using test::RecordingOutbox;
using wire::Op;

TEST(ExchangeService, FetchWaitsForWhatWillBePublishedAndRefusesTheRest) {
  ExchangeService x;
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
