// FilmCheckpoint alone: finished tiles round-trip with their pixels bit for bit; a file of another frame (another
// key or size) or a damaged one restores nothing and says so; writes wait for the interval unless forced; a dead
// writer's temporary is swept.
#include "actors/director/film_checkpoint.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace lf {
namespace {

namespace fs = std::filesystem;

struct Files {
  fs::path dir = fs::temp_directory_path() / ("lightfarm-checkpoint-" + std::to_string(::getpid()));
  Files() { fs::create_directories(dir); }
  ~Files() { fs::remove_all(dir); }
  std::string path() const { return (dir / "x.png.lfresume").string(); }
};

TEST(FilmCheckpoint, FinishedTilesComeBackBitForBit) {
  Files f;
  RenderMaster before(20, 12, 8);
  for (uint64_t id : {0u, 2u}) {
    std::vector<float> rgb;
    const TileRect& t = before.rect(id);
    for (int y = t.y0; y < t.y1; ++y)
      for (int x = t.x0; x < t.x1; ++x) rgb.insert(rgb.end(), {x + 0.25f, y + 0.5f, 1.0f / (1 + x + y)});
    ASSERT_TRUE(before.restore(id, rgb));
  }
  FilmCheckpoint written(f.path(), "key", 20, 12, 8, 1000);
  written.save(before);  // within the interval: nothing yet
  EXPECT_FALSE(fs::exists(f.path()));
  written.save(before, true);
  ASSERT_TRUE(fs::exists(f.path()));

  RenderMaster after(20, 12, 8);
  std::string note;
  EXPECT_EQ(FilmCheckpoint(f.path(), "key", 20, 12, 8, 1).restore(after, note), 2u);
  EXPECT_EQ(note, "resumed from " + f.path() + ": 2 of 6 tiles were done");
  for (uint64_t id = 0; id < after.total(); ++id) EXPECT_EQ(after.is_done(id), id == 0 || id == 2) << id;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 20; ++x) EXPECT_TRUE(after.film().at(x, y) == before.film().at(x, y)) << x << " " << y;
  // The rest is still handed out, and only the rest.
  int handed = 0;
  while (auto a = after.next("r")) {
    EXPECT_NE(a->id, 0u);
    EXPECT_NE(a->id, 2u);
    ++handed;
  }
  EXPECT_EQ(handed, 4);

  RenderMaster other(20, 12, 8);
  EXPECT_EQ(FilmCheckpoint(f.path(), "another key", 20, 12, 8, 1).restore(other, note), 0u);
  EXPECT_NE(note.find("holds another frame's tiles"), std::string::npos) << note;
  EXPECT_EQ(FilmCheckpoint(f.path(), "key", 20, 12, 4, 1).restore(other, note), 0u);  // another tile size
  EXPECT_EQ(other.done(), 0u);

  std::ofstream(f.path(), std::ios::binary | std::ios::trunc) << "LFRESUME1\x05";
  EXPECT_EQ(FilmCheckpoint(f.path(), "key", 20, 12, 8, 1).restore(other, note), 0u);
  EXPECT_EQ(note, f.path() + " is damaged or not a lightfarm film; rendering the frame from its start");

  // A temporary whose writer is gone (a director killed while writing) goes; one still being written stays.
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const fs::path stale = f.dir / (".x.png.partial-" + std::to_string(dead) + ".lfresume");
  const fs::path live = f.dir / (".x.png.partial-" + std::to_string(::getpid()) + ".lfresume");
  std::ofstream(stale) << "half";
  std::ofstream(live) << "being written";
  FilmCheckpoint(f.path(), "key", 20, 12, 8, 1).restore(other, note);
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));

  FilmCheckpoint(f.path(), "key", 20, 12, 8, 1).remove();
  EXPECT_FALSE(fs::exists(f.path()));
  EXPECT_EQ(FilmCheckpoint(f.path(), "key", 20, 12, 8, 1).restore(other, note), 0u);
  EXPECT_TRUE(note.empty()) << "no file: nothing to say";
}

}  // namespace
}  // namespace lf
