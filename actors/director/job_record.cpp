#include "actors/director/job_record.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "render/images/image.hpp"      // write_file_whole
#include "render/scene/scene_file.hpp"  // content_hash

namespace lf {

namespace fs = std::filesystem;

namespace {

constexpr const char* kHeader = "lightfarm job record 1";

std::string read_all(const std::string& path, bool& ok) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  ok = static_cast<bool>(in) || in.eof();
  return ss.str();
}

}  // namespace

std::string file_checksum(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return {};
  bool ok = false;
  const std::string bytes = read_all(path, ok);
  return ok ? content_hash(bytes) : std::string();
}

std::string JobRecord::folder_for(const std::string& output_pattern) {
  const fs::path p(output_pattern);
  std::string name = p.filename().string();
  // The name without its extension and its run of '#' (and the separator before the run).
  const std::string ext = p.extension().string();
  name = name.substr(0, name.size() - ext.size());
  const size_t last = name.find_last_of('#');
  if (last != std::string::npos) {
    size_t first = last;
    while (first > 0 && name[first - 1] == '#') --first;
    if (first > 0 && (name[first - 1] == '.' || name[first - 1] == '_' || name[first - 1] == '-')) --first;
    name.erase(first, last + 1 - first);
  }
  if (name.empty()) name = "frames";
  return (p.parent_path() / (name + ".lfjob")).string();
}

JobRecord::JobRecord(const std::string& output_pattern) : folder_(folder_for(output_pattern)) {}

void JobRecord::load(std::string& note) {
  note.clear();
  frames_.clear();
  const std::string path = folder_ + "/frames";
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return;
  bool ok = false;
  std::istringstream in(read_all(path, ok));
  std::string line;
  if (!ok || !std::getline(in, line) || line != kHeader) {
    note = path + " is not a lightfarm job record; rendering every frame";
    return;
  }
  size_t skipped = 0;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    int number = 0;
    Entry e;
    if (!(fields >> number >> e.key >> e.checksum) || !std::getline(fields >> std::ws, e.file) || e.file.empty()) {
      ++skipped;
      continue;
    }
    frames_[number] = std::move(e);
  }
  if (skipped > 0) note = path + ": " + std::to_string(skipped) + " damaged line(s) skipped; those frames render again";
}

bool JobRecord::done(int number, const std::string& key, const std::string& output) const {
  auto it = frames_.find(number);
  if (it == frames_.end() || it->second.key != key || it->second.file != fs::path(output).filename().string())
    return false;
  return file_checksum(output) == it->second.checksum;
}

Status JobRecord::add(int number, const std::string& key, const std::string& output) {
  const std::string checksum = file_checksum(output);
  if (checksum.empty()) return make_error("cannot read " + output + " back to record it in " + folder_);
  frames_[number] = Entry{key, checksum, fs::path(output).filename().string()};
  std::string text = std::string(kHeader) + "\n";
  for (const auto& [n, e] : frames_) text += std::to_string(n) + " " + e.key + " " + e.checksum + " " + e.file + "\n";
  std::error_code ec;
  fs::create_directories(folder_, ec);
  const std::string path = folder_ + "/frames";
  sweep_stale_partials(path);
  if (ec || !write_file_whole(path, text)) return make_error("cannot write the job record " + path);
  return Ok{};
}

void JobRecord::clear() {
  frames_.clear();
  std::error_code ec;
  fs::remove(folder_ + "/frames", ec);
}

}  // namespace lf
