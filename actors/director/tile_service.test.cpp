// The tile service driven message by message: tiles wait for the render phase and for lost renderers' tiles,
// results count only from the holder, a lost renderer's tiles go to the others.
#include "actors/director/tile_service.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <set>
#include <thread>

#include "actors/codecs/control_codec.hpp"
#include "actors/director/next_view_timing.hpp"
#include "actors/director/service_test_support.hpp"

namespace lf {
namespace {

using test::RecordingOutbox;
using wire::Op;

ImageSpec image(int w, int h, int tile) {
  ImageSpec i;
  i.width = w;
  i.height = h;
  i.tile = tile;
  i.spp = 1;
  return i;
}

Value pixels_for(const Value& tile, float v) {
  const auto& t = tile.find("tile")->as_map();
  const int64_t n = (t.at("x1").as_int() - t.at("x0").as_int()) * (t.at("y1").as_int() - t.at("y0").as_int());
  return floats_to_bytes(std::vector<float>(static_cast<size_t>(3 * n), v));
}

TEST(TileService, TileRequestsWaitForTheRenderPhase) {
  TileService s(image(32, 32, 16), {"r0"}, false, true);
  RecordingOutbox out;
  ASSERT_TRUE(s.on_request("r0", Op::tile, 1, Value::Map{}, out).ok());
  EXPECT_TRUE(out.take().empty());
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].actor, "r0");
  EXPECT_EQ(sent[0].id, 1u);
  EXPECT_TRUE(sent[0].body.find("tile"));
}

