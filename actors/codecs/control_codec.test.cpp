// The director's tile and peer bodies: each round-trips, and each decoder refuses what is malformed with a message.
#include "actors/codecs/control_codec.hpp"

#include <gtest/gtest.h>

namespace lf::control {
namespace {

TEST(ControlCodec, TilesRoundTripAndStayInsideTheImage) {
  const Tile tile{7, TileRect{32, 0, 64, 16}};
  auto back = decode_tile_reply(encode_tile_reply(tile), 64, 48);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->size(), 1u);
  EXPECT_EQ((*back)[0].id, 7u);
  EXPECT_EQ((*back)[0].rect.x0, 32);
  EXPECT_EQ((*back)[0].rect.y1, 16);
  auto none = decode_tile_reply(encode_tile_reply(std::nullopt), 64, 48);
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->empty()) << "no tile left";
  auto outside = decode_tile_reply(encode_tile_reply(tile), 48, 48);
  ASSERT_FALSE(outside.ok());
  EXPECT_EQ(outside.error().message, "the render master sent a tile outside the image");
  EXPECT_FALSE(decode_tile_reply(encode_tile_reply(Tile{1, TileRect{8, 8, 8, 16}}), 64, 48).ok()) << "empty";
  EXPECT_FALSE(decode_tile_reply(Value::Map{{"tile", Value::Map{{"id", -1}}}}, 64, 48).ok());
  EXPECT_FALSE(decode_tile_reply(Value("tile"), 64, 48).ok());
  // A time-limited frame's later pass: its first sample travels; the first pass's says nothing (0).
  EXPECT_EQ(encode_tile_reply(tile).find("tile")->find("first"), nullptr);
  auto pass = decode_tile_reply(encode_tile_reply(Tile{3, TileRect{0, 0, 16, 16}, 48}), 64, 48);
  ASSERT_TRUE(pass.ok() && pass->size() == 1);
  EXPECT_EQ((*pass)[0].first_sample, 48u);
  auto bad = decode_tile_reply(
      Value::Map{{"tile", Value::Map{{"id", 1}, {"x0", 0}, {"y0", 0}, {"x1", 8}, {"y1", 8}, {"first", -2}}}}, 64, 48);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message, "the render master sent a tile whose first sample is not an index (0 to 2^31 - 1)");
}

TEST(ControlCodec, TileDoneCarriesItsPixels) {
  const std::vector<float> rgb{0.1f, 0.2f, 0.3f, 1, 2, 3};
  auto back = decode_tile_done(encode_tile_done(9, rgb));
  ASSERT_TRUE(back.ok());
  ASSERT_EQ(back->tiles.size(), 1u);
  EXPECT_EQ(back->tiles[0].id, 9u);
  EXPECT_EQ(back->tiles[0].rgb, rgb);
  EXPECT_EQ(back->count, 0) << "the one-tile form";
  auto partial = decode_tile_done(encode_tile_done(9, std::span<const float>(rgb).first(4)));
  ASSERT_FALSE(partial.ok()) << "pixels come in threes";
  EXPECT_EQ(partial.error().code, ErrorCode::bad_request);
  EXPECT_EQ(partial.error().message, "tile_done needs id and pixels");
  EXPECT_FALSE(decode_tile_done(Value::Map{{"id", 1}}).ok());
  EXPECT_FALSE(decode_tile_done(Value::Map{{"id", "one"}, {"pixels", floats_to_bytes(rgb)}}).ok());
  EXPECT_FALSE(back->next);
  EXPECT_FALSE(encode_tile_done(9, rgb).find("next")) << "a renderer that asks for no tile sends what it always did";
  auto asking = decode_tile_done(encode_tile_done(9, rgb, true));
  ASSERT_TRUE(asking.ok());
  EXPECT_TRUE(asking->next);
  auto odd = decode_tile_done(Value::Map{{"id", 1}, {"pixels", floats_to_bytes(rgb)}, {"next", 1}});
  ASSERT_FALSE(odd.ok());
  EXPECT_EQ(odd.error().message, "tile_done's next must be true or false");
}

