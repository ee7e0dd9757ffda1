#include "actors/runtime/lean_points.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "render/scene/surface.hpp"
#include "render/test_support.hpp"
#include "transport/message.hpp"

namespace lf {

// A square image of `side` pixels and `spp` samples a pixel, the default sampler.
static ImageSpec square_image(int side, int spp) {
  ImageSpec image;
  image.width = image.height = side;
  image.spp = spp;
  return image;
}

// A renderer's request to a lean input: only the fields the receiver cannot rebuild.
static Value tile_request(const TileWork& work, size_t begin, size_t end, const Scene& scene, SamplerKind sampler,
                          int64_t image_width, bool fold = false) {
  const PointFields fields = fields_to_send(work, begin, end, scene, sampler, image_width);
  return encode_tile_request(work, begin, end, fields, fold && !fields.key);
}

// A scene with flat faces of two materials and one smoothly shaded triangle (vertex normals), lit by a lamp.
static Scene lean_scene() {
  Scene s;
  const uint32_t white = s.add_material(Material{"white", {0.5f, 0.5f, 0.5f}, {}});
  const uint32_t red = s.add_material(Material{"red", {0.6f, 0.1f, 0.1f}, {}});
  const uint32_t lamp = s.add_material(Material{"lamp", {}, {1, 1, 1}});
  s.add_quad({0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, white);
  s.add_quad({0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}, red);
  const Vec3 bent[3] = {normalize(Vec3{0.2f, 1, 0}), normalize(Vec3{-0.3f, 1, 0.1f}), normalize(Vec3{0, 1, -0.4f})};
  s.add_triangle({0, 0.5f, 0}, {1, 0.5f, 0}, {0, 0.5f, 1}, white, CornerAttributes{bent, nullptr});
  s.add_quad({0.4f, 0.99f, 0.4f}, {0.6f, 0.99f, 0.4f}, {0.6f, 0.99f, 0.6f}, {0.4f, 0.99f, 0.6f}, lamp);
  EXPECT_TRUE(s.finalize("lean").ok());
  return s;
}

// Points on every triangle, seen from both sides, with the normals and materials the renderer gives them.
static ShadingPoints points_on(const Scene& s) {
  ShadingPoints pts;
  for (uint32_t t = 0; t < s.triangle_count(); ++t)
    for (int k = 0; k < 4; ++k) {
      const float u = 0.1f + 0.2f * k, v = 0.15f + 0.1f * k;
      const Vec3 p = s.vertex(t, 0) * (1 - u - v) + s.vertex(t, 1) * u + s.vertex(t, 2) * v;
      const Vec3 wo = normalize(Vec3{0.3f * k - 0.5f, k % 2 ? 1.0f : -1.0f, 0.2f});
      pts.push_back(p, surface_at(s, t, p, wo).ns, wo, s.material_of(t), 77 + t * 4 + k, t);
    }
  return pts;
}

static bool same_bits(const ShadingPoints& a, const ShadingPoints& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof x[0]) == 0);
  };
  return same(a.position, b.position) && same(a.normal, b.normal) && same(a.wo, b.wo) && same(a.material, b.material) &&
         same(a.key, b.key) && same(a.triangle, b.triangle);
}

// The Cornell box and its BVH, and a tile of it as a renderer traces it (with the scripts' default camera).
class CornellTiles {
 public:
  const Scene scene = std::move(Scene::builtin("cornell").value());
  TileWork trace(const ImageSpec& image, TileRect rect, const CameraSpec& camera = {}) const {
    TileWork work;
    trace_tile(scene, tracer_, Camera(camera, image.width, image.height), image, rect, work);
    return work;
  }

 private:
  const RayTracer tracer_{scene};
};

