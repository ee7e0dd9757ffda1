#include "actors/director/job_record.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

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

// content_hash's form: 16 hex digits.
bool is_hash(const std::string& s) {
  return s.size() == 16 && s.find_first_not_of("0123456789abcdef") == std::string::npos;
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
  read_into(frames_, note);
}

void JobRecord::read_into(std::map<int, Entry>& frames, std::string& note) const {
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
    if (!(fields >> number >> e.key >> e.checksum) || !is_hash(e.key) || !is_hash(e.checksum) ||
        !std::getline(fields >> std::ws, e.file) || e.file.empty()) {
      ++skipped;
      continue;
    }
    frames[number] = std::move(e);
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
  std::error_code ec;
  fs::create_directories(folder_, ec);
  const std::string path = folder_ + "/frames";
  // Other runs of the job may record frames in the same folder at the same time (a Slurm array's tasks, each with
  // its --frames): under the folder's lock, what they wrote is read back and kept beside this run's frames.
  const int lock = ::open((folder_ + "/lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) {
    if (lock >= 0) ::close(lock);
    return make_error("cannot lock the job record " + folder_ + "/lock");
  }
  std::map<int, Entry> on_disk;
  std::string note;
  read_into(on_disk, note);
  for (auto& [n, e] : on_disk) frames_.try_emplace(n, std::move(e));
  std::string text = std::string(kHeader) + "\n";
  for (const auto& [n, e] : frames_) text += std::to_string(n) + " " + e.key + " " + e.checksum + " " + e.file + "\n";
  sweep_stale_partials(path);
  const bool written = !ec && write_file_whole(path, text);
  ::close(lock);  // releases the lock
  if (!written) return make_error("cannot write the job record " + path);
  return Ok{};
}

void JobRecord::clear() {
  frames_.clear();
  std::error_code ec;
  fs::remove(folder_ + "/frames", ec);
}

}  // namespace lf
