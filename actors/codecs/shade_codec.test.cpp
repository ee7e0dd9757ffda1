#include "actors/codecs/shade_codec.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "render/test_support.hpp"
#include "transport/message.hpp"

namespace lf {

TEST(ShadeCodec, RequestRoundTripsASlice) {
  auto pts = test::numbered_points(10);
  auto back = decode_shade_request(encode_shade_request(pts, 2, 7));
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->n, 5u);
  EXPECT_EQ(back->points.position[0], pts.position[2]);
  EXPECT_EQ(back->points.key[4], pts.key[6]);
  EXPECT_EQ(back->points.material[1], pts.material[3]);
  EXPECT_FALSE(back->origin || back->tile);
}

// What is left out stays out: the decoder rebuilds nothing (actors/runtime/lean_points.hpp does).
TEST(ShadeCodec, FieldsLeftOutComeBackEmpty) {
  ShadingPoints pts = test::numbered_points(6);
  for (uint32_t i = 0; i < pts.size(); ++i) pts.triangle.push_back(i);
  auto back = decode_shade_request(encode_shade_request(pts, 1, 5, {.normal = false, .material = false}));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(back->points.normal.empty());
  EXPECT_TRUE(back->points.material.empty());
  EXPECT_EQ(back->points.triangle, (std::vector<uint32_t>{1, 2, 3, 4}));
  TileWork work;
  work.rect = TileRect{2, 3, 5, 5};
  work.spp = 2;
  work.eye = Vec3{1, 2, 3};
  work.points = pts;
  for (uint32_t i = 0; i < pts.size(); ++i) {
    work.sample_of_point.push_back(2 * i + 1);
    work.distance.push_back(0.5f + static_cast<float>(i));
  }
  const Value body = encode_tile_request(work, 1, 5, {.position = false, .key = false}, true);
  auto tile = decode_shade_request(body);
  ASSERT_TRUE(tile.ok()) << tile.error().message;
  EXPECT_TRUE(tile->points.position.empty());
  EXPECT_TRUE(tile->points.key.empty());
  ASSERT_TRUE(tile->origin && tile->tile);
  EXPECT_EQ(*tile->origin, work.eye);
  EXPECT_EQ(tile->distance, (std::vector<float>{1.5f, 2.5f, 3.5f, 4.5f}));
  EXPECT_EQ(tile->tile->x0, 2);
  EXPECT_EQ(tile->tile->y1, 5);
  EXPECT_EQ(tile->spp, 2);
  EXPECT_EQ(tile->samples, (std::vector<uint32_t>{3, 5, 7, 9}));
  auto fold = decode_pixel_fold(body);
  ASSERT_TRUE(fold.ok() && fold->has_value());
  EXPECT_EQ((*fold)->samples, tile->samples);
  // Keys that travel as keys cannot be folded by: fold is then not asked for.
  EXPECT_EQ(encode_tile_request(work, 1, 5, {.position = false}, true).find("fold"), nullptr);
}

TEST(ShadeCodec, InconsistentRequestsAreRefusedWithAReason) {
  auto body = encode_shade_request(test::numbered_points(4), 0, 4);
  body.as_map()["n"] = 5;
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request 'wo' holds 48 bytes, expected 60");
  body = encode_shade_request(test::numbered_points(4), 0, 4);
  body.as_map().erase("k");
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request 'k' must hold 4 u64 sample keys");
  body.as_map()["n"] = -1;
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request: 'n' (point count) missing or negative");
  body = encode_shade_request(test::numbered_points(4), 0, 4);
  body.as_map().erase("p");
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request has no 'p' array");
  body.as_map()["o"] = Bytes{"xyz"};
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request has neither 'p' nor a ray origin 'o' of 3 floats");
  body = encode_shade_request(test::numbered_points(4), 0, 4);
  body.as_map().erase("k");
  body.as_map()["s"] = Bytes{"abcd"};
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{0}, int64_t{1}, int64_t{1}};
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request has neither 'k' nor a tile [x0, y0, x1, y1, spp]");
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{2}, int64_t{1}, int64_t{1}};
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request 's' must hold 4 u32 sample indices");
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{2}, int64_t{1}, int64_t{1}, int64_t{-1}};
  EXPECT_EQ(decode_shade_request(body).error().message, "shade request has neither 'k' nor a tile [x0, y0, x1, y1, spp]")
      << "a pass's first sample is an index";
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

