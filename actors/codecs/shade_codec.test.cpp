#include "actors/codecs/shade_codec.hpp"

#include <gtest/gtest.h>

namespace lf {

static ShadingPoints sample_points(size_t n) {
  ShadingPoints p;
  for (size_t i = 0; i < n; ++i) {
    float f = static_cast<float>(i);
    p.push_back({f, f + 1, f + 2}, {0, 1, 0}, {0, 0, 1}, static_cast<uint32_t>(i % 3), 1000 + i);
  }
  return p;
}

TEST(ShadeCodec, RequestRoundTripsASlice) {
  auto pts = sample_points(10);
  auto back = decode_shade_request(encode_shade_request(pts, 2, 7), 3);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->size(), 5u);
  EXPECT_EQ(back->position[0], pts.position[2]);
  EXPECT_EQ(back->key[4], pts.key[6]);
  EXPECT_EQ(back->material[1], pts.material[3]);
}

TEST(ShadeCodec, InconsistentRequestsAreRefusedWithAReason) {
  auto body = encode_shade_request(sample_points(4), 0, 4);
  body.as_map()["n"] = 5;
  EXPECT_EQ(decode_shade_request(body, 3).error().message, "shade request 'p' holds 48 bytes, expected 60");
  body = encode_shade_request(sample_points(4), 0, 4);
  EXPECT_EQ(decode_shade_request(body, 2).error().message, "shade request: point 2 has material 2 but the scene has 2");
  body.as_map().erase("k");
  EXPECT_EQ(decode_shade_request(body, 3).error().message, "shade request 'k' must hold 4 u64 sample keys");
  body.as_map()["n"] = -1;
  EXPECT_EQ(decode_shade_request(body, 3).error().message, "shade request: 'n' (point count) missing or negative");
}

TEST(ShadeCodec, RadianceCountMustMatch) {
  std::vector<RGB> l{{1, 2, 3}, {4, 5, 6}};
  auto ok = decode_radiance(encode_radiance(l), 2);
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ((*ok)[1], (RGB{4, 5, 6}));
  EXPECT_EQ(decode_radiance(encode_radiance(l), 3).error().message, "shade reply holds 2 radiance values, expected 3");
  // A reply whose n disagrees with its data is refused even when the data has the right size.
  Value lying = encode_radiance(l);
  lying.as_map()["n"] = 3;
  auto refused = decode_radiance(lying, 2);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message, "shade reply says n = 3 but holds 2 radiance values");
  EXPECT_EQ(refused.error().code, ErrorCode::bad_message);
  lying.as_map().erase("n");
  EXPECT_FALSE(decode_radiance(lying, 2).ok());
}

}  // namespace lf
