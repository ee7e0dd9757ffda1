#include "actors/codecs/control_codec.hpp"

#include <climits>

namespace lf::control {
namespace {

Error bad(const std::string& what) { return Error{what, ErrorCode::bad_request}; }

const std::string* string_field(const Value& body, const char* key) {
  const Value* v = body.find(key);
  return v && v->is_string() ? &v->as_string() : nullptr;
}

}  // namespace

namespace {

Value::Map tile_map(const Tile& tile) {
  const TileRect& r = tile.rect;
  Value::Map t{{"id", tile.id}, {"x0", r.x0}, {"y0", r.y0}, {"x1", r.x1}, {"y1", r.y1}};
  if (tile.first_sample > 0) t["first"] = static_cast<int64_t>(tile.first_sample);
  if (tile.frame) t["frame"] = static_cast<int64_t>(*tile.frame);
  return t;
}

Result<Tile> read_tile(const Value& tile, int width, int height) {
  if (!tile.is_map()) return bad("the render master sent a tile outside the image");
  auto get = [&](const char* k) {
    const Value* v = tile.find(k);
    return v && v->is_int() && v->as_int() >= 0 && v->as_int() <= INT32_MAX ? static_cast<int>(v->as_int()) : -1;
  };
  const TileRect rect{get("x0"), get("y0"), get("x1"), get("y1")};
  if (get("id") < 0 || rect.x0 < 0 || rect.y0 < 0 || rect.x1 > width || rect.y1 > height ||
      rect.width() <= 0 || rect.height() <= 0)
    return bad("the render master sent a tile outside the image");
  int first = 0;
  if (tile.find("first") && (first = get("first")) < 0)
    return bad("the render master sent a tile whose first sample is not an index (0 to 2^31 - 1)");
  std::optional<int> frame;
  if (const Value* f = tile.find("frame")) {
    if (!f->is_int() || f->as_int() < INT32_MIN || f->as_int() > INT32_MAX)
      return bad("the render master sent a tile whose frame is not a frame number");
    frame = static_cast<int>(f->as_int());
  }
  return Tile{static_cast<uint64_t>(get("id")), rect, static_cast<uint32_t>(first), frame};
}

// A tile request's or tile_done's count: absent 0, else 1 to kMaxTilesPerMessage.
Result<int> read_count(const Value& body, const char* what) {
  const Value* count = body.find("count");
  if (!count) return 0;
  if (!count->is_int() || count->as_int() < 1 || count->as_int() > kMaxTilesPerMessage)
    return bad(std::string(what) + "'s count must be a whole number from 1 to " + std::to_string(kMaxTilesPerMessage));
  return static_cast<int>(count->as_int());
}

Result<FinishedTile> read_finished(const Value& body) {
  const Value* id = body.find("id");
  const Value* pixels = body.find("pixels");
  FinishedTile done;
  if (!id || !id->is_int() || id->as_int() < 0 || !pixels || !pixels->is_bytes() ||
      !bytes_to_floats(pixels->as_bytes(), done.rgb) || done.rgb.size() % 3 != 0)
    return bad("tile_done needs id and pixels");
  done.id = static_cast<uint64_t>(id->as_int());
  return done;
}

}  // namespace

Value encode_tile_reply(const std::optional<Tile>& tile) {
  if (!tile) return Value::Map{};
  return Value::Map{{"tile", tile_map(*tile)}};
}

Value encode_tiles_reply(std::span<const Tile> tiles) {
  if (tiles.empty()) return Value::Map{};
  Value::Array list;
  for (const Tile& t : tiles) list.push_back(tile_map(t));
  return Value::Map{{"tiles", std::move(list)}};
}

Result<std::vector<Tile>> decode_tile_reply(const Value& body, int width, int height) {
  if (!body.is_map()) return bad("a tile reply must be a map");
  std::vector<Tile> out;
  if (const Value* tile = body.find("tile")) {
    auto t = read_tile(*tile, width, height);
    if (!t) return t.error();
    out.push_back(*t);
  } else if (const Value* tiles = body.find("tiles")) {
    if (!tiles->is_array() || tiles->as_array().empty() ||
        tiles->as_array().size() > static_cast<size_t>(kMaxTilesPerMessage))
      return bad("the render master's tiles must be a list of 1 to " + std::to_string(kMaxTilesPerMessage) + " tiles");
    for (const Value& v : tiles->as_array()) {
      auto t = read_tile(v, width, height);
      if (!t) return t.error();
      out.push_back(*t);
    }
  }
  return out;
}

Result<int> decode_tile_count(const Value& body) {
  if (!body.is_map()) return bad("a tile request must be a map");
  return read_count(body, "a tile request");
}

Value encode_tile_request(int count) {
  if (count <= 0) return Value::Map{};
  return Value::Map{{"count", count}};
}

Value encode_tile_done(uint64_t id, std::span<const float> rgb, bool next) {
  Value::Map m{{"id", id}, {"pixels", floats_to_bytes(rgb)}};
  if (next) m["next"] = true;
  return m;
}

Value encode_tile_done(std::span<const FinishedTile> tiles, int count) {
  Value::Array list;
  for (const FinishedTile& t : tiles) list.push_back(Value::Map{{"id", t.id}, {"pixels", floats_to_bytes(t.rgb)}});
  Value::Map m{{"tiles", std::move(list)}};
  if (count > 0) m["next"] = true, m["count"] = count;
  return m;
}

Result<TileDone> decode_tile_done(const Value& body) {
  if (!body.is_map()) return bad("tile_done needs id and pixels");
  TileDone done;
  if (const Value* tiles = body.find("tiles")) {
    if (!tiles->is_array() || tiles->as_array().empty() ||
        tiles->as_array().size() > static_cast<size_t>(kMaxTilesPerMessage))
      return bad("tile_done's tiles must be a list of 1 to " + std::to_string(kMaxTilesPerMessage) +
                 " maps of id and pixels");
    for (const Value& v : tiles->as_array()) {
      auto t = read_finished(v);
      if (!t) return t.error();
      done.tiles.push_back(std::move(*t));
    }
  } else {
    auto t = read_finished(body);
    if (!t) return t.error();
    done.tiles.push_back(std::move(*t));
  }
  if (const Value* next = body.find("next")) {
    if (!next->is_bool()) return bad("tile_done's next must be true or false");
    done.next = next->as_bool();
  }
  auto count = read_count(body, "tile_done");
  if (!count) return count.error();
  done.count = *count;
  return done;
}

Value encode_peer_moved(const PeerMoved& moved) {
  return Value::Map{{"name", moved.name}, {"endpoint", moved.endpoint}, {"key", moved.key}};
}

Result<PeerMoved> decode_peer_moved(const Value& body) {
  const std::string *name = string_field(body, "name"), *endpoint = string_field(body, "endpoint");
  if (!name || !endpoint) return bad("a PEER_MOVED without name and endpoint");
  const std::string* key = string_field(body, "key");
  return PeerMoved{*name, *endpoint, key ? *key : std::string()};
}

Value encode_peer_down(const std::string& name) { return Value::Map{{"name", name}}; }

Result<std::string> decode_peer_down(const Value& body) {
  const std::string* name = string_field(body, "name");
  if (!name) return bad("a PEER_DOWN without a name");
  return *name;
}

Value::Map encode_frame(const FrameView& view) {
  Value::Map m{{"frame", static_cast<int64_t>(view.frame)}, {"camera", view.camera.to_value()}};
  if (view.renew) {
    Value::Array names;
    for (const auto& n : *view.renew) names.push_back(n);
    m["renew"] = std::move(names);
  }
  if (view.keep) m["keep"] = true;
  if (view.restore) m["restore"] = true;
  if (!view.materials.empty()) m["materials"] = view.materials;
  if (view.new_materials) m["new_materials"] = true;
  if (view.in_flight) m["in_flight"] = static_cast<int64_t>(*view.in_flight);
  return m;
}

Result<FrameView> decode_frame(const Value& body) {
  const Value* frame = body.find("frame");
  if (!frame || !frame->is_int() || frame->as_int() < INT_MIN || frame->as_int() > INT_MAX)
    return bad("a PHASE frame without a frame number");
  const Value* camera = body.find("camera");
  if (!camera) return bad("a PHASE frame without a camera");
  auto spec = CameraSpec::from_value(*camera);
  if (!spec) return bad("a PHASE frame's camera: " + spec.error().message);
  FrameView view{static_cast<int>(frame->as_int()), *spec, std::nullopt};
  if (const Value* renew = body.find("renew")) {
    if (!renew->is_array()) return bad("a PHASE frame's renew is not a list of names");
    view.renew.emplace();
    for (const Value& n : renew->as_array()) {
      if (!n.is_string()) return bad("a PHASE frame's renew is not a list of names");
      view.renew->push_back(n.as_string());
    }
  }
  for (auto [name, flag] : {std::pair{"keep", &view.keep}, std::pair{"restore", &view.restore},
                            std::pair{"new_materials", &view.new_materials}}) {
    const Value* v = body.find(name);
    if (v && !v->is_bool()) return bad(std::string("a PHASE frame's ") + name + " is not true or false");
    *flag = v && v->as_bool();
  }
  if (const Value* changes = body.find("materials")) {
    if (!is_material_change_list(*changes))
      return bad("a PHASE frame's materials are not a list of material changes, each a map with a name");
    view.materials = changes->as_array();
  }
  if (view.keep && view.restore) return bad("a PHASE frame asks to keep and to restore the same setup");
  if (view.new_materials && view.restore) return bad("a PHASE frame restores a kept setup where the materials change");
  if (const Value* earlier = body.find("in_flight")) {
    if (!earlier->is_int() || earlier->as_int() < INT_MIN || earlier->as_int() > INT_MAX || earlier->as_int() == view.frame)
      return bad("a PHASE frame's in_flight is not the number of another frame");
    view.in_flight = static_cast<int>(earlier->as_int());
  }
  if (view.in_flight && (view.restore || view.new_materials || view.renew))
    return bad("a PHASE frame in flight (the frame before still rendering) must be the job's next view, with the "
               "same materials, set up by every actor");
  return view;
}

}  // namespace lf::control