TEST(ControlCodec, TilesTravelInBatches) {
  // A request for several tiles, answered with a list; the one-tile form stays what it was.
  EXPECT_EQ(encode_tile_request(0), Value(Value::Map{}));
  auto count = decode_tile_count(encode_tile_request(2));
  ASSERT_TRUE(count.ok());
  EXPECT_EQ(*count, 2);
  EXPECT_EQ(*decode_tile_count(Value::Map{}), 0);
  for (const Value& bad : {Value(Value::Map{{"count", 0}}), Value(Value::Map{{"count", 65}}),
                           Value(Value::Map{{"count", "two"}})}) {
    auto refused = decode_tile_count(bad);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().message, "a tile request's count must be a whole number from 1 to 64");
  }
  const std::vector<Tile> tiles{{4, TileRect{0, 0, 16, 16}}, {5, TileRect{16, 0, 32, 16}, 8}};
  auto back = decode_tile_reply(encode_tiles_reply(tiles), 64, 48);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->size(), 2u);
  EXPECT_EQ((*back)[1].id, 5u);
  EXPECT_EQ((*back)[1].rect.x1, 32);
  EXPECT_EQ((*back)[1].first_sample, 8u);
  EXPECT_TRUE(decode_tile_reply(encode_tiles_reply({}), 64, 48)->empty()) << "none left: {}";
  auto outside = decode_tile_reply(encode_tiles_reply(tiles), 24, 48);
  ASSERT_FALSE(outside.ok()) << "every tile of the list is checked";
  EXPECT_EQ(outside.error().message, "the render master sent a tile outside the image");
  auto empty = decode_tile_reply(Value::Map{{"tiles", Value::Array{}}}, 64, 48);
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().message, "the render master's tiles must be a list of 1 to 64 tiles");
  EXPECT_FALSE(decode_tile_reply(Value::Map{{"tiles", Value::Array{Value(3)}}}, 64, 48).ok());

  // Several tiles' pixels in one tile_done, asking for as many next.
  const std::vector<FinishedTile> finished{{4, {0.5f, 0.5f, 0.5f}}, {5, {1, 2, 3, 4, 5, 6}}};
  auto done = decode_tile_done(encode_tile_done(finished, 2));
  ASSERT_TRUE(done.ok()) << done.error().message;
  ASSERT_EQ(done->tiles.size(), 2u);
  EXPECT_EQ(done->tiles[1].id, 5u);
  EXPECT_EQ(done->tiles[1].rgb, finished[1].rgb);
  EXPECT_TRUE(done->next);
  EXPECT_EQ(done->count, 2);
  auto last = decode_tile_done(encode_tile_done(finished, 0));
  ASSERT_TRUE(last.ok());
  EXPECT_FALSE(last->next) << "no count: no next tile asked for";
  auto broken = decode_tile_done(Value::Map{
      {"tiles", Value::Array{Value::Map{{"id", 4}, {"pixels", floats_to_bytes(finished[0].rgb)}}, Value::Map{{"id", 5}}}}});
  ASSERT_FALSE(broken.ok()) << "every tile of the batch needs its pixels";
  EXPECT_EQ(broken.error().message, "tile_done needs id and pixels");
  auto none = decode_tile_done(Value::Map{{"tiles", Value::Array{}}});
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().message, "tile_done's tiles must be a list of 1 to 64 maps of id and pixels");
  auto too_many = decode_tile_done(Value::Map{{"id", 1}, {"pixels", floats_to_bytes(finished[0].rgb)}, {"next", true},
                                              {"count", 100}});
  ASSERT_FALSE(too_many.ok());
  EXPECT_EQ(too_many.error().message, "tile_done's count must be a whole number from 1 to 64");
}

