// The farm's keys arrive on an actor's standard input as one line; these feed it through a pipe.
#include "actors/runtime/process.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <thread>

namespace lf {
namespace {

// Runs read_farm_keys_from_stdin with `text` written to its stdin (then EOF), stdin restored after.
Result<wire::FarmKeys> read_keys_from(const std::string& text) {
  int pipe_fds[2];
  EXPECT_EQ(::pipe(pipe_fds), 0);
  const int saved = ::dup(STDIN_FILENO);
  ::dup2(pipe_fds[0], STDIN_FILENO);
  ::close(pipe_fds[0]);
  std::thread writer([fd = pipe_fds[1], text] {
    for (size_t done = 0; done < text.size();) {
      const ssize_t w = ::write(fd, text.data() + done, text.size() - done);
      if (w <= 0) break;
      done += static_cast<size_t>(w);
    }
    ::close(fd);
  });
  auto keys = read_farm_keys_from_stdin();
  writer.join();
  ::dup2(saved, STDIN_FILENO);
  ::close(saved);
  return keys;
}

wire::FarmKeys farm_of(size_t actors) {
  wire::FarmKeys k;
  k.own = wire::make_curve_keypair();
  k.director = wire::make_curve_keypair().public_key;
  const std::string one = k.own.public_key;
  for (size_t i = 0; i < actors; ++i) k.allowed.push_back(one);
  return k;
}

TEST(FarmKeysOnStdin, ALargeFarmsLineArrivesWhole) {
  // 3,000 actors: 123 KB of public keys, past the 64 KiB an earlier reader stopped at.
  const wire::FarmKeys sent = farm_of(3000);
  auto got = read_keys_from(sent.to_line() + "\n");
  ASSERT_TRUE(got) << got.error().message;
  EXPECT_EQ(got->allowed.size(), 3000u);
  EXPECT_EQ(got->own.secret_key, sent.own.secret_key);
  EXPECT_EQ(got->director, sent.director);
}

TEST(FarmKeysOnStdin, ALineEndedByEofIsRead) {
  const wire::FarmKeys sent = farm_of(2);
  auto got = read_keys_from(sent.to_line());
  ASSERT_TRUE(got) << got.error().message;
  EXPECT_EQ(got->allowed.size(), 2u);
}

TEST(FarmKeysOnStdin, NothingOrGarbageIsAnError) {
  auto none = read_keys_from("");
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().message, "--curve: no keys on standard input");
  EXPECT_FALSE(read_keys_from("not keys\n"));
}

}  // namespace
}  // namespace lf