TEST(LeanPoints, ALeanRequestLeavesOutWhatTheSceneGivesAndTheReceiverRestoresItBitForBit) {
  const Scene s = lean_scene();
  ASSERT_TRUE(s.has_shading_normals());
  const ShadingPoints pts = points_on(s);
  const Value lean = encode_shade_request(pts, 0, pts.size(), fields_to_send(pts, 0, pts.size(), s));
  EXPECT_EQ(lean.find("nrm"), nullptr);
  EXPECT_EQ(lean.find("m"), nullptr);
  ASSERT_NE(lean.find("tri"), nullptr);
  const size_t full_bytes = wire::encode_body(encode_shade_request(pts, 0, pts.size())).size();
  // 12 bytes of normal and 4 of material per point, and the two arrays' keys and lengths.
  EXPECT_GE(full_bytes - wire::encode_body(lean).size(), 16 * pts.size());
  EXPECT_LE(full_bytes - wire::encode_body(lean).size(), 16 * pts.size() + 16);
  auto back = read_shade_request(lean, s.materials().size(), s.triangle_count(), &s);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_bits(*back, pts));
  // Without the scene a lean request cannot be read, and says what it lacks.
  EXPECT_EQ(read_shade_request(lean, s.materials().size()).error().message, "shade request has no 'nrm' array");
}

TEST(LeanPoints, PointsWhoseNormalOrMaterialTheSceneDoesNotGiveTravelWhole) {
  const Scene s = lean_scene();
  ShadingPoints pts = points_on(s);
  pts.normal[5] = -pts.normal[5];  // not what its triangle gives: the batch keeps its normals
  Value body = encode_shade_request(pts, 0, pts.size(), fields_to_send(pts, 0, pts.size(), s));
  EXPECT_NE(body.find("nrm"), nullptr);
  EXPECT_EQ(body.find("m"), nullptr);
  auto back = read_shade_request(body, s.materials().size(), s.triangle_count(), &s);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_bits(*back, pts));
  pts = points_on(s);
  pts.material[2] = 1;  // an override the scene does not know
  ASSERT_NE(s.material_of(pts.triangle[2]), 1u);
  body = encode_shade_request(pts, 0, pts.size(), fields_to_send(pts, 0, pts.size(), s));
  EXPECT_EQ(body.find("nrm"), nullptr);
  EXPECT_NE(body.find("m"), nullptr);
  back = read_shade_request(body, s.materials().size(), s.triangle_count(), &s);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_bits(*back, pts));
  // Points without triangles have nothing to take a normal from.
  body = encode_shade_request(test::numbered_points(3), 0, 3, fields_to_send(test::numbered_points(3), 0, 3, s));
  EXPECT_NE(body.find("nrm"), nullptr);
  EXPECT_NE(body.find("m"), nullptr);
}

TEST(LeanPoints, APointOnAMaterialTheReceiverLacksIsRefused) {
  const Value body = encode_shade_request(test::numbered_points(4), 0, 4);
  EXPECT_EQ(read_shade_request(body, 2).error().message, "shade request: point 2 has material 2 but the scene has 2");
  EXPECT_TRUE(read_shade_request(body, 3).ok());
}

TEST(LeanPoints, ALeanRequestOnATriangleTheSceneLacksIsRefused) {
  const Scene s = lean_scene();
  ShadingPoints pts = points_on(s);
  Value body = encode_shade_request(pts, 0, 2, fields_to_send(pts, 0, 2, s));
  std::vector<uint32_t> tri{0, static_cast<uint32_t>(s.triangle_count())};
  body.as_map()["tri"] = u32_to_bytes(tri);
  EXPECT_EQ(read_shade_request(body, s.materials().size(), s.triangle_count(), &s).error().message,
            "shade request: point 1 is on triangle " + std::to_string(s.triangle_count()) + " but the scene has " +
                std::to_string(s.triangle_count()));
}

