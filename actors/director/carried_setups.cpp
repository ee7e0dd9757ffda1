#include "actors/director/carried_setups.hpp"

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "render/images/image.hpp"       // write_file_whole
#include "render/scene/scene_file.hpp"   // content_hash

namespace lf {

namespace fs = std::filesystem;

namespace {
constexpr std::string_view kMagic = "LFSETUP1";

// Actor names come from scripts: anything but a plain name character becomes '_' in the file's name (the file
// holds the name itself, so two names that map alike cannot be mistaken for each other).
std::string file_name_part(const std::string& actor) {
  std::string out = actor;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  return out;
}
}  // namespace

std::string setup_key(const std::string& previous, const std::string& frame) { return content_hash(previous + frame); }

void CarriedSetups::begin(std::string folder, std::map<int, std::string> keys_by_frame) {
  folder_ = std::move(folder);
  keys_ = std::move(keys_by_frame);
}

std::string CarriedSetups::path(const std::string& actor, int number) const {
  return folder_ + "/setups/" + file_name_part(actor) + "." + std::to_string(number) + ".setup";
}

Status CarriedSetups::on_request(const std::string& actor, wire::Op, uint64_t id, Value body, Outbox& out) {
  const Value* frame = body.find("frame");
  const Value* state = body.find("state");
  if (!frame || !frame->is_int() || !state || !state->is_bytes()) {
    out.refuse(actor, id, ErrorCode::bad_request, "keep_setup needs {frame: int, state: bin}");
    return Ok{};
  }
  const auto key = frame->as_int() >= INT32_MIN && frame->as_int() <= INT32_MAX
                       ? keys_.find(static_cast<int>(frame->as_int()))
                       : keys_.end();
  if (folder_.empty() || key == keys_.end()) {
    out.refuse(actor, id, ErrorCode::bad_request, "no frame " + std::to_string(frame->as_int()) + " of a job to keep a setup for");
    return Ok{};
  }
  const std::string& bytes = state->as_bytes().data;
  const std::string file = path(actor, key->first);
  // What this run kept last for the actor, if the state begins with it: only the rest is written.
  std::string base = "- 0";
  size_t from = 0;
  if (auto last = last_.find(actor); last != last_.end() && last->second.frame != key->first &&
                                     last->second.length <= bytes.size() &&
                                     content_hash(std::string_view(bytes).substr(0, last->second.length)) == last->second.prefix_hash) {
    base = std::to_string(last->second.frame) + " " + std::to_string(last->second.length);
    from = last->second.length;
  }
  std::error_code ec;
  fs::create_directories(folder_ + "/setups", ec);
  const std::string whole = content_hash(bytes);
  const std::string head = std::string(kMagic) + "\n" + actor + "\n" + key->second + "\n" + whole + "\n" + base + "\n";
  if (ec || !write_file_whole(file, head + std::string(std::string_view(bytes).substr(from)))) {
    out.refuse(actor, id, ErrorCode::failed, "cannot write " + file);
    return Ok{};
  }
  ++kept_, bytes_kept_ += bytes.size() - from;
  last_[actor] = Last{key->first, bytes.size(), whole};
  out.reply(actor, id, Value::Map{});
  return Ok{};
}

std::optional<std::string> CarriedSetups::find(const std::string& actor, int number) const {
  // The chain from `number` back to a whole state, then the bytes forward; each link checked as it is read.
  struct Link {
    std::string bytes, checksum;
    size_t base_length = 0;
  };
  std::vector<Link> chain;
  for (int at = number, more = 1; more;) {
    const auto key = keys_.find(at);
    if (folder_.empty() || key == keys_.end() || chain.size() > keys_.size()) return std::nullopt;
    std::ifstream in(path(actor, at), std::ios::binary);
    std::string magic, name, file_key, checksum, base;
    if (!in || !std::getline(in, magic) || magic != kMagic || !std::getline(in, name) || name != actor ||
        !std::getline(in, file_key) || file_key != key->second || !std::getline(in, checksum) || !std::getline(in, base))
      return std::nullopt;
    Link link{{}, checksum, 0};
    more = 0;
    if (base != "- 0") {
      int base_frame = 0;
      unsigned long long length = 0;
      char end = 0;
      if (std::sscanf(base.c_str(), "%d %llu%c", &base_frame, &length, &end) != 2 || base_frame == number) return std::nullopt;
      at = base_frame, more = 1;
      link.base_length = static_cast<size_t>(length);
    }
    std::stringstream rest;
    rest << in.rdbuf();
    link.bytes = rest.str();
    chain.push_back(std::move(link));
  }
  std::string state;
  for (auto link = chain.rbegin(); link != chain.rend(); ++link) {
    if (state.size() != link->base_length) return std::nullopt;  // the base is not the state this one grew from
    state += link->bytes;
    if (content_hash(state) != link->checksum) return std::nullopt;
  }
  return state;
}

void CarriedSetups::restored(const std::string& actor, int number, const std::string& state) {
  last_[actor] = Last{number, state.size(), content_hash(state)};
}

void CarriedSetups::clear(const std::string& folder) {
  std::error_code ec;
  fs::remove_all(folder + "/setups", ec);
}

}  // namespace lf
