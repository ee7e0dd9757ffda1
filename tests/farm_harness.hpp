#pragma once
// The multi-process tests' fixture: a temporary folder per test and the no-leftovers check, over
// tests/process_harness.hpp (which runs the real lightfarm binary and finds what a farm leaves behind).
#include <gtest/gtest.h>

#include "tests/process_harness.hpp"

namespace lf::test {

// A test's own temporary folder, removed afterwards.
class FarmFixture : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("lightfarm-test-" + unique_tag());
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return path(name);
  }
  size_t files_in_dir() const {
    return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
  }
  static void expect_no_leftovers(const RunResult& r) {
    auto left = wait_no_leftovers(r.tag);
    EXPECT_TRUE(left.empty()) << left.size() << " lightfarm processes left behind, e.g. pid " << left[0];
  }
};

}  // namespace lf::test