// A tile_done that asks for the next tile (the built-in renderer's): its reply is a tile request's. With tiles free
// it is the next one; with none free but one still out it waits, and that tile's pixels answer it with no tile.
TEST(TileService, ATileDoneAskingForTheNextIsAnsweredAsATileRequest) {
  TileService s(image(48, 16, 16), {"r0", "r1"}, false, true);
  RecordingOutbox out;
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  auto first_of = [&](const char* r, uint64_t req) {
    EXPECT_TRUE(s.on_request(r, Op::tile, req, Value::Map{}, out).ok());
    auto sent = out.take();
    EXPECT_EQ(sent.size(), 1u);
    return sent.empty() ? Value() : sent[0].body;
  };
  const Value a = first_of("r0", 1), b = first_of("r1", 2);
  auto done_asking = [&](const char* r, uint64_t req, const Value& tile) {
    return s.on_request(r, Op::tile_done, req,
                        Value::Map{{"id", tile.find("tile")->find("id")->as_int()}, {"pixels", pixels_for(tile, 0.5f)},
                                   {"next", true}},
                        out);
  };
  ASSERT_TRUE(done_asking("r0", 3, a).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].id, 3u);
  ASSERT_TRUE(sent[0].body.find("tile")) << "the third tile, with the first's acknowledgement";
  const Value c = sent[0].body;
  ASSERT_TRUE(done_asking("r0", 4, c).ok());
  EXPECT_TRUE(out.take().empty()) << "no tile is free, r1's is still out: the reply waits";
  ASSERT_TRUE(done_asking("r1", 5, b).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  for (const auto& m : sent) {
    EXPECT_FALSE(m.refused);
    EXPECT_FALSE(m.body.find("tile")) << "every tile is done";
  }
  EXPECT_TRUE(s.finished());
  // Pixels from a renderer that does not hold the tile are refused, the next tile with them.
  ASSERT_TRUE(done_asking("r1", 6, c).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_TRUE(sent[0].refused);
}

// Tiles in batches: a request with a count gets up to that many while every renderer could take as many of the
// free tiles, the frame's last ones one at a time; a tile_done carrying several counts each on its own, and one
// refused does not lose the others.
TEST(TileService, TilesGoAndComeBackInBatchesAndTheLastOnesOneAtATime) {
  TileService s(image(128, 16, 16), {"r0", "r1"}, false, true);  // 8 tiles, 2 renderers
  RecordingOutbox out;
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  auto tiles_of = [](const Value& body) {
    std::vector<control::Tile> t;
    if (auto d = control::decode_tile_reply(body, 128, 16)) t = *d;
    return t;
  };
  auto finished = [](const std::vector<control::Tile>& tiles, float v) {
    std::vector<control::FinishedTile> f;
    for (const auto& t : tiles) f.push_back({t.id, std::vector<float>(3 * t.rect.pixel_count(), v)});
    return f;
  };
  ASSERT_TRUE(s.on_request("r0", Op::tile, 1, control::encode_tile_request(3), out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  const auto first = tiles_of(sent[0].body);
  EXPECT_EQ(first.size(), 3u) << "8 free for 2 renderers: 3 of them fit the share of 4";
  ASSERT_TRUE(s.on_request("r1", Op::tile, 2, control::encode_tile_request(3), out).ok());
  const auto second = tiles_of(out.take()[0].body);
  EXPECT_EQ(second.size(), 2u) << "5 free for 2 renderers: a share of 2";
  // r0 hands in two with one message and asks for two: 1 free for 2 renderers, so one.
  const std::vector<control::Tile> two{first[0], first[1]};
  ASSERT_TRUE(s.on_request("r0", Op::tile_done, 3, control::encode_tile_done(finished(two, 0.5f), 2), out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  ASSERT_FALSE(sent[0].refused) << sent[0].message;
  const auto third = tiles_of(sent[0].body);
  ASSERT_EQ(third.size(), 1u) << "the last tile alone";
  EXPECT_EQ(s.tiles_done(), 2u);
  // A batch with a tile its sender does not hold: that one is refused by name, the other counts.
  const std::vector<control::Tile> mixed{second[0], first[2]};
  ASSERT_TRUE(s.on_request("r1", Op::tile_done, 4, control::encode_tile_done(finished(mixed, 0.5f), 0), out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_TRUE(sent[0].refused);
  EXPECT_EQ(sent[0].message, "tile " + std::to_string(first[2].id) + ": the tile is not assigned to this renderer");
  EXPECT_EQ(s.tiles_done(), 3u);
  // The rest. Two tiles are free for two renderers: one to each request, whatever its count.
  ASSERT_TRUE(s.on_request("r1", Op::tile_done, 5, control::encode_tile_done(finished({second[1]}, 0.5f), 0), out).ok());
  ASSERT_TRUE(s.on_request("r0", Op::tile_done, 6, control::encode_tile_done(finished({first[2]}, 0.5f), 0), out).ok());
  ASSERT_TRUE(
      s.on_request("r0", Op::tile_done, 7, control::encode_tile_done(finished({third[0]}, 0.5f), 2), out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 3u);
  for (const auto& m : sent) EXPECT_FALSE(m.refused) << m.message;
  const auto r0_last = tiles_of(sent[2].body);
  ASSERT_EQ(r0_last.size(), 1u);
  ASSERT_TRUE(s.on_request("r1", Op::tile, 8, control::encode_tile_request(4), out).ok());
  const auto r1_last = tiles_of(out.take()[0].body);
  ASSERT_EQ(r1_last.size(), 1u);
  EXPECT_EQ(s.tiles_done(), 6u);
  // r0's request for more waits while r1's tile is out; r1's pixels answer both with none left.
  ASSERT_TRUE(s.on_request("r0", Op::tile_done, 9, control::encode_tile_done(finished(r0_last, 0.5f), 2), out).ok());
  EXPECT_TRUE(out.take().empty());
  ASSERT_TRUE(s.on_request("r1", Op::tile_done, 10, control::encode_tile_done(finished(r1_last, 0.5f), 2), out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 2u);
  for (const auto& m : sent) EXPECT_EQ(m.body, Value(Value::Map{})) << "none left";
  EXPECT_TRUE(s.finished());
  for (const RGB& p : s.film().pixels) EXPECT_EQ(p, (RGB{0.5f, 0.5f, 0.5f}));
  // A bad count is refused with its reason.
  ASSERT_TRUE(s.on_request("r1", Op::tile, 11, Value::Map{{"count", 0}}, out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].code, ErrorCode::bad_request);
  EXPECT_EQ(sent[0].message, "a tile request's count must be a whole number from 1 to 64");
}

TEST(TileService, EveryTileOnceThenNoneLeftAndTheFilmIsFilled) {
  TileService s(image(32, 16, 16), {"r0", "r1"}, false, true);
  RecordingOutbox out;
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  std::set<int64_t> ids;
  uint64_t req = 1;
  for (const char* r : {"r0", "r1"}) {
    ASSERT_TRUE(s.on_request(r, Op::tile, req++, Value::Map{}, out).ok());
    auto sent = out.take();
    ASSERT_EQ(sent.size(), 1u);
    const Value& tile = sent[0].body;
    ids.insert(tile.find("tile")->find("id")->as_int());
    ASSERT_TRUE(s.on_request(r, Op::tile_done, req++,
                             Value::Map{{"id", tile.find("tile")->find("id")->as_int()}, {"pixels", pixels_for(tile, 0.25f)}},
                             out)
                    .ok());
    sent = out.take();
    ASSERT_EQ(sent.size(), 1u);
    EXPECT_FALSE(sent[0].refused) << sent[0].message;
  }
  EXPECT_EQ(ids.size(), 2u);
  EXPECT_TRUE(s.finished());
  // Every tile done: a tile request is answered at once with no tile.
  ASSERT_TRUE(s.on_request("r0", Op::tile, req, Value::Map{}, out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].body.find("tile"), nullptr);
  for (const RGB& p : s.film().pixels) EXPECT_EQ(p, (RGB{0.25f, 0.25f, 0.25f}));
}

TEST(TileService, ResultsCountOnlyFromTheHolderAndBadBodiesAreRefused) {
  TileService s(image(16, 16, 16), {"r0", "r1"}, false, true);
  RecordingOutbox out;
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  ASSERT_TRUE(s.on_request("r0", Op::tile, 1, Value::Map{}, out).ok());
  const Value tile = out.take()[0].body;
  const int64_t id = tile.find("tile")->find("id")->as_int();
  ASSERT_TRUE(s.on_request("r1", Op::tile_done, 2, Value::Map{{"id", id}, {"pixels", pixels_for(tile, 1)}}, out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_TRUE(sent[0].refused);
  EXPECT_EQ(sent[0].code, ErrorCode::refused);
  ASSERT_TRUE(s.on_request("r0", Op::tile_done, 3, Value::Map{{"id", id}}, out).ok());
  sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].code, ErrorCode::bad_request);
  EXPECT_EQ(sent[0].message, "tile_done needs id and pixels");
  EXPECT_FALSE(s.finished());
}

TEST(TileService, ALostRenderersTilesGoToAWaitingOne) {
  TileService s(image(16, 16, 16), {"r0", "r1"}, false, true);  // one tile
  RecordingOutbox out;
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  ASSERT_TRUE(s.on_request("r0", Op::tile, 1, Value::Map{}, out).ok());
  const int64_t id = out.take()[0].body.find("tile")->find("id")->as_int();
  // r1 asks while r0 holds the only tile: it waits rather than hear "none left".
  ASSERT_TRUE(s.on_request("r1", Op::tile, 2, Value::Map{}, out).ok());
  EXPECT_TRUE(out.take().empty());
  // A replica's loss is not this service's business.
  ASSERT_TRUE(s.on_lost("direct.0", "was killed", out).ok());
  EXPECT_TRUE(out.take().empty());
  ASSERT_TRUE(s.on_lost("r0", "was killed by signal 9", out).ok());
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].actor, "r1");
  EXPECT_EQ(sent[0].id, 2u);
  EXPECT_EQ(sent[0].body.find("tile")->find("id")->as_int(), id);
}

// A time-limited frame: its tiles go out pass after pass while the time lasts, each pass's from the sample after
// the last pass's (tile.first), and the film is the mean of the passes completed.
struct Passes {
  TileService service;
  RecordingOutbox out;
  uint64_t req = 1;
  explicit Passes(double time_limit) : service(limited(time_limit), {"r0", "r1"}, false, true) {
    EXPECT_TRUE(service.on_phase(wire::Phase::render, out).ok());
  }
  static ImageSpec limited(double time_limit) {
    ImageSpec i = image(32, 16, 16);  // two tiles
    i.spp = 2;
    i.time_limit = time_limit;
    return i;
  }
  // `renderer` asks for a tile: the reply's tile (a map), or null when none is given.
  Value ask(const char* renderer) {
    EXPECT_TRUE(service.on_request(renderer, Op::tile, req++, Value::Map{}, out).ok());
    auto sent = out.take();
    if (sent.empty()) return Value();  // waiting
    EXPECT_EQ(sent.size(), 1u);
    return sent.back().body;
  }
  void finish(const char* renderer, const Value& tile, float v) {
    ASSERT_TRUE(service.on_request(renderer, Op::tile_done, req++,
                                   Value::Map{{"id", tile.find("tile")->find("id")->as_int()}, {"pixels", pixels_for(tile, v)}},
                                   out)
                    .ok());
    for (const auto& m : out.take())
      if (m.actor == renderer) EXPECT_FALSE(m.refused) << m.message;
  }
  static int64_t first(const Value& tile) {
    const Value* f = tile.find("tile")->find("first");
    return f ? f->as_int() : 0;
  }
};

TEST(TileService, ATimeLimitedFrameRendersPassesWhileTheTimeLastsAndShowsTheirMean) {
  Passes p(60);
  for (int pass = 0; pass < 3; ++pass) {
    const Value a = p.ask("r0"), b = p.ask("r1");
    ASSERT_TRUE(a.find("tile") && b.find("tile")) << "pass " << pass;
    EXPECT_EQ(Passes::first(a), 2 * pass) << "pass " << pass << " takes the next spp samples of each pixel";
    EXPECT_EQ(Passes::first(b), 2 * pass);
    p.finish("r0", a, static_cast<float>(pass + 1));
    p.finish("r1", b, static_cast<float>(pass + 1));
    EXPECT_EQ(p.service.passes(), pass + 1);
    EXPECT_FALSE(p.service.finished()) << "time is left: another pass goes out";
    for (const RGB& px : p.service.film().pixels) ASSERT_EQ(px.x, static_cast<float>(pass + 2) / 2) << "the mean of passes 1.." << pass + 1;
  }
}

TEST(TileService, PastItsTimeAFrameGivesUpThePassUnderWayAndKeepsTheCompletedOnes) {
  Passes p(0.3);
  Value a = p.ask("r0"), b = p.ask("r1");
  p.finish("r0", a, 1);
  p.finish("r1", b, 1);
  ASSERT_EQ(p.service.passes(), 1);
  ASSERT_FALSE(p.service.finished()) << "a pass that took no time fits in 0.3 s";
  // Pass 2: both tiles out; the time runs out before they are in.
  a = p.ask("r0");
  b = p.ask("r1");
  ASSERT_EQ(Passes::first(a), 2);
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  p.finish("r0", a, 50);
  EXPECT_EQ(p.ask("r0").find("tile"), nullptr) << "no tile goes out past the time";
  EXPECT_FALSE(p.service.finished()) << "r1's tile is still out";
  // r1's tile completes pass 2 after all: it counts. Then nothing more.
  p.finish("r1", b, 50);
  EXPECT_TRUE(p.service.finished());
  EXPECT_EQ(p.service.passes(), 2);
  for (const RGB& px : p.service.film().pixels) ASSERT_EQ(px.x, 25.5f);
  EXPECT_EQ(p.ask("r1").find("tile"), nullptr);
}

TEST(TileService, APassLeftIncompletePastTheTimeIsDropped) {
  Passes p(0.3);
  Value a = p.ask("r0"), b = p.ask("r1");
  p.finish("r0", a, 1);
  p.finish("r1", b, 1);
  a = p.ask("r0");  // pass 2's first tile; its second is never handed out
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  p.finish("r0", a, 50);
  EXPECT_EQ(p.ask("r1").find("tile"), nullptr);
  EXPECT_TRUE(p.service.finished());
  EXPECT_EQ(p.service.passes(), 1);
  for (const RGB& px : p.service.film().pixels) ASSERT_EQ(px.x, 1.0f) << "the half pass is not in the image";
}


// A job's frames in flight: with the next frame coming, a request that finds every tile of frame 1 out waits
// instead of hearing "none left"; frame 2 begins beside frame 1 and its tiles (which name frame 2, with ids of their
// own) answer it; frame 1's last tile still lands in frame 1's film, a tile frame 1 gets back from a lost renderer
// goes out before frame 2's, and frame 1 is written to its own output once complete.
TEST(TileService, TheNextFrameBeginsWhileTheLastTilesOfOneAreOut) {
  const std::string dir = ::testing::TempDir();
  TileService s(image(32, 16, 16), {"r0", "r1"}, false, true);  // two tiles a frame
  RecordingOutbox out;
  s.begin_frame(dir + "/fly.0001.exr", "k1", 0, false, 0, 1);
  s.expect_next_frame(true);
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  uint64_t req = 1;
  auto ask = [&](const char* r) {
    EXPECT_TRUE(s.on_request(r, Op::tile, req++, Value::Map{}, out).ok());
    auto sent = out.take();
    EXPECT_LE(sent.size(), 1u);
    return sent.empty() ? Value() : sent[0].body;
  };
  auto finish = [&](const char* r, const Value& tile, float v) {
    ASSERT_TRUE(s.on_request(r, Op::tile_done, req++,
                             Value::Map{{"id", tile.find("tile")->find("id")->as_int()}, {"pixels", pixels_for(tile, v)}}, out)
                    .ok());
    for (const auto& m : out.take()) EXPECT_FALSE(m.refused) << m.message;
  };
  auto frame_of = [](const Value& tile) { return tile.find("tile")->find("frame")->as_int(); };
  const Value a = ask("r0"), b = ask("r1");
  ASSERT_TRUE(a.find("tile") && b.find("tile"));
  EXPECT_EQ(frame_of(a), 1);
  EXPECT_EQ(s.tiles_unassigned(), 0u);
  finish("r0", a, 1.0f);
  EXPECT_TRUE(ask("r0").is_nil()) << "told no tile is left while the next frame is coming";
  // Frame 2 begins in flight: the waiting request gets its first tile.
  s.begin_frame(dir + "/fly.0002.exr", "k2", 0, false, 0, 2, /*in_flight=*/true);
  s.serve(out);
  auto sent = out.take();
  ASSERT_EQ(sent.size(), 1u);
  const Value c = sent[0].body;
  EXPECT_EQ(frame_of(c), 2);
  EXPECT_NE(c.find("tile")->find("id")->as_int(), a.find("tile")->find("id")->as_int());
  EXPECT_NE(c.find("tile")->find("id")->as_int(), b.find("tile")->find("id")->as_int());
  // r1 is lost holding frame 1's last tile: it goes out again before frame 2's second tile.
  ASSERT_TRUE(s.on_lost("r1", "was killed", out).ok());
  const Value again = ask("r0");
  ASSERT_TRUE(again.find("tile"));
  EXPECT_EQ(frame_of(again), 1);
  EXPECT_EQ(again.find("tile")->find("id")->as_int(), b.find("tile")->find("id")->as_int());
  EXPECT_FALSE(s.earlier_finished());
  finish("r0", again, 2.0f);
  EXPECT_TRUE(s.earlier_finished());
  EXPECT_FALSE(s.finished()) << "frame 1's tiles counted in frame 2";
  ASSERT_TRUE(s.write_earlier().ok());
  auto one = read_image(dir + "/fly.0001.exr");
  ASSERT_TRUE(one.ok()) << one.error().message;
  EXPECT_EQ(one->pixels.front(), (RGB{1, 1, 1}));
  EXPECT_EQ(one->pixels.back(), (RGB{2, 2, 2}));
  const Value d = ask("r0");
  EXPECT_EQ(frame_of(d), 2);
  finish("r0", c, 3.0f);
  finish("r0", d, 3.0f);
  EXPECT_TRUE(s.finished());
  for (const RGB& p : s.film().pixels) EXPECT_EQ(p, (RGB{3, 3, 3}));
  EXPECT_EQ(ask("r0").find("tile"), nullptr) << "the job's last frame done: no tile left";
}

// The next frame may begin while some of this frame's tiles are not yet handed out (NextViewTiming sends its view
// early): those still go out first, each to be rendered as a tile of its own frame, and then the new frame's.
TEST(TileService, AFrameBegunEarlyHandsOutTheTilesLeftOfTheOneBeforeFirst) {
  const std::string dir = ::testing::TempDir();
  TileService s(image(64, 16, 16), {"r0"}, false, true);  // four tiles a frame
  RecordingOutbox out;
  s.begin_frame(dir + "/early.0001.exr", "k1", 0, false, 0, 1);
  s.expect_next_frame(true);
  ASSERT_TRUE(s.on_phase(wire::Phase::render, out).ok());
  uint64_t req = 1;
  auto ask = [&] {
    EXPECT_TRUE(s.on_request("r0", Op::tile, req++, Value::Map{}, out).ok());
    auto sent = out.take();
    EXPECT_EQ(sent.size(), 1u);
    return sent.empty() ? Value() : sent[0].body;
  };
  auto frame_of = [](const Value& tile) { return tile.find("tile")->find("frame")->as_int(); };
  std::vector<Value> given{ask()};
  EXPECT_EQ(s.tiles_unassigned(), 3u);
  s.begin_frame(dir + "/early.0002.exr", "k2", 0, false, 0, 2, /*in_flight=*/true);
  EXPECT_EQ(s.tiles_unassigned(), 4u) << "the new frame's";
  for (int i = 0; i < 7; ++i) given.push_back(ask());
  std::vector<int> frames;
  std::set<int64_t> ids;
  for (const Value& t : given) {
    ASSERT_TRUE(t.find("tile"));
    frames.push_back(static_cast<int>(frame_of(t)));
    ids.insert(t.find("tile")->find("id")->as_int());
  }
  EXPECT_EQ(frames, (std::vector<int>{1, 1, 1, 1, 2, 2, 2, 2}));
  EXPECT_EQ(ids.size(), 8u) << "each tile of the two frames once";
  for (const Value& t : given)
    ASSERT_TRUE(s.on_request("r0", Op::tile_done, req++,
                             Value::Map{{"id", t.find("tile")->find("id")->as_int()}, {"pixels", pixels_for(t, static_cast<float>(frame_of(t)))}},
                             out)
                    .ok());
  for (const auto& m : out.take()) EXPECT_FALSE(m.refused) << m.message;
  EXPECT_TRUE(s.earlier_finished());
  ASSERT_TRUE(s.write_earlier().ok());
  auto one = read_image(dir + "/early.0001.exr");
  ASSERT_TRUE(one.ok()) << one.error().message;
  for (const RGB& p : one->pixels) EXPECT_EQ(p, (RGB{1, 1, 1}));
  EXPECT_TRUE(s.finished());
  for (const RGB& p : s.film().pixels) EXPECT_EQ(p, (RGB{2, 2, 2}));
}

// The next view goes out once the tiles left take the renderers as long as the last switch took, at this frame's
// rate; never before a switch has been timed, always once every tile is out.
TEST(NextViewTiming, TheViewGoesOutWhenTheTilesLeftLastAsLongAsTheLastSwitch) {
  NextViewTiming t;
  EXPECT_FALSE(t.due(10, 70, 3.5)) << "the job's first switch: nothing to go by";
  EXPECT_TRUE(t.due(0, 80, 4.0));
  t.switched(0.5);  // 20 tiles a second below: 10 tiles last 0.5 s
  EXPECT_FALSE(t.due(11, 70, 3.5));
  EXPECT_TRUE(t.due(10, 70, 3.5));
  EXPECT_FALSE(t.due(10, 0, 0.0)) << "no rate yet";
  EXPECT_TRUE(t.due(0, 0, 0.0));
}

}  // namespace
}  // namespace lf
