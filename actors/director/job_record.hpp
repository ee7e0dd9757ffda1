#pragma once
// JobRecord: what a job of frames has finished, in a folder beside its outputs (walk.####.png -> walk.lfjob/), so
// that `lightfarm run` again after Ctrl-C, a killed director, a lost host or a reboot renders only the frames not
// done. Its file `frames` has a line per finished frame:
//   <frame> <key> <checksum of the image file's bytes> <the image file's name>
// (the key: frame_key, what the frame's pixels depend on). A frame counts as done only while its key is the one
// the frame has now and its file still has the recorded checksum: a changed scene, camera or network, or an image
// deleted or overwritten since, renders it again. The file is written whole (renamed into place) after each frame,
// under a lock on the folder (flock on OUTPUT.lfjob/lock), merged with what other runs of the job recorded
// meanwhile: the tasks of a Slurm array may share the folder on a file system whose clients honour flock (NFSv4,
// Lustre and BeeGFS mounted with locking, any local one).
#include <map>
#include <string>

#include "core/result.hpp"

namespace lf {

class JobRecord {
 public:
  // The record of the job whose outputs follow `output_pattern` (its #### and the separator before them left out).
  explicit JobRecord(const std::string& output_pattern);
  static std::string folder_for(const std::string& output_pattern);
  const std::string& folder() const { return folder_; }

  // Reads the record; a missing one is a job not yet begun. `note`: what was found that cannot be used.
  void load(std::string& note);
  // Whether frame `number` is done: recorded with `key`, and `output` holds the bytes it was recorded with.
  bool done(int number, const std::string& key, const std::string& output) const;
  // Frame `number` was written to `output`: recorded (the folder made if need be), with the frames other runs
  // recorded since this one loaded. An error says why it could not be.
  Status add(int number, const std::string& key, const std::string& output);
  // --restart: the record is forgotten (the folder's file removed).
  void clear();

 private:
  struct Entry {
    std::string key, checksum, file;
  };
  // The file's lines into `frames` (a missing file adds nothing); `note`: what could not be used.
  void read_into(std::map<int, Entry>& frames, std::string& note) const;
  std::string folder_;
  std::map<int, Entry> frames_;
};

// The checksum the record keeps of a file (empty if it cannot be read).
std::string file_checksum(const std::string& path);

}  // namespace lf
