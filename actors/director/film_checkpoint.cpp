#include "actors/director/film_checkpoint.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/log.hpp"
#include "render/byte_io.hpp"
#include "render/images/image.hpp"  // partial_path
#include "render/scene/scene_file.hpp"  // content_hash
#include "transport/message.hpp"        // kProtocolVersion

namespace lf {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {
constexpr std::string_view kMagic = "LFRESUME1";
}

std::string frame_key(const FarmSpec& spec, const std::string& scene_hash, const CameraSpec& camera,
                      const Value::Array& materials) {
  // The renderers and the hosts are left out: which process renders a tile, and where, changes no pixel.
  Value::Array actors;
  for (const ActorSpec& a : spec.actors) {
    if (a.is_renderer()) continue;
    Value::Array inputs;
    for (int i : a.inputs) inputs.push_back(spec.actors[static_cast<size_t>(i)].name);
    actors.push_back(Value::Map{{"name", a.name}, {"kind", a.kind}, {"params", Value(a.params)},
                                {"runtime", Value(a.runtime)}, {"inputs", Value(inputs)}});
  }
  Value::Map image = spec.image.to_value().as_map();
  image.erase("output");  // where the image goes is not what it is (the file sits beside it anyway)
  Value what = Value::Map{{"protocol", static_cast<int64_t>(wire::kProtocolVersion)},
                                {"scene", spec.scene.to_value()},
                                {"scene_hash", scene_hash},
                                {"camera", camera.to_value()},
                                {"image", Value(image)},
                                {"lighting", spec.lighting >= 0 ? Value(spec.actors[static_cast<size_t>(spec.lighting)].name) : Value()},
                                {"actors", Value(actors)},
                                {"partition", static_cast<int64_t>(spec.partition_parts)}};
  // Only where a frame changes materials: the keys of every other frame stay those earlier builds recorded.
  if (!materials.empty()) what.as_map()["materials"] = materials;
  return content_hash(to_json(what));
}

FilmCheckpoint::FilmCheckpoint(std::string path, std::string key, int width, int height, int tile, double interval_seconds)
    : path_(std::move(path)), key_(std::move(key)), width_(width), height_(height), tile_(tile),
      interval_(interval_seconds), last_save_(Clock::now()) {}

size_t FilmCheckpoint::restore(RenderMaster& master, std::string& note) const {
  note.clear();
  if (!enabled()) return 0;
  sweep_stale_partials(path_);  // what a director killed while writing left
  std::error_code ec;
  if (!fs::is_regular_file(path_, ec)) return 0;
  std::ifstream in(path_, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  bytes::Reader r(bytes);
  std::string magic, key;
  uint32_t key_length = 0, width = 0, height = 0, tile = 0, count = 0;
  if (!r.str(magic, static_cast<uint32_t>(kMagic.size())) || magic != kMagic || !r.u32(key_length) ||
      !r.str(key, key_length) || !r.u32(width) || !r.u32(height) || !r.u32(tile) || !r.u32(count)) {
    note = path_ + " is damaged or not a lightfarm film; rendering the frame from its start";
    return 0;
  }
  if (key != key_ || width != static_cast<uint32_t>(width_) || height != static_cast<uint32_t>(height_) ||
      tile != static_cast<uint32_t>(tile_)) {
    note = path_ + " holds another frame's tiles (the scene, camera, image or network changed); rendering from the "
           "start, and this frame's tiles will replace it";
    return 0;
  }
  size_t restored = 0;
  std::vector<float> rgb;
  for (uint32_t k = 0; k < count; ++k) {
    uint64_t id = 0;
    if (!r.u64(id) || id >= master.total()) break;
    rgb.resize(3 * static_cast<size_t>(master.rect(id).pixel_count()));
    bool ok = r.room(rgb.size(), 4);
    for (size_t i = 0; ok && i < rgb.size(); ++i) ok = r.f32(rgb[i]);
    if (!ok || !master.restore(id, rgb)) break;
    ++restored;
  }
  note = "resumed from " + path_ + ": " + std::to_string(restored) + " of " + std::to_string(master.total()) +
         " tiles were done";
  return restored;
}

void FilmCheckpoint::save(const RenderMaster& master, bool now_anyway) {
  if (!enabled() || master.done() == saved_tiles_) return;
  if (!now_anyway && std::chrono::duration<double>(Clock::now() - last_save_).count() < interval_) return;
  std::string out(kMagic);
  bytes::put(out, static_cast<uint32_t>(key_.size()));
  out += key_;
  for (int v : {width_, height_, tile_}) bytes::put(out, static_cast<uint32_t>(v));
  bytes::put(out, static_cast<uint32_t>(master.done()));
  for (uint64_t id = 0; id < master.total(); ++id) {
    if (!master.is_done(id)) continue;
    bytes::put(out, id);
    const TileRect& t = master.rect(id);
    for (int y = t.y0; y < t.y1; ++y)
      for (int x = t.x0; x < t.x1; ++x) bytes::put_rgb(out, master.film().at(x, y));
  }
  if (!write_file_whole(path_, out)) {
    if (!warned_) log_warn("cannot write the frame's checkpoint " + path_ + "; the frame goes on without one");
    warned_ = true;
  }
  last_save_ = Clock::now();
  saved_tiles_ = master.done();
}

void FilmCheckpoint::remove() const {
  if (!enabled()) return;
  std::error_code ec;
  fs::remove(path_, ec);
}

}  // namespace lf
