// Private folders in /tmp: made 0700 and named after their owner; a folder whose owner died is swept, a live
// owner's never.
#include "core/private_dir.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace lf {
namespace {

namespace fs = std::filesystem;

TEST(PrivateDir, IsMadeForItsOwnerAlone) {
  const std::string dir = make_private_dir("test");
  ASSERT_FALSE(dir.empty());
  EXPECT_EQ(dir.rfind("/tmp/lightfarm-test-" + std::to_string(::getpid()) + "-", 0), 0u) << dir;
  struct stat st {};
  ASSERT_EQ(::stat(dir.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700u);
  fs::remove_all(dir);
}

TEST(PrivateDir, ADeadOwnersFolderIsSweptALiveOnesIsNot) {
  const std::string mine = make_private_dir("sweeptest");
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Dies without cleaning up, as a SIGKILLed process would.
    const std::string dir = make_private_dir("sweeptest");
    std::ofstream(dir + "/socket") << "x";
    (void)!::write(pipe_fds[1], dir.c_str(), dir.size());
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  char buffer[256] = {};
  ASSERT_GT(::read(pipe_fds[0], buffer, sizeof buffer - 1), 0);
  ::close(pipe_fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  const std::string orphan = buffer;
  ASSERT_TRUE(fs::exists(orphan + "/socket"));
  const std::string odd = "/tmp/lightfarm-sweeptest-notapid";
  fs::create_directories(odd);

  EXPECT_EQ(sweep_stale_private_dirs("sweeptest"), 1);
  EXPECT_FALSE(fs::exists(orphan));
  EXPECT_TRUE(fs::exists(mine));
  EXPECT_TRUE(fs::exists(odd));  // not a name this module makes: left alone
  EXPECT_EQ(sweep_stale_private_dirs("sweeptest"), 0);
  fs::remove_all(mine);
  fs::remove_all(odd);
}

}  // namespace
}  // namespace lf
