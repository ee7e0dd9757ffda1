#include "actors/codecs/trace_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace lf {
namespace {

TEST(TraceCodec, RaysHitsAndOcclusionComeBackAsSent) {
  const std::vector<Ray> rays{Ray{{1, 2, 3}, {0, 0, 1}}, Ray{{-1, 0.5f, 2}, {0.6f, 0.8f, 0}, 0.01f, 7.5f}};
  for (bool any : {false, true}) {
    auto back = decode_trace_request(encode_trace_request(rays, any), 16);
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_EQ(back->any, any);
    ASSERT_EQ(back->rays.size(), 2u);
    EXPECT_EQ(back->rays[1].origin, rays[1].origin);
    EXPECT_EQ(back->rays[1].direction, rays[1].direction);
    EXPECT_EQ(back->rays[1].tnear, 0.01f);
    EXPECT_EQ(back->rays[1].tfar, 7.5f);
    EXPECT_EQ(back->rays[0].tfar, std::numeric_limits<float>::infinity());
  }
  const std::vector<Hit> hits{Hit{4, 1.5f}, Hit{}};
  auto h = decode_hits(encode_hits(hits), 2, 10);
  ASSERT_TRUE(h) << h.error().message;
  EXPECT_EQ((*h)[0].triangle, 4u);
  EXPECT_EQ((*h)[0].t, 1.5f);
  EXPECT_FALSE((*h)[1].valid());
  const std::vector<uint8_t> blocked{1, 0, 1};
  auto o = decode_occlusion(encode_occlusion(blocked), 3);
  ASSERT_TRUE(o) << o.error().message;
  EXPECT_EQ(*o, blocked);
}

TEST(TraceCodec, BadBodiesAreRefusedWithAReason) {
  const std::vector<Ray> rays{Ray{{1, 2, 3}, {0, 0, 1}}};
  Value body = encode_trace_request(rays, false);
  body.as_map()["n"] = int64_t{2};
  EXPECT_EQ(decode_trace_request(body, 16).error().message, "trace request 'r' must hold 2 rays of 8 floats");
  EXPECT_NE(decode_trace_request(encode_trace_request(rays, false), 0).error().message.find("more than the 0"),
            std::string::npos);
  Ray bad{{std::nanf(""), 0, 0}, {0, 0, 1}};
  EXPECT_EQ(decode_trace_request(encode_trace_request(std::vector<Ray>{bad}, false), 16).error().message,
            "trace request: ray 0 has a coordinate that is not finite");
  Ray inf_dir{{0, 0, 0}, {0, std::numeric_limits<float>::infinity(), 1}};
  EXPECT_FALSE(decode_trace_request(encode_trace_request(std::vector<Ray>{inf_dir}, true), 16));
  Value any = encode_trace_request(rays, false);
  any.as_map()["any"] = "yes";
  EXPECT_EQ(decode_trace_request(any, 16).error().message, "trace request 'any' must be true or false");
  EXPECT_FALSE(decode_trace_request(Value::Map{{"n", int64_t{-1}}}, 16));
  // A reply that names a triangle the scene does not have, or holds the wrong count.
  EXPECT_EQ(decode_hits(encode_hits(std::vector<Hit>{Hit{12, 1}}), 1, 10).error().message,
            "trace reply names triangle 12, which the scene does not have");
  EXPECT_FALSE(decode_hits(encode_hits(std::vector<Hit>{Hit{1, 1}}), 2, 10));
  EXPECT_FALSE(decode_occlusion(encode_occlusion(std::vector<uint8_t>{1}), 2));
}

}  // namespace
}  // namespace lf
