// A job's kept setups driven message by message: what is kept is found again under the frame's key only, whole;
// a setup that grew is kept as what it added; a damaged or foreign file is not used.
#include "actors/director/carried_setups.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "actors/director/service_test_support.hpp"

namespace lf {
namespace {

namespace fs = std::filesystem;
using test::RecordingOutbox;
using wire::Op;

class CarriedSetupsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("lf_setups_" + std::to_string(::getpid()));
    fs::remove_all(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  Value keep(int frame, const std::string& state) { return Value::Map{{"frame", int64_t{frame}}, {"state", Bytes{state}}}; }
  size_t files() const {
    size_t n = 0;
    if (fs::exists(folder_ / "setups"))
      for ([[maybe_unused]] const auto& e : fs::directory_iterator(folder_ / "setups")) ++n;
    return n;
  }
  fs::path folder_;
};

TEST_F(CarriedSetupsTest, AKeptSetupIsFoundUnderItsFramesKeyOnly) {
  CarriedSetups kept;
  kept.begin(folder_.string(), {{1, "k1"}, {2, "k2"}, {3, "k3"}});
  RecordingOutbox out;
  const std::string state("records\0and\nnewlines", 20);
  ASSERT_TRUE(kept.on_request("indirect", Op::keep_setup, 7, keep(2, state), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_FALSE(sent[0].refused) << sent[0].message;
  EXPECT_EQ(sent[0].id, 7u);
  EXPECT_EQ(kept.kept(), 1u);
  EXPECT_EQ(kept.find("indirect", 2), state);
  EXPECT_FALSE(kept.find("indirect", 3));  // no file
  EXPECT_FALSE(kept.find("other", 2));     // another actor's
  // The same folder, the job changed (its views' keys differ): nothing is found.
  CarriedSetups changed;
  changed.begin(folder_.string(), {{2, "k2 of another camera"}});
  EXPECT_FALSE(changed.find("indirect", 2));
  CarriedSetups same;
  same.begin(folder_.string(), {{2, "k2"}});
  EXPECT_EQ(same.find("indirect", 2), state);
}

// A setup that grew from the one kept before is kept as what it added; every frame's state is found whole.
TEST_F(CarriedSetupsTest, AGrowingSetupIsKeptAsWhatEachFrameAdded) {
  CarriedSetups run;
  run.begin(folder_.string(), {{1, "k1"}, {2, "k2"}, {3, "k3"}, {4, "k4"}});
  RecordingOutbox out;
  const std::string one(4000, 'a'), two = one + std::string(100, 'b'), three = two + "c", other(50, 'z');
  ASSERT_TRUE(run.on_request("a", Op::keep_setup, 1, keep(1, one), out).ok());
  ASSERT_TRUE(run.on_request("b", Op::keep_setup, 2, keep(1, other), out).ok());
  ASSERT_TRUE(run.on_request("a", Op::keep_setup, 3, keep(2, two), out).ok());
  ASSERT_TRUE(run.on_request("a", Op::keep_setup, 4, keep(3, three), out).ok());
  ASSERT_TRUE(run.on_request("a", Op::keep_setup, 5, keep(4, other), out).ok());  // not grown from three: whole
  for (const auto& s : out.take()) EXPECT_FALSE(s.refused) << s.message;
  EXPECT_EQ(run.find("a", 1), one);
  EXPECT_EQ(run.find("a", 2), two);
  EXPECT_EQ(run.find("a", 3), three);
  EXPECT_EQ(run.find("a", 4), other);
  EXPECT_EQ(run.find("b", 1), other);
  EXPECT_LT(fs::file_size(folder_ / "setups" / "a.2.setup"), 400u) << "frame 2 keeps what it added to frame 1's";
  EXPECT_EQ(run.bytes_kept(), one.size() + 100 + 1 + other.size() + other.size());
  // Another run of the job finds them all.
  CarriedSetups later;
  later.begin(folder_.string(), {{1, "k1"}, {2, "k2"}, {3, "k3"}, {4, "k4"}});
  EXPECT_EQ(later.find("a", 3), three);
  // A run that restored frame 3 keeps frame 4's as what it adds to it.
  later.restored("a", 3, three);
  RecordingOutbox later_out;
  ASSERT_TRUE(later.on_request("a", Op::keep_setup, 6, keep(4, three + "d"), later_out).ok());
  EXPECT_EQ(later.find("a", 4), three + "d");
  EXPECT_LT(fs::file_size(folder_ / "setups" / "a.4.setup"), 400u);
  ASSERT_TRUE(later.on_request("a", Op::keep_setup, 7, keep(4, other), later_out).ok());
  // A lost base: what grew from it is lost too, the rest is not.
  fs::remove(folder_ / "setups" / "a.1.setup");
  EXPECT_FALSE(later.find("a", 2));
  EXPECT_FALSE(later.find("a", 3));
  EXPECT_EQ(later.find("a", 4), other);
  CarriedSetups::clear(folder_.string());  // --restart
  EXPECT_EQ(files(), 0u);
  EXPECT_FALSE(later.find("a", 4));
}

TEST_F(CarriedSetupsTest, ADamagedFileIsNotUsed) {
  CarriedSetups kept;
  kept.begin(folder_.string(), {{1, "k1"}});
  RecordingOutbox out;
  ASSERT_TRUE(kept.on_request("a/b c", Op::keep_setup, 1, keep(1, std::string(1000, 'x')), out).ok());
  ASSERT_EQ(kept.find("a/b c", 1), std::string(1000, 'x'));  // a name that is no file name still finds its file
  ASSERT_EQ(files(), 1u);
  const fs::path file = fs::directory_iterator(folder_ / "setups")->path();
  fs::resize_file(file, fs::file_size(file) - 1);  // cut short, as by a full disk
  EXPECT_FALSE(kept.find("a/b c", 1));
  std::ofstream(file, std::ios::trunc) << "garbage";
  EXPECT_FALSE(kept.find("a/b c", 1));
}

TEST_F(CarriedSetupsTest, WhatCannotBeKeptIsRefused) {
  CarriedSetups kept;
  RecordingOutbox out;
  ASSERT_TRUE(kept.on_request("a", Op::keep_setup, 1, keep(1, "x"), out).ok());  // no job
  kept.begin(folder_.string(), {{1, "k1"}});
  ASSERT_TRUE(kept.on_request("a", Op::keep_setup, 2, keep(5, "x"), out).ok());  // no such frame
  ASSERT_TRUE(kept.on_request("a", Op::keep_setup, 3, Value::Map{{"frame", int64_t{1}}}, out).ok());
  ASSERT_TRUE(kept.on_request("a", Op::keep_setup, 4, Value::Map{{"frame", "1"}, {"state", Bytes{"x"}}}, out).ok());
  const auto sent = out.take();
  ASSERT_EQ(sent.size(), 4u);
  for (const auto& s : sent) EXPECT_TRUE(s.refused && s.code == ErrorCode::bad_request) << s.id;
  EXPECT_EQ(kept.kept(), 0u);
  EXPECT_EQ(files(), 0u);
}

}  // namespace
}  // namespace lf
