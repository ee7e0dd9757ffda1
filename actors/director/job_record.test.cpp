// JobRecord alone: where a job's record lives, what counts as a frame done (its key, its file's bytes), a damaged
// record, --restart, and two runs of one job recording frames in the same folder.
#include "actors/director/job_record.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace lf {
namespace {

namespace fs = std::filesystem;

struct Folder {
  fs::path dir = fs::temp_directory_path() / ("lightfarm-job-record-" + std::to_string(::getpid()));
  Folder() { fs::create_directories(dir); }
  ~Folder() { fs::remove_all(dir); }
  std::string at(const std::string& name) const { return (dir / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return at(name);
  }
};

TEST(JobRecord, FolderBesideTheOutputsWithoutTheFrameNumber) {
  EXPECT_EQ(JobRecord::folder_for("out/walk.####.png"), "out/walk.lfjob");
  EXPECT_EQ(JobRecord::folder_for("walk_##.exr"), "walk.lfjob");
  EXPECT_EQ(JobRecord::folder_for("####.png"), "frames.lfjob");
  EXPECT_EQ(JobRecord::folder_for("still.png"), "still.lfjob");
}

TEST(JobRecord, AFrameIsDoneWhileItsKeyAndItsFileAreUnchanged) {
  Folder f;
  const std::string pattern = f.at("t.####.png");
  JobRecord record(pattern);
  std::string note;
  record.load(note);
  EXPECT_TRUE(note.empty());
  const std::string one = f.write("t.0001.png", "frame one"), two = f.write("t.0002.png", "frame two");
  ASSERT_TRUE(record.add(1, "00000000000000a1", one).ok());
  ASSERT_TRUE(record.add(2, "00000000000000a2", two).ok());

  JobRecord again(pattern);
  again.load(note);
  EXPECT_TRUE(note.empty()) << note;
  EXPECT_TRUE(again.done(1, "00000000000000a1", one));
  EXPECT_TRUE(again.done(2, "00000000000000a2", two));
  EXPECT_FALSE(again.done(1, "00000000000000ff", one)) << "another scene, camera or network";
  EXPECT_FALSE(again.done(3, "00000000000000a1", one)) << "never recorded";
  f.write("t.0002.png", "frame two, overwritten");
  EXPECT_FALSE(again.done(2, "00000000000000a2", two)) << "the file's bytes changed";
  fs::remove(one);
  EXPECT_FALSE(again.done(1, "00000000000000a1", one)) << "the file is gone";

  again.clear();
  JobRecord restarted(pattern);
  restarted.load(note);
  f.write("t.0001.png", "frame one");
  EXPECT_FALSE(restarted.done(1, "00000000000000a1", one)) << "--restart forgets the record";
}

TEST(JobRecord, ADamagedRecordIsSaidAndItsBadLinesRenderAgain) {
  Folder f;
  fs::create_directories(f.dir / "t.lfjob");
  const std::string one = f.write("t.0001.png", "frame one");
  JobRecord writer(f.at("t.####.png"));
  ASSERT_TRUE(writer.add(1, "00000000000000a1", one).ok());
  std::ofstream(f.dir / "t.lfjob" / "frames", std::ios::app) << "2 half a line\n";
  JobRecord reader(f.at("t.####.png"));
  std::string note;
  reader.load(note);
  EXPECT_NE(note.find("1 damaged line(s) skipped"), std::string::npos) << note;
  EXPECT_TRUE(reader.done(1, "00000000000000a1", one));
  std::ofstream(f.dir / "t.lfjob" / "frames") << "something else\n";
  reader.load(note);
  EXPECT_NE(note.find("is not a lightfarm job record"), std::string::npos) << note;
  EXPECT_FALSE(reader.done(1, "00000000000000a1", one));
}

// Two runs (a Slurm array's tasks) that loaded the record before either wrote: each keeps the other's frames.
TEST(JobRecord, RunsSharingTheFolderKeepEachOthersFrames) {
  Folder f;
  const std::string pattern = f.at("t.####.png");
  JobRecord a(pattern), b(pattern);
  std::string note;
  a.load(note);
  b.load(note);
  const std::string one = f.write("t.0001.png", "1"), two = f.write("t.0002.png", "2"), three = f.write("t.0003.png", "3");
  ASSERT_TRUE(a.add(1, "00000000000000a1", one).ok());
  ASSERT_TRUE(b.add(2, "00000000000000a2", two).ok());
  ASSERT_TRUE(a.add(3, "00000000000000a3", three).ok());
  JobRecord reader(pattern);
  reader.load(note);
  EXPECT_TRUE(reader.done(1, "00000000000000a1", one));
  EXPECT_TRUE(reader.done(2, "00000000000000a2", two));
  EXPECT_TRUE(reader.done(3, "00000000000000a3", three));
}

}  // namespace
}  // namespace lf