// A renderer's tile as a lean input gets it: no positions, normals, materials or keys on the wire, and the points the
// LightOp rebuilds are the renderer's, bit for bit, for either sampler; a slice of it rebuilds as those points.
TEST(LeanPoints, ACameraRequestCarriesDistancesAndSampleIndicesAndRebuildsTheRenderersPoints) {
  const CornellTiles cornell;
  const Scene& scene = cornell.scene;
  for (const char* sampler : {"independent", "sobol"}) {
    ImageSpec image;
    image.width = 64;
    image.height = 48;
    image.spp = 3;
    image.sampler = sampler;
    const SamplerKind kind = sampler_of(image);
    const TileWork work = cornell.trace(image, TileRect{16, 8, 32, 24});
    ASSERT_GT(work.points.size(), 100u);
    const Value body = tile_request(work, 0, work.points.size(), scene, kind, image.width);
    for (const char* gone : {"p", "nrm", "m", "k"}) EXPECT_EQ(body.find(gone), nullptr) << gone;
    const size_t n = work.points.size();
    const size_t full = wire::encode_body(encode_shade_request(work.points, 0, n)).size();
    // wo 12, t 4, tri 4, s 4: 24 bytes a point instead of 52, and a few dozen for the keys, o and tile.
    EXPECT_LE(wire::encode_body(body).size(), 24 * n + 100);
    EXPECT_GE(full, 52 * n);
    const PixelKeys keys{image.width, kind};
    auto back = read_shade_request(body, scene.materials().size(), scene.triangle_count(), &scene, &keys);
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_TRUE(same_bits(*back, work.points)) << sampler;
    auto slice = slice_shade_request(body, 7, n - 5);
    ASSERT_TRUE(slice.ok()) << slice.error().message;
    auto part = read_shade_request(*slice, scene.materials().size(), scene.triangle_count(), &scene, &keys);
    ASSERT_TRUE(part.ok()) << part.error().message;
    EXPECT_EQ(part->key[0], work.points.key[7]);
    EXPECT_EQ(std::memcmp(&part->position.back(), &work.points.position[n - 6], sizeof(Vec3)), 0);
    // A time-limited frame's later pass: the tile's samples are each pixel's from `first_sample` on, and its keys
    // are rebuilt as such (none of them the first pass's).
    const TileWork later = cornell.trace(image, TileRect{16, 8, 32, 24, 9});
    ASSERT_GT(later.points.size(), 100u);
    const Value later_body = tile_request(later, 0, later.points.size(), scene, kind, image.width);
    ASSERT_EQ(later_body.find("tile")->as_array().size(), 6u);
    auto later_back = read_shade_request(later_body, scene.materials().size(), scene.triangle_count(), &scene, &keys);
    ASSERT_TRUE(later_back.ok()) << later_back.error().message;
    EXPECT_EQ(later_back->key, later.points.key);
    EXPECT_EQ(later.points.key[0], pixel_sample_key(kind, 8 * 64 + 16, 9)) << "pixel (16, 8), sample 9";
    EXPECT_EQ(work.points.key[0], pixel_sample_key(kind, 8 * 64 + 16, 0));
    // Without the image's width and sampler the keys cannot be rebuilt, and the request says what it lacks.
    EXPECT_EQ(read_shade_request(body, scene.materials().size(), scene.triangle_count(), &scene).error().message,
              "shade request 'k' must hold " + std::to_string(n) + " u64 sample keys");
  }
}

