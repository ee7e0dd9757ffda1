// Every ring body round-trips, and decoders refuse what is out of range or inconsistent.
#include "actors/codecs/ring_codec.hpp"

#include <gtest/gtest.h>

namespace lf::ring {
namespace {

radiosity::SamplePacket packet() {
  radiosity::SamplePacket p;
  p.origin = 2;
  p.serial = 77;
  p.iteration = 5;
  p.route = 0b1011;
  p.points = {{1, 2, 3}, {4, 5, 6}};
  p.normals = {{0, 1, 0}, {0, 0, 1}};
  p.visible = {0xffff, 0x00f0};
  return p;
}

TEST(RingCodec, PacketsRoundTripAndOutOfRangeFieldsAreRefused) {
  auto back = decode_packet(encode_packet(packet(), 3), 4);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->home, 3);
  EXPECT_EQ(back->packet.origin, 2u);
  EXPECT_EQ(back->packet.serial, 77u);
  EXPECT_EQ(back->packet.iteration, 5u);
  EXPECT_EQ(back->packet.route, 0b1011u);
  EXPECT_EQ(back->packet.visible, packet().visible);
  EXPECT_EQ(back->packet.points[1].y, 5.0f);
  EXPECT_EQ(back->packet.normals[1].z, 1.0f);
  // Node 3 does not exist in a ring of 3 nodes.
  auto refused = decode_packet(encode_packet(packet(), 3), 3);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::bad_request);
  Value short_normals = encode_packet(packet(), 0);
  short_normals.as_map()["n"] = floats_to_bytes(std::vector<float>{0, 1, 0});
  EXPECT_EQ(decode_packet(short_normals, 4).error().message,
            "a sample packet needs p, n (3 floats per sample) and v (one u64 per sample)");
}

TEST(RingCodec, PollsAndTheirRepliesRoundTrip) {
  auto poll = decode_poll(encode_poll({2, 4, {0, 2}}));
  ASSERT_TRUE(poll.ok());
  EXPECT_EQ(poll->epoch, 2u);
  EXPECT_EQ(poll->iteration, 4);
  EXPECT_EQ(poll->idle, (std::vector<int>{0, 2}));
  EXPECT_EQ(decode_poll(Value::Map{{"iteration", 4}}).error().message, "ring.poll needs an epoch and an iteration");

  PollReply lending;
  lending.lent.push_back(packet());
  auto lent = decode_poll_reply(encode_poll_reply(lending), 4, 2);
  ASSERT_TRUE(lent.ok());
  ASSERT_EQ(lent->lent.size(), 1u);
  EXPECT_EQ(lent->lent[0].serial, 77u);
  PollReply idle_reply;
  idle_reply.finished = true;
  idle_reply.idle = {1, 9};
  auto idle = decode_poll_reply(encode_poll_reply(idle_reply), 4, 2);  // ring 9 does not exist: dropped
  ASSERT_TRUE(idle.ok());
  EXPECT_TRUE(idle->finished);
  EXPECT_EQ(idle->idle, (std::vector<int>{1}));
  EXPECT_FALSE(decode_poll_reply(Value::Map{{"packets", Value::Array{Value::Map{}}}}, 4, 2).ok());
}

