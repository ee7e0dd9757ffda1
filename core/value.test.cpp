#include "core/value.hpp"

#include <gtest/gtest.h>

namespace lf {

TEST(Value, FloatsRoundTripThroughBytes) {
  std::vector<float> in{1.5f, -2.25f, 0.0f, 3.4e38f};
  Bytes b = floats_to_bytes(in);
  EXPECT_EQ(b.data.size(), 16u);
  // Little-endian float32: 1.5f is 0x3fc00000.
  EXPECT_EQ(static_cast<unsigned char>(b.data[3]), 0x3f);
  EXPECT_EQ(static_cast<unsigned char>(b.data[2]), 0xc0);
  std::vector<float> out;
  ASSERT_TRUE(bytes_to_floats(b, out));
  EXPECT_EQ(out, in);
}

TEST(Value, BytesOfWrongLengthAreRejected) {
  std::vector<float> out;
  EXPECT_FALSE(bytes_to_floats(Bytes{"abcde"}, out));
  std::vector<uint64_t> keys;
  EXPECT_FALSE(bytes_to_u64(Bytes{"abcd"}, keys));
}

TEST(Value, JsonEscapesAndNests) {
  Value v = Value::Map{{"a", Value::Array{1, 2.5, "x\"y"}}, {"b", true}, {"c", nullptr}};
  EXPECT_EQ(to_json(v), R"({"a":[1,2.5,"x\"y"],"b":true,"c":null})");
}

TEST(Value, FindOnlyInMaps) {
  Value m = Value::Map{{"k", 3}};
  ASSERT_NE(m.find("k"), nullptr);
  EXPECT_EQ(m.find("k")->as_int(), 3);
  EXPECT_EQ(m.find("missing"), nullptr);
  EXPECT_EQ(Value(5).find("k"), nullptr);
}

TEST(Value, MapOfBuildsTheBracedMapAndMovesBytesIn) {
  std::string payload(1 << 16, 'x');
  const char* before = payload.data();
  Value built = map_of("n", 3, "name", "direct", "p", Bytes{std::move(payload)});
  EXPECT_EQ(built, Value(Value::Map{{"n", 3}, {"name", "direct"}, {"p", Bytes{std::string(1 << 16, 'x')}}}));
  // The bytes are the ones handed in, not a copy (a braced Value::Map would have copied them).
  EXPECT_EQ(built.find("p")->as_bytes().data.data(), before);
  // A later key replaces an earlier one, as insert_or_assign does.
  EXPECT_EQ(map_of("k", 1, "k", 2), Value(Value::Map{{"k", 2}}));
}

}  // namespace lf