// Through a thin lens camera rays leave from the lens, not the eye: their points travel with their positions (keys,
// normals and materials are still left out) and come back bit for bit.
TEST(LeanPoints, ALensCamerasPointsTravelWithTheirPositions) {
  const CornellTiles cornell;
  const ImageSpec image = square_image(32, 3);
  CameraSpec camera;
  camera.aperture = 40;  // mm, in a box 555 wide
  camera.focus_distance = 1000;
  const TileWork work = cornell.trace(image, TileRect{8, 8, 24, 24}, camera);
  const size_t n = work.points.size();
  ASSERT_GT(n, 100u);
  EXPECT_TRUE(work.distance.empty());
  const SamplerKind kind = sampler_of(image);
  const Value body = tile_request(work, 0, n, cornell.scene, kind, image.width);
  EXPECT_NE(body.find("p"), nullptr);
  EXPECT_EQ(body.find("o"), nullptr);
  EXPECT_EQ(body.find("k"), nullptr);
  EXPECT_EQ(body.find("nrm"), nullptr);
  const PixelKeys keys{image.width, kind};
  auto back = read_shade_request(body, cornell.scene.materials().size(), cornell.scene.triangle_count(), &cornell.scene,
                                 &keys);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(same_bits(*back, work.points));
  // The lens moves the camera rays' origins: the same tile through a pinhole has other positions.
  const TileWork pinhole = cornell.trace(image, TileRect{8, 8, 24, 24});
  EXPECT_FALSE(pinhole.distance.empty());
  EXPECT_NE(std::memcmp(pinhole.points.position.data(), work.points.position.data(),
                        std::min(pinhole.points.size(), n) * sizeof(Vec3)), 0);
}

// trace_tile marks its points rebuildable, and the renderer then skips checking them point by point: the request is
// the one the checks would have made, byte for byte. A point changed afterwards (the mark cleared) travels whole.
TEST(LeanPoints, ATrustedTileEncodesAsTheCheckedOneAndAChangedPointTravelsWhole) {
  const CornellTiles cornell;
  const Scene& scene = cornell.scene;
  const ImageSpec image = square_image(32, 2);
  const TileWork work = cornell.trace(image, TileRect{8, 8, 24, 24});
  ASSERT_TRUE(work.rebuildable);
  const size_t n = work.points.size();
  const SamplerKind kind = sampler_of(image);
  const std::string trusted = wire::encode_body(tile_request(work, 3, n - 2, scene, kind, image.width, true));
  TileWork checked = work;
  checked.rebuildable = false;
  EXPECT_EQ(wire::encode_body(tile_request(checked, 3, n - 2, scene, kind, image.width, true)), trusted);
  // Another sampler than trace_tile used: the mark does not hold, and the keys travel as keys.
  const SamplerKind other = kind == SamplerKind::sobol ? SamplerKind::independent : SamplerKind::sobol;
  const Value keyed = tile_request(work, 0, n, scene, other, image.width);
  EXPECT_NE(keyed.find("k"), nullptr);
  EXPECT_EQ(keyed.find("s"), nullptr);
  checked.points.normal[4] = -checked.points.normal[4];
  checked.points.position[5].x += 1;
  const Value whole = tile_request(checked, 0, n, scene, kind, image.width);
  EXPECT_NE(whole.find("nrm"), nullptr);
  EXPECT_NE(whole.find("p"), nullptr);
}

TEST(LeanPoints, ACameraRequestWithABadTileOrSampleIsRefused) {
  const CornellTiles cornell;
  const Scene& scene = cornell.scene;
  ImageSpec image = square_image(32, 2);
  image.sampler = "independent";
  const TileWork work = cornell.trace(image, TileRect{0, 0, 16, 16});
  const PixelKeys keys{image.width, SamplerKind::independent};
  auto decode = [&](const Value& body) {
    auto r = read_shade_request(body, scene.materials().size(), scene.triangle_count(), &scene, &keys);
    return r.ok() ? std::string("ok") : r.error().message;
  };
  Value body = tile_request(work, 0, 4, scene, SamplerKind::independent, image.width);
  EXPECT_EQ(decode(body), "ok");
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{64}, int64_t{16}, int64_t{2}};
  EXPECT_EQ(decode(body), "shade request has neither 'k' nor a tile [x0, y0, x1, y1, spp] inside an image 32 pixels wide");
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{1}, int64_t{1}, int64_t{1}};
  EXPECT_EQ(decode(body).rfind("shade request: point ", 0), 0u) << "a sample beyond the tile's one";
  // A tile whose samples do not fit 64 bits (pixels x spp) is counted without overflowing: any 32-bit s is in it.
  body.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{32}, int64_t{1} << 24, int64_t{1} << 24};
  EXPECT_EQ(decode(body), "ok");
  body = tile_request(work, 0, 4, scene, SamplerKind::independent, image.width);
  body.as_map()["t"] = Bytes{"abc"};
  EXPECT_EQ(decode(body), "shade request 't' must hold 4 f32 distances");
}

