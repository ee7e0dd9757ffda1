#pragma once
// The radiosity ring's message bodies (docs/PROTOCOL.md, "The radiosity ring"), defined once for the node, the
// director's ring service and the tests. Decoders check every field and its range; an error says what is wrong.
//
//   ring.visit / ring.back / ring.return (node -> node), and each lent packet in a ring.poll reply:
//     { o: origin node, s: serial, it: iteration, r: route bits, home: node, p: f32[3n], n: f32[3n], v: u64[n] }
//   ring.poll (node -> node):     { iteration, idle: [ring, ...] }
//     reply:                      { packets: [packet, ...] } | { finished: bool, idle: [ring, ...] }
//   ring.shooter (node -> director): { iteration, unshot_power, emitted_power, power_arrived,
//                                      candidate?: {patch, power, unshot: [r, g, b]} }
//     reply:                      { shooter: {iteration, patch, unshot: [r, g, b]} } | { done: true }
//   ring.result (node -> director): { patch: u32[n], corners: u32[n], points: f32[12n], radiosity: f32[3n],
//                                     unshot: f32[3n] }   (leaf elements; corners padded to 4)
#include <optional>
#include <vector>

#include "core/result.hpp"
#include "core/value.hpp"
#include "radiosity/ring.hpp"

namespace lf::ring {

// A sample packet and the node it circulates for.
struct PacketMessage {
  radiosity::SamplePacket packet;
  int home = 0;
};
Value encode_packet(const radiosity::SamplePacket& packet, int home);
Result<PacketMessage> decode_packet(const Value& body, int nodes);

struct PollRequest {
  int64_t iteration = 0;
  std::vector<int> idle;  // rings the poller knows are idle
};
Value encode_poll(const PollRequest& poll);
Result<PollRequest> decode_poll(const Value& body);

struct PollReply {
  std::vector<radiosity::SamplePacket> lent;  // non-empty: work to run
  bool finished = false;                      // otherwise: whether the answerer's ring is idle
  std::vector<int> idle;
};
Value encode_poll_reply(const std::vector<Value>& lent_packets);  // packets already encoded with encode_packet
Value encode_poll_reply(bool finished, const std::vector<int>& idle);
// Rings outside [0, rings) are dropped from `idle`.
Result<PollReply> decode_poll_reply(const Value& body, int nodes, int rings);

struct ShooterReport {
  int64_t iteration = -1;  // the iteration this node finished; -1 before the first
  double unshot_power = 0;
  double emitted_power = 0;
  double power_arrived = 0;
  std::optional<radiosity::Candidate> candidate;
};
Value encode_shooter_report(const ShooterReport& report);
Result<ShooterReport> decode_shooter_report(const Value& body);

// The director's answer: the next shooter, or nothing (converged or stopped).
struct ShooterChoice {
  int64_t iteration = 0;
  uint32_t patch = 0;
  RGB unshot;
};
Value encode_shooter_choice(const std::optional<ShooterChoice>& choice);
// nullopt inside the Result: done. `patches` bounds the patch number.
Result<std::optional<ShooterChoice>> decode_shooter_choice(const Value& body, size_t patches);

// Leaf elements, with `patches` bounding their patch numbers when decoding.
Value encode_result(const std::vector<radiosity::Element>& elements);
Result<std::vector<radiosity::Element>> decode_result(const Value& body, size_t patches);

}  // namespace lf::ring
