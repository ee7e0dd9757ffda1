#pragma once
// The radiosity ring's message bodies (docs/PROTOCOL.md, "The radiosity ring"), defined once for the node, the
// director's ring service and the tests; the structs they carry are the ring protocol's (radiosity/ring_protocol.hpp). Decoders check every field and its range; an error says what is wrong.
//
//   ring.visit / ring.back / ring.return (node -> node), and each lent packet in a ring.poll reply:
//     { o: origin node, s: serial, it: iteration, e: epoch, r: route bits, home: node, p: f32[3n], n: f32[3n],
//       v: u64[n] }
//   ring.poll (node -> node):     { epoch, iteration, idle: [ring, ...] }
//     reply:                      { packets: [packet, ...] } | { finished: bool, idle: [ring, ...] }
//   ring.shooter (node -> director): { epoch, iteration, unshot_power, emitted_power, power_arrived,
//                                      candidate?: {patch, power, unshot: [r, g, b]}, checkpoint?: ELEMENTS }
//     reply:                      { shooter: {iteration, patch, unshot: [r, g, b]} } | { done: true }
//   ring.result (node -> director): ELEMENTS + { epoch }
//   ROLLBACK (director -> node):  ELEMENTS + { epoch, iteration }
// where ELEMENTS (leaf elements; corners padded to 4) is
//     { patch: u32[n], corners: u32[n], points: f32[12n], radiosity: f32[3n], unshot: f32[3n], depth: u32[n] }
#include <optional>
#include <vector>

#include "core/result.hpp"
#include "core/value.hpp"
#include "radiosity/ring.hpp"
#include "radiosity/ring_protocol.hpp"

namespace lf::ring {

// A sample packet and the node it circulates for.
struct PacketMessage {
  radiosity::SamplePacket packet;
  int home = 0;
};
Value encode_packet(const radiosity::SamplePacket& packet, int home);
Result<PacketMessage> decode_packet(const Value& body, int nodes);

using radiosity::PollReply;
using radiosity::PollRequest;
using radiosity::ShooterChoice;
using radiosity::ShooterReport;

Value encode_poll(const PollRequest& poll);
Result<PollRequest> decode_poll(const Value& body);
// Lent packets travel with home = their origin. Rings outside [0, rings) are dropped from `idle` when decoding.
Value encode_poll_reply(const PollReply& reply);
Result<PollReply> decode_poll_reply(const Value& body, int nodes, int rings);

// `patches` bounds the checkpoint's patch numbers.
Value encode_shooter_report(const ShooterReport& report);
Result<ShooterReport> decode_shooter_report(const Value& body, size_t patches);

Value encode_shooter_choice(const std::optional<ShooterChoice>& choice);
// nullopt inside the Result: done. `patches` bounds the patch number.
Result<std::optional<ShooterChoice>> decode_shooter_choice(const Value& body, size_t patches);

// Leaf elements (split parents are left out), with `patches` bounding their patch numbers when decoding.
inline constexpr uint32_t kMaxElementDepth = 8;  // read_ring_config's bound on max_depth
inline constexpr size_t kElementWireBytes = 84;  // patch, corners, 4 corners, radiosity, unshot, depth
Value encode_elements(const std::vector<radiosity::Element>& elements);
Result<std::vector<radiosity::Element>> decode_elements(const Value& body, size_t patches);

struct ResultMessage {
  uint32_t epoch = 0;
  std::vector<radiosity::Element> elements;
};
Value encode_result(const std::vector<radiosity::Element>& elements, uint32_t epoch);
Result<ResultMessage> decode_result(const Value& body, size_t patches);

using radiosity::Rollback;
Value encode_rollback(const Rollback& rollback);
Result<Rollback> decode_rollback(const Value& body, size_t patches);

}  // namespace lf::ring