// A renderer's request that asks for its reply folded by pixel: the LightOp's sums over each pixel's points give
// the renderer's pixels bit for bit, for pixels whose samples see no emitter (those go one value a point).
TEST(LeanPoints, AFoldedReplyHoldsEachPixelsRadianceSummedAndResolvesToTheSamePixels) {
  const CornellTiles cornell;
  const Scene& scene = cornell.scene;
  const ImageSpec image = square_image(48, 5);
  // The whole image as one tile: it sees the light, and its corners look past the box's open side (some pixels
  // have fewer points than samples).
  const TileWork work = cornell.trace(image, TileRect{0, 0, 48, 48});
  const size_t n = work.points.size(), pixels = static_cast<size_t>(work.rect.pixel_count());
  ASSERT_LT(n, pixels * image.spp);
  std::vector<RGB> radiance(n);
  for (size_t j = 0; j < n; ++j) radiance[j] = {0.1f * float(j % 7), 1.0f / float(j + 1), float(j) * 1e-3f};
  // Cut into requests between pixels; those without an emitter in sight folded as a LightOp folds them.
  std::vector<RGB> pixel_radiance(pixels, RGB{});
  std::vector<uint8_t> folded(pixels, 0);
  const uint32_t spp = static_cast<uint32_t>(image.spp);
  size_t folded_requests = 0, whole_requests = 0;
  for (size_t begin = 0, end = 0; begin < n; begin = end) {
    end = std::min(begin + 37, n);
    while (end < n && work.sample_of_point[end] / spp == work.sample_of_point[end - 1] / spp) ++end;
    bool foldable = true;
    for (size_t j = begin; j < end; ++j) foldable = foldable && !pixel_sees_emitter(work, work.sample_of_point[j] / spp);
    const Value body = tile_request(work, begin, end, scene, sampler_of(image), image.width, foldable);
    auto fold = decode_pixel_fold(body);
    ASSERT_TRUE(fold.ok()) << fold.error().message;
    ASSERT_EQ(fold->has_value(), foldable);
    if (!foldable) {
      ++whole_requests;
      continue;
    }
    ++folded_requests;
    std::vector<RGB> sums;
    fold_by_pixel(std::span(radiance).subspan(begin, end - begin), (*fold)->samples, (*fold)->spp, sums);
    ASSERT_EQ(sums.size(), (*fold)->runs());
    auto back = decode_radiance(encode_radiance(sums), (*fold)->runs());
    ASSERT_TRUE(back.ok());
    for (size_t j = begin, run = 0; j < end; ++j)
      if (j == begin || work.sample_of_point[j] / spp != work.sample_of_point[j - 1] / spp) {
        pixel_radiance[work.sample_of_point[j] / spp] = (*back)[run++];
        folded[work.sample_of_point[j] / spp] = 1;
      }
  }
  EXPECT_GT(whole_requests, 0u) << "the light is in view";
  EXPECT_GT(folded_requests, whole_requests);
  std::vector<RGB> mixed, per_point;
  resolve_tile(work, radiance, pixel_radiance, folded, mixed);
  resolve_tile(work, radiance, per_point);
  ASSERT_EQ(mixed.size(), per_point.size());
  EXPECT_EQ(std::memcmp(mixed.data(), per_point.data(), mixed.size() * sizeof(RGB)), 0);
  // A request that does not ask is answered one value a point.
  auto plain = decode_pixel_fold(tile_request(work, 0, n, scene, sampler_of(image), image.width));
  ASSERT_TRUE(plain.ok());
  EXPECT_FALSE(plain->has_value());
}

}  // namespace lf