TEST(ShadeCodec, ASliceCutsEveryArrayAndDecodesAsThosePoints) {
  ShadingPoints pts = test::numbered_points(14);
  for (uint32_t i = 0; i < pts.size(); ++i) pts.triangle.push_back(i);
  for (PointFields fields : {PointFields{}, PointFields{.normal = false, .material = false}}) {
    const Value body = encode_shade_request(pts, 0, pts.size(), fields);
    auto slice = slice_shade_request(body, 3, 11);
    ASSERT_TRUE(slice.ok()) << slice.error().message;
    EXPECT_EQ(*slice, encode_shade_request(pts, 3, 11, fields));
  }
  Value body = encode_shade_request(pts, 0, pts.size());
  EXPECT_EQ(slice_shade_request(body, 3, pts.size() + 1).error().message, "shade request: slice out of range");
  body.as_map()["k"] = Bytes{"short"};
  EXPECT_EQ(slice_shade_request(body, 0, 2).error().message,
            "shade request 'k' must hold " + std::to_string(pts.size()) + " entries of 8 bytes");
}

TEST(ShadeCodec, AFoldWithoutItsTileOrSamplesIsRefused) {
  auto pts = test::numbered_points(4);
  Value body = encode_shade_request(pts, 0, 4);
  auto why = [&] {
    auto r = decode_pixel_fold(body);
    return r.ok() ? std::string("ok") : r.error().message;
  };
  body.as_map()["fold"] = int64_t{1};
  EXPECT_EQ(why(), "shade request 'fold' must be true or false");
  body.as_map()["fold"] = true;
  EXPECT_EQ(why(), "shade request: 'fold' needs a tile [x0, y0, x1, y1, spp]");
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{2}, int64_t{2}, int64_t{0}};
  EXPECT_EQ(why(), "shade request: 'fold' needs a tile [x0, y0, x1, y1, spp]") << "spp 0";
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{2}, int64_t{2}, int64_t{2}};
  EXPECT_EQ(why(), "shade request: 'fold' needs 's' with 4 u32 sample indices");
  const uint32_t s[] = {0, 1, 3, 6};
  body.as_map()["s"] = u32_to_bytes(std::span<const uint32_t>(s));
  auto fold = decode_pixel_fold(body);
  ASSERT_TRUE(fold.ok()) << fold.error().message;
  EXPECT_EQ((*fold)->runs(), 3u);  // pixels 0, 1, 3
}

}  // namespace lf

namespace lf {

// Frames in flight: a request names the frame whose view it is shaded for, every slice a pool cuts keeps it, and a
// view that is no frame number is refused.
TEST(ShadeCodec, AViewTravelsWithTheRequestAndItsSlices) {
  ShadingPoints pts = test::numbered_points(8);
  Value body = encode_shade_request(pts, 0, pts.size());
  EXPECT_EQ(*decode_shade_view(body), std::nullopt);
  set_shade_view(body, 7);
  EXPECT_EQ(*decode_shade_view(body), std::optional<int>(7));
  auto slice = slice_shade_request(body, 2, 5);
  ASSERT_TRUE(slice.ok()) << slice.error().message;
  EXPECT_EQ(*decode_shade_view(*slice), std::optional<int>(7));
  body.as_map()["view"] = -3;  // frame numbers may be negative
  EXPECT_EQ(*decode_shade_view(body), std::optional<int>(-3));
  body.as_map()["view"] = int64_t{1} << 40;
  EXPECT_EQ(decode_shade_view(body).error().message, "shade request 'view' must be a frame number");
  body.as_map()["view"] = "seven";
  EXPECT_FALSE(decode_shade_view(body).ok());
}

}  // namespace lf
