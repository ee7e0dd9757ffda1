#pragma once
// The wire, defined once (STYLE habit 6). docs/PROTOCOL.md describes the same thing for people writing actors
// in other languages; keep the two in step.
//
// A message is two ZeroMQ frames: a header (msgpack map with short keys) and a body (msgpack, usually a map).
// Message type numbers are fixed forever: a retired number is never reused.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#ifdef LIGHTFARM_ALGORITHM_LAYER
#error "render/ and radiosity/ must not include transport headers (algorithm code cannot reach the network)"
#endif

namespace lf::wire {

// Bumped whenever a change would make an old peer misread a new one. HELLO carries it and the director refuses a
// mismatch by name.
inline constexpr uint32_t kProtocolVersion = 1;

enum class MsgType : uint8_t {
  hello = 1,      // actor -> director: name, kind, pid, data endpoint, build settings
  config = 2,     // director -> actor: parameters, scene, camera, image, input endpoints
  phase = 3,      // director -> actor: enter a phase ("setup", "render", "finish")
  request = 4,    // client -> server: an operation with a batch; answered later by REPLY or ERROR with the same id
  reply = 5,      // server -> client: the answer to request `id`; header `q` carries the server's queue length
  error = 6,      // any -> any: something was wrong; `id` names the request it answers, if any
  stats = 7,      // actor -> director: counters (requests, points, bytes, busy time, peak queue)
  heartbeat = 8,  // both ways: "still here"
  bye = 9,        // director -> actor: stop now; actor -> director: stopping
  ready = 10,     // actor -> director: finished a phase (body names it)
  peer_down = 11, // director -> actor: one of your inputs is gone (body: {name}); re-route its work
  peer_moved = 12, // director -> actor: one of your inputs was restarted (body: {name, endpoint, key}); what was
                   // outstanding with it is forgotten
  rollback = 13,   // director -> ring node: back to a checkpoint in a new epoch (body: actors/codecs/ring_codec.hpp)
  progress = 14,   // actor -> director: how far a long setup is (body: {what, done, total}); a few a second at most
};

std::string_view type_name(MsgType type);
std::optional<MsgType> type_from_number(uint64_t number);

// Operations a REQUEST names in its header `op`. On the wire they are strings; in code they are these values, and
// their wire names live in one table (transport/message.cpp). docs/PROTOCOL.md describes each body.
enum class Op : uint8_t {
  unknown,       // a name this build does not serve (the raw name stays in Header::op for the error message)
  shade,         // renderer/LightOp -> LightOp: shade a batch of points
  tile,          // renderer -> director: the next tile
  tile_done,     // renderer -> director: a finished tile's pixels
  fetch,         // actor -> director: a blob the farm publishes (the radiosity solution)
  ring_shooter,  // ring node -> director: this iteration is done here; the next shooter?
  ring_result,   // ring node -> director: the node's elements, after the last iteration
  ring_visit,    // ring node -> ring node: process this sample packet and pass it on
  ring_back,     // ring node -> home node: the packet is round its ring
  ring_return,   // borrower -> origin node: a lent packet comes back
  ring_poll,     // idle ring node -> node at its position in another ring: lend me work
  trace,         // LightOp -> geometry actor: trace a batch of rays through this part of a partitioned scene
  pool_part,     // pool replica -> pool replica: its part of one round of the pool's setup exchange
  keep_setup,    // LightOp -> director: its setup carried over a job's views, as extended to this frame's view
};
std::string_view op_name(Op op);
Op op_from_name(std::string_view name);

// Phases the director drives (PHASE and READY carry the name in header `op`). configure is answered by READY
// without a PHASE: CONFIG starts it. frame comes between one frame of a job and the next (its body: the frame
// number and camera): what depends on the view is redone, then render again.
enum class Phase : uint8_t { configure, setup, render, finish, frame };
std::string_view phase_name(Phase phase);
std::optional<Phase> phase_from_name(std::string_view name);

// Limits every receiver enforces; anything larger is refused before it is decoded.
inline constexpr size_t kMaxHeaderBytes = 4096;
inline constexpr size_t kMaxBodyBytes = 256u << 20;
inline constexpr size_t kMaxNameBytes = 128;
inline constexpr size_t kMaxOpBytes = 64;
inline constexpr size_t kMaxDepth = 32;

// The build setting that changes how bulk arrays read; HELLO carries it so a peer that disagrees is refused.
inline constexpr std::string_view kFloatFormat = "f32le";

}  // namespace lf::wire