TEST(ControlCodec, PeerMessagesRoundTrip) {
  auto moved = decode_peer_moved(encode_peer_moved({"ring.0.1", "tcp://10.0.0.2:4000", "KEY"}));
  ASSERT_TRUE(moved.ok());
  EXPECT_EQ(moved->name, "ring.0.1");
  EXPECT_EQ(moved->endpoint, "tcp://10.0.0.2:4000");
  EXPECT_EQ(moved->key, "KEY");
  auto keyless = decode_peer_moved(Value::Map{{"name", "a"}, {"endpoint", "ipc:///x"}});
  ASSERT_TRUE(keyless.ok());
  EXPECT_EQ(keyless->key, "");
  auto bad = decode_peer_moved(Value::Map{{"name", "a"}});
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().message, "a PEER_MOVED without name and endpoint");
  auto down = decode_peer_down(encode_peer_down("direct.1"));
  ASSERT_TRUE(down.ok());
  EXPECT_EQ(*down, "direct.1");
  EXPECT_FALSE(decode_peer_down(Value::Map{{"name", 3}}).ok());
}

// PHASE frame: the frame number, the camera as CONFIG's, and on a replayed view the actors that set up for it.
TEST(ControlCodec, FrameRoundTripsAndRefusesWhatIsNotAFrame) {
  CameraSpec camera;
  camera.eye = {1, 2, 3};
  camera.fov = 50;
  auto plain = decode_frame(Value(encode_frame({7, camera, std::nullopt})));
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain->frame, 7);
  EXPECT_EQ(plain->camera.eye, camera.eye);
  EXPECT_EQ(plain->camera.fov, 50);
  EXPECT_FALSE(plain->renew.has_value());
  auto replay = decode_frame(Value(encode_frame({3, camera, std::vector<std::string>{"direct", "paths"}})));
  ASSERT_TRUE(replay.ok());
  EXPECT_EQ(*replay->renew, (std::vector<std::string>{"direct", "paths"}));
  EXPECT_EQ(decode_frame(Value::Map{{"camera", camera.to_value()}}).error().message,
            "a PHASE frame without a frame number");
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}}).error().message, "a PHASE frame without a camera");
  EXPECT_NE(decode_frame(Value::Map{{"frame", 1}, {"camera", Value::Map{{"eye", 3}}}}).error().message.find(
                "a PHASE frame's camera: "),
            std::string::npos);
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}, {"camera", camera.to_value()}, {"renew", Value::Array{1}}}).error().message,
            "a PHASE frame's renew is not a list of names");
  // A job's kept setups: keep (send it once extended) or restore (take the published one), never both.
  EXPECT_FALSE(plain->keep || plain->restore);
  FrameView kept{4, camera, std::nullopt};
  kept.keep = true;
  auto keep = decode_frame(Value(encode_frame(kept)));
  ASSERT_TRUE(keep.ok());
  EXPECT_TRUE(keep->keep && !keep->restore);
  FrameView restored{5, camera, std::vector<std::string>{}};
  restored.restore = true;
  auto restore = decode_frame(Value(encode_frame(restored)));
  ASSERT_TRUE(restore.ok());
  EXPECT_TRUE(restore->restore && !restore->keep && restore->renew && restore->renew->empty());
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}, {"camera", camera.to_value()}, {"keep", 1}}).error().message,
            "a PHASE frame's keep is not true or false");
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}, {"camera", camera.to_value()}, {"keep", true}, {"restore", true}})
                .error().message,
            "a PHASE frame asks to keep and to restore the same setup");
  // A frame's materials (frames { materials }) and where they change.
  FrameView lit{6, camera, std::nullopt};
  lit.materials = {Value::Map{{"name", "light"}, {"emission", Value::Array{1.0, 2.0, 3.0}}}};
  lit.new_materials = true;
  auto with = decode_frame(Value(encode_frame(lit)));
  ASSERT_TRUE(with.ok()) << with.error().message;
  EXPECT_EQ(with->materials, lit.materials);
  EXPECT_TRUE(with->new_materials);
  EXPECT_TRUE(plain->materials.empty() && !plain->new_materials);
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}, {"camera", camera.to_value()}, {"materials", Value::Array{Value::Map{{"kd", 1}}}}})
                .error().message,
            "a PHASE frame's materials are not a list of material changes, each a map with a name");
  EXPECT_EQ(decode_frame(Value::Map{{"frame", 1}, {"camera", camera.to_value()}, {"restore", true}, {"new_materials", true}})
                .error().message,
            "a PHASE frame restores a kept setup where the materials change");
}

}  // namespace
}  // namespace lf::control
