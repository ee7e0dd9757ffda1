#pragma once
// The director's tile and peer bodies (docs/PROTOCOL.md), defined once for the director's parts, the runtime and
// the renderer; decoders check every field and its range, and an error says what is wrong.
//   tile (renderer -> director): { count? }
//     reply: { tile: {id, x0, y0, x1, y1, first?} } (half-open, inside the image; first: the pass's first sample
//            index, 0 when absent) | {} when no tile is left; asked with count (1-64): { tiles: [tile, ...] },
//            1 to count of them, or {}
//   tile_done (renderer -> director): { id, pixels: f32[3wh], next?, count? }, or several tiles' pixels at once,
//            { tiles: [{id, pixels}, ...], next?, count? }  reply: {}; with next: true, the reply is a tile
//            request's (the renderer's next tile or tiles, or {} when none is left)
//   PEER_MOVED (director -> actor): { name, endpoint, key }  (key "" without CURVE or over same-host IPC)
//   PEER_DOWN (director -> actor):  { name }
//   PHASE frame (director -> actor): { frame, camera: {eye, at, ...} (CameraSpec), renew?: [names] }
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "core/specs.hpp"
#include "core/value.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf::control {

struct Tile {
  uint64_t id = 0;
  TileRect rect;
  // A time-limited frame's pass: the tile's pixels take their samples from this index on (sent when not 0).
  uint32_t first_sample = 0;
  // A job's frames in flight: the number of the frame the tile is of (sent in a job; none: the renderer's latest).
  std::optional<int> frame;
};
// The most tiles one message asks for or carries.
inline constexpr int kMaxTilesPerMessage = 64;
Value encode_tile_reply(const std::optional<Tile>& tile);
// The reply to a request with a count: `tiles` (empty: none is left).
Value encode_tiles_reply(std::span<const Tile> tiles);
// Either form; empty: no tile is left. An error for a tile outside a `width` x `height` image or an empty one.
Result<std::vector<Tile>> decode_tile_reply(const Value& body, int width, int height);
// A tile request's count: 0 when the request asks in the one-tile form (no count), else 1 to kMaxTilesPerMessage.
Result<int> decode_tile_count(const Value& body);
Value encode_tile_request(int count);

struct FinishedTile {
  uint64_t id = 0;
  std::vector<float> rgb;  // 3 per pixel, rows of the tile top first
};
struct TileDone {
  std::vector<FinishedTile> tiles;  // one, or a batch's
  bool next = false;  // the renderer's next tile is asked for too: one round trip a tile instead of two
  int count = 0;      // with next: how many (0: the one-tile form)
};
// One tile's pixels in the one-tile form; several in the batch form. `count` > 0 asks for that many next tiles.
Value encode_tile_done(uint64_t id, std::span<const float> rgb, bool next = false);
Value encode_tile_done(std::span<const FinishedTile> tiles, int count);
Result<TileDone> decode_tile_done(const Value& body);

struct PeerMoved {
  std::string name, endpoint, key;
};
Value encode_peer_moved(const PeerMoved& moved);
Result<PeerMoved> decode_peer_moved(const Value& body);

Value encode_peer_down(const std::string& name);
Result<std::string> decode_peer_down(const Value& body);

// A job's next view. `renew`: on a replayed view (no render), the actors that set themselves up for it. `keep`: an
// op that carries its setup over the views sends it to the director once extended (REQUEST keep_setup), for the
// job's record. `restore`: such an op takes its setup as the director publishes it ("setup/<actor>", fetch)
// instead of extending it, and nothing else sets up for the view.
struct FrameView {
  int frame = 0;
  CameraSpec camera;
  std::optional<std::vector<std::string>> renew;
  bool keep = false;
  bool restore = false;
  Value::Array materials;  // the frame's material changes over the shipped scene (FrameSpec::materials)
  bool new_materials = false;  // the materials change at this frame: every actor sets up anew
  // The frame before, still rendering (frames in flight): its requests, which name it, are answered as before.
  std::optional<int> in_flight;
};
Value::Map encode_frame(const FrameView& view);  // the body besides the phase's name (wire::make_phase adds it)
Result<FrameView> decode_frame(const Value& body);

}  // namespace lf::control
