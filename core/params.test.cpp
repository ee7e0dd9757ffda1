#include "core/params.hpp"

#include <gtest/gtest.h>

namespace lf {

TEST(ParamTable, ReadsWithDefaultsAndRanges) {
  ParamTable p(Value::Map{{"samples", 8}, {"gain", 0.5}, {"mode", "fast"}}, "lightop 'x'");
  EXPECT_EQ(p.get_int("samples", 1, 1, 100), 8);
  EXPECT_EQ(p.get_int("absent", 7, 1, 100), 7);
  EXPECT_DOUBLE_EQ(p.get_float("gain", 1.0, 0.0, 1.0), 0.5);
  EXPECT_EQ(p.get_string("mode", "slow", {"fast", "slow"}), "fast");
  EXPECT_NO_THROW(p.report_unused());
}

TEST(ParamTable, OutOfRangeNamesParameterAndRange) {
  ParamTable p(Value::Map{{"samples", 0}}, "lightop 'direct'");
  try {
    p.get_int("samples", 1, 1, 100);
    FAIL() << "expected ParamError";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "lightop 'direct': parameter 'samples' must be in [1, 100], got 0");
  }
}

TEST(ParamTable, WrongTypeAndFractionsAreErrors) {
  ParamTable p(Value::Map{{"n", "four"}, {"m", 2.5}}, "o");
  EXPECT_THROW(p.get_int("n", 1, 0, 10), ParamError);
  EXPECT_THROW(p.get_int("m", 1, 0, 10), ParamError);
}

TEST(ParamTable, UnusedParametersAreReportedWithKnownOnes) {
  ParamTable p(Value::Map{{"light_sample", 4}}, "lightop 'direct'");
  p.get_int("light_samples", 1, 1, 100);
  try {
    p.report_unused();
    FAIL() << "expected ParamError";
  } catch (const ParamError& e) {
    EXPECT_STREQ(e.what(), "lightop 'direct': unknown parameter 'light_sample' (known: light_samples)");
  }
}

}  // namespace lf