TEST(RingCodec, ShooterReportsAndChoicesRoundTrip) {
  ShooterReport r;
  r.iteration = 3;
  r.unshot_power = 1.5;
  r.emitted_power = 9;
  r.power_arrived = 0.25;
  r.candidate = radiosity::Candidate{12, 4.5, RGB{1, 2, 3}};
  r.epoch = 5;
  auto back = decode_shooter_report(encode_shooter_report(r), 13);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->epoch, 5u);
  EXPECT_EQ(back->iteration, 3);
  EXPECT_FALSE(back->checkpoint);
  EXPECT_EQ(back->unshot_power, 1.5);
  EXPECT_EQ(back->emitted_power, 9);
  EXPECT_EQ(back->power_arrived, 0.25);
  ASSERT_TRUE(back->candidate);
  EXPECT_EQ(back->candidate->patch, 12u);
  EXPECT_EQ(back->candidate->unshot, (RGB{1, 2, 3}));
  r.candidate.reset();
  EXPECT_FALSE(decode_shooter_report(encode_shooter_report(r), 13)->candidate);
  // A checkpoint travels with its elements' depth (splitting depends on it); one of a patch the mesh does not have
  // is refused.
  radiosity::Element e;
  e.patch = 12;
  e.depth = 2;
  e.unshot = {0.5f, 0, 1};
  r.checkpoint = std::vector<radiosity::Element>{e};
  auto with = decode_shooter_report(encode_shooter_report(r), 13);
  ASSERT_TRUE(with.ok() && with->checkpoint && with->checkpoint->size() == 1u);
  EXPECT_EQ((*with->checkpoint)[0].depth, 2);
  EXPECT_EQ((*with->checkpoint)[0].unshot, e.unshot);
  EXPECT_FALSE(decode_shooter_report(encode_shooter_report(r), 12).ok());

  auto choice = decode_shooter_choice(encode_shooter_choice(ShooterChoice{6, 12, RGB{1, 2, 3}}), 13);
  ASSERT_TRUE(choice.ok());
  ASSERT_TRUE(choice->has_value());
  EXPECT_EQ((*choice)->patch, 12u);
  auto done = decode_shooter_choice(encode_shooter_choice(std::nullopt), 13);
  ASSERT_TRUE(done.ok());
  EXPECT_FALSE(done->has_value());
  // Patch 12 of a mesh with 12 patches does not exist.
  EXPECT_EQ(decode_shooter_choice(encode_shooter_choice(ShooterChoice{6, 12, RGB{}}), 12).error().message,
            "the director sent a malformed shooter");
}

TEST(RingCodec, ResultsRoundTripLeafElementsOnly) {
  radiosity::Element a, b;
  a.patch = 1;
  a.polygon.count = 3;
  a.polygon.v[0] = {1, 0, 0};
  a.radiosity = {0.5f, 0.25f, 0.125f};
  b = a;
  b.leaf = false;  // split: its children carry its radiosity
  auto back = decode_result(encode_result({a, b}, 3), 2);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->epoch, 3u);
  ASSERT_EQ(back->elements.size(), 1u);
  EXPECT_EQ(back->elements[0].patch, 1u);
  EXPECT_EQ(back->elements[0].polygon.count, 3);
  EXPECT_EQ(back->elements[0].radiosity, a.radiosity);
  EXPECT_EQ(decode_result(encode_result({a}, 0), 1).error().message, "a malformed result");
  EXPECT_EQ(decode_elements(encode_elements({a}), 1).error().message, "an element of an unknown patch");
}

TEST(RingCodec, RollbacksRoundTripAndNeedAnEpochPastTheFirst) {
  radiosity::Element a;
  a.patch = 1;
  a.depth = 1;
  a.radiosity = {0.5f, 0.25f, 0.125f};
  auto back = decode_rollback(encode_rollback({2, 9, {a}}), 2);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->epoch, 2u);
  EXPECT_EQ(back->iteration, 9);
  ASSERT_EQ(back->elements.size(), 1u);
  EXPECT_EQ(back->elements[0].depth, 1);
  auto start = decode_rollback(encode_rollback({1, -1, {}}), 2);
  ASSERT_TRUE(start.ok());
  EXPECT_EQ(start->iteration, -1);
  EXPECT_TRUE(start->elements.empty());
  EXPECT_EQ(decode_rollback(encode_rollback({0, 9, {a}}), 2).error().message,
            "a rollback needs an epoch (from 1) and an iteration");
  a.depth = 9;  // deeper than any ring may split
  EXPECT_FALSE(decode_rollback(encode_rollback({2, 9, {a}}), 2).ok());
}

}  // namespace
}  // namespace lf::ring
