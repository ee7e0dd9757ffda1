// Surface detail from OBJ files: smooth normals from `vn`, textures from `vt` + map_Kd, alpha cut-outs from map_d,
// each against a closed form, and all of it through the shipped scene file and the mapped scene image.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "render/tracing/camera.hpp"
#include "render/images/image.hpp"
#include "render/lights/light_sampling.hpp"
#include "render/lightops/lightop_registry.hpp"
#include "render/shading/sampler.hpp"
#include "render/scene/scene_file.hpp"
#include "render/scene/scene_image.hpp"
#include "render/scene/surface.hpp"
#include "render/test_support.hpp"
#include "render/shading/tile_kernel.hpp"

namespace lf {
namespace {

namespace fs = std::filesystem;

class SurfaceFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("lightfarm-surface-" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }
  fs::path dir;
};

// A UV sphere (centre c, radius r) in OBJ with vertex normals along the radius; `inward` winds the faces (and
// points the normals) inwards.
std::string sphere_obj(Vec3 c, float r, int slices, int stacks, bool inward, const std::string& material) {
  std::ostringstream o;
  o << "mtllib sphere.mtl\nusemtl " << material << "\n";
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const double theta = M_PI * i / stacks, phi = 2 * M_PI * j / slices;
      const Vec3 n{static_cast<float>(std::sin(theta) * std::cos(phi)), static_cast<float>(std::cos(theta)),
                   static_cast<float>(std::sin(theta) * std::sin(phi))};
      const Vec3 p = c + n * r;
      const Vec3 vn = inward ? -n : n;
      o << "v " << p.x << " " << p.y << " " << p.z << "\nvn " << vn.x << " " << vn.y << " " << vn.z << "\n";
    }
  auto at = [&](int i, int j) { return i * (slices + 1) + j + 1; };
  auto face = [&](int a, int b, int d) {
    if (inward) std::swap(b, d);
    o << "f " << a << "//" << a << " " << b << "//" << b << " " << d << "//" << d << "\n";
  };
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      // Wound so that (b - a) x (d - a) points out of the sphere.
      face(at(i, j), at(i, j + 1), at(i + 1, j));
      face(at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
    }
  return o.str();
}

double degrees_between(Vec3 a, Vec3 b) {
  return std::acos(std::clamp(static_cast<double>(dot(normalize(a), normalize(b))), -1.0, 1.0)) * 180 / M_PI;
}

TEST_F(SurfaceFiles, ATessellatedSphereShadesWithItsAnalyticNormals) {
  write("sphere.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
  const Vec3 c{1, 2, 3};
  auto s = Scene::load_obj_unlit(write("sphere.obj", sphere_obj(c, 2, 24, 12, false, "grey")));
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_TRUE(s->has_shading_normals());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  double worst_shading = 0, worst_face = 0;
  for (uint32_t t = 0; t < s->triangle_count(); ++t)
    for (int k = 0; k < 4; ++k) {
      const float su = std::sqrt(u(rng)), v = u(rng);
      const Vec3 b{1 - su, su * (1 - v), su * v};
      const Vec3 p = s->vertex(t, 0) * b.x + s->vertex(t, 1) * b.y + s->vertex(t, 2) * b.z;
      const Vec3 analytic = p - c;
      // From the point, as a LightOp gets it, not from the barycentrics drawn here.
      worst_shading = std::max(worst_shading, degrees_between(s->shading_normal(t, s->barycentrics(t, p)), analytic));
      worst_face = std::max(worst_face, degrees_between(s->normal(t), analytic));
    }
  EXPECT_LT(worst_shading, 1.0);
  EXPECT_GT(worst_face, 5.0) << "the facets themselves are that far off: the test tells smooth from flat";
}

// Inside a closed sphere whose every face emits E and reflects rho, radiance is E / (1 - rho) everywhere; smooth
// normals must not lose or make energy (paths the shading normal sends below a face end there, which the fine
// tessellation keeps rare).
TEST_F(SurfaceFiles, AFurnaceWithSmoothNormalsStillGivesEOverOneMinusRho) {
  const float rho = 0.8f, e = 1.0f;
  write("sphere.mtl", "newmtl furnace\nKd 0.8 0.8 0.8\nKe 1 1 1\n");
  auto s = Scene::load_obj(write("sphere.obj", sphere_obj({0, 0, 0}, 1, 96, 48, true, "furnace")));
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_TRUE(s->has_shading_normals());
  RayTracer tracer(*s);
  // Points where rays from near the centre meet the wall, with their shading normals as the renderer makes them.
  std::vector<Ray> rays;
  for (int i = 0; i < 16; ++i) {
    const float a = 0.7f * i, z = -0.9f + 0.12f * i;
    rays.push_back(Ray{{0.1f, -0.05f, 0.02f}, normalize(Vec3{std::cos(a), z, std::sin(a)})});
  }
  std::vector<Hit> hits(rays.size());
  tracer.intersect(rays, hits);
  ShadingPoints pts;
  double bent = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(hits[i].valid());
    const Vec3 p = rays[i].origin + rays[i].direction * hits[i].t, wo = -rays[i].direction;
    const SurfacePoint sp = surface_at(*s, hits[i].triangle, p, wo);
    bent = std::max(bent, degrees_between(sp.ns, sp.ng));
    pts.push_back(p, sp.ns, wo, s->material_of(hits[i].triangle), sample_key(i, 0), hits[i].triangle);
  }
  EXPECT_GT(bent, 0.2) << "the shading normals differ from the faces'";
  auto op = create_lightop(*find_lightop_kind("pathtrace"),
                           ParamTable(Value::Map{{"samples", 4096}, {"max_depth", 1000}}, "pathtrace"));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&*s, &tracer}, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  double mean = 0;
  for (const RGB& l : out) mean += l.y;
  mean /= static_cast<double>(out.size());
  EXPECT_NEAR((e + mean) / (e / (1 - rho)), 1.0, 0.02) << "reflected " << mean;
}

// A size x size texture of random colours, written as an 8-bit sRGB PNG; returns the mean albedo it decodes to.
RGB write_random_texture(const std::string& path, int size = 8) {
  Image img(size, size);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.05f, 0.95f);
  for (auto& p : img.pixels) p = {u(rng), u(rng), u(rng)};
  EXPECT_TRUE(write_image(img, path).ok());
  auto back = read_image(path);  // OpenImageIO's floats, decoded from sRGB: not the texture code under test
  RGB mean{};
  for (const auto& p : back->pixels) mean += p * (1.0f / static_cast<float>(back->pixels.size()));
  return mean;
}

// The quad y = 0, x and z in [-1, 1], with texture coordinates 0..1 across it.
const char* kTexturedQuad =
    "mtllib quad.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
    "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nusemtl textured\nf 1/1 4/4 3/3 2/2\n";

// Renders the scene in-process through `direct` (every pixel's camera samples, then the LightOp), as the farm
// would with one renderer and one op.
Image render_direct(const Scene& s, const CameraSpec& cam, int size, int spp, int light_samples) {
  RayTracer tracer(s);
  ImageSpec image;
  image.width = image.height = size;
  image.spp = spp;
  Camera camera(cam, size, size);
  TileWork work;
  trace_tile(s, tracer, camera, image, TileRect{0, 0, size, size}, work);
  auto op = create_lightop(*find_lightop_kind("direct"),
                           ParamTable(Value::Map{{"light_samples", light_samples}}, "direct"));
  LocalInputs none;
  SceneContext ctx{&s, &tracer};
  ctx.camera = &camera;  // textures are filtered to the camera's pixels
  ctx.width = ctx.height = size;
  run_to_completion(op->setup(ctx, none));
  std::vector<RGB> radiance(work.points.size());
  run_to_completion(op->shade(work.points, radiance, none));
  std::vector<RGB> pixels;
  resolve_tile(work, radiance, pixels);
  Image out(size, size);
  out.pixels = pixels;
  return out;
}

// A textured quad exactly filling the view, lit by a distant point light (uniform irradiance E): its pixels'
// mean is E times the texture's mean albedo over pi.
TEST_F(SurfaceFiles, ATexturedQuadReflectsItsIrradianceTimesTheTexturesMeanAlbedo) {
  const RGB mean_albedo = write_random_texture((dir / "tex.png").string());
  write("quad.mtl", "newmtl textured\nKd 0.5 0.5 0.5\nmap_Kd tex.png\n");
  auto s = Scene::load_obj_unlit(write("quad.obj", kTexturedQuad));
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->textures().size(), 1u);
  ASSERT_TRUE(s->has_uvs());
  const float d = 1000, intensity = 1e6f;  // E = I / d^2 = 1, uniform within 1e-6 over the quad
  s->add_point_light({0, d, 0}, {intensity, intensity, intensity});
  ASSERT_TRUE(s->finalize("quad").ok());
  CameraSpec cam;
  cam.eye = {0, 1, 0};  // fov 90 from height 1: the view is exactly the quad
  cam.at = {0, 0, 0};
  cam.up = {0, 0, -1};
  cam.fov = 90;
  const Image img = render_direct(*s, cam, 64, 16, 1);
  RGB mean{};
  for (const auto& p : img.pixels) mean += p * (1.0f / static_cast<float>(img.pixels.size()));
  const RGB expected = mean_albedo * (1.0f / kPi);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c] / expected[c], 1.0, 0.02) << "channel " << c;
  // And it is the texture, not the flat Kd: the image varies as the texels do.
  float lo = 1e9f, hi = 0;
  for (const auto& p : img.pixels) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  EXPECT_GT(hi - lo, 0.1f / kPi);
}

// Far away, a texture is seen through its mip levels: 64 x 64 random texels on 8 x 8 pixels (8 texels a pixel,
// level 3) keep the mean, and each pixel already holds about the mean of the texels it covers, where the full
// resolution would give a few random texels (the noise a pixel's samples would have to average away).
TEST_F(SurfaceFiles, ADistantTextureIsFilteredToThePixelAndKeepsItsMean) {
  const RGB mean_albedo = write_random_texture((dir / "tex.png").string(), 64);
  write("quad.mtl", "newmtl textured\nKd 0.5 0.5 0.5\nmap_Kd tex.png\n");
  auto s = Scene::load_obj_unlit(write("quad.obj", kTexturedQuad));
  ASSERT_TRUE(s.ok()) << s.error().message;
  const float d = 1000, intensity = 1e6f;
  s->add_point_light({0, d, 0}, {intensity, intensity, intensity});
  ASSERT_TRUE(s->finalize("quad").ok());
  // The pyramid: 64, 32, ..., 1; its last level is the texture's mean (in linear values, up to 8-bit steps).
  const Texture& tex = s->textures()[0];
  EXPECT_EQ(tex.texels.size(), Texture::pyramid_bytes(64, 64, 3));
  EXPECT_EQ(Texture::pyramid_bytes(64, 64, 3), 3u * (4096 + 1024 + 256 + 64 + 16 + 4 + 1));
  for (uint32_t c = 0; c < 3; ++c) EXPECT_NEAR(tex.sample({0.3f, 0.7f}, c, 6.0f) / mean_albedo[c], 1.0, 0.02);
  CameraSpec cam;
  cam.eye = {0, 1, 0};
  cam.at = {0, 0, 0};
  cam.up = {0, 0, -1};
  cam.fov = 90;
  const Image img = render_direct(*s, cam, 8, 4, 1);
  RGB mean{};
  double spread = 0;
  for (const auto& p : img.pixels) mean += p * (1.0f / static_cast<float>(img.pixels.size()));
  for (const auto& p : img.pixels) spread += std::pow((p.y - mean.y) / mean.y, 2) / static_cast<double>(img.pixels.size());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c] / (mean_albedo[c] / kPi), 1.0, 0.02) << "channel " << c;
  // Random texels in [0.05, 0.95] vary by about 50 % of their mean; the means of 8 x 8 of them by about a tenth
  // of that. Unfiltered, 4 samples a pixel would leave about half.
  EXPECT_LT(std::sqrt(spread), 0.15) << "pixels are filtered";
}

// A 16 x 16 coverage map: the left half of u cut out (0), the right half there (1).
void write_half_alpha(const std::string& path) {
  Image img(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) img.at(x, y) = x < 8 ? RGB{0, 0, 0} : RGB{1, 1, 1};
  ASSERT_TRUE(write_image(img, path).ok());
}

// A floor at y = 0 and, at y = 1, a quad over x in [-1, 1] (u = 0..1 along x) whose left half the alpha map cuts.
const char* kCutOutOverFloor =
    "mtllib cut.mtl\nv -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\nusemtl floor\nf 1 4 3 2\n"
    "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl leaf\nf 5/1 8/4 7/3 6/2\n";

TEST_F(SurfaceFiles, AlphaCutGeometryIsNotThereForCameraOrShadowRays) {
  write_half_alpha((dir / "alpha.png").string());
  write("cut.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl leaf\nKd 0.5 0.5 0.5\nmap_d alpha.png\n");
  auto s = Scene::load_obj_unlit(write("cut.obj", kCutOutOverFloor));
  ASSERT_TRUE(s.ok()) << s.error().message;
  const float intensity = 100;
  s->add_point_light({0, 10, 0}, {intensity, intensity, intensity});
  ASSERT_TRUE(s->finalize("cut").ok());
  ASSERT_TRUE(s->has_cutouts());
  RayTracer tracer(*s);
  // Camera rays straight down: through the cut half they reach the floor, on the other half they stop at y = 1.
  std::vector<Ray> down;
  for (float x : {-0.9f, -0.5f, -0.1f, 0.1f, 0.5f, 0.9f}) down.push_back(Ray{{x, 5, 0.3f}, {0, -1, 0}});
  std::vector<Hit> hits(down.size());
  tracer.intersect(down, hits);
  for (size_t i = 0; i < down.size(); ++i) EXPECT_NEAR(hits[i].t, down[i].origin.x < 0 ? 5.0f : 4.0f, 1e-4f) << i;
  // Floor points under each half, lit by the point light above: under the cut half the full I cos / d^2, under
  // the other half nothing.
  ShadingPoints pts;
  const uint32_t floor_material = s->material_of(0);
  for (int i = 0; i < 6; ++i) {
    const float x = -0.9f + 0.36f * i;
    pts.push_back({x, 0, 0.2f}, {0, 1, 0}, normalize(Vec3{0.1f, 1, 0}), floor_material, sample_key(i, 0), 0);
  }
  auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{}, "direct"));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&*s, &tracer}, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  for (size_t i = 0; i < pts.size(); ++i) {
    const Vec3 to = Vec3{0, 10, 0} - pts.position[i];
    const float cos = to.y / length(to), e = intensity * cos / dot(to, to);
    const float lit = 0.5f / kPi * e;
    EXPECT_NEAR(out[i].y, pts.position[i].x < 0 ? lit : 0.0f, 1e-3f * lit) << "x " << pts.position[i].x;
  }
}

// Triangles whose every reachable texel is there are known opaque, and the tracer leaves them unfiltered: a quad
// over the map's solid half (u in 0.6-0.9) is opaque everywhere, one over its cut half (u in 0.1-0.4) is not, and
// neither is one whose bilinear lookups reach across the cut (u in 0.45-0.9). Rays find the same hits either way.
TEST_F(SurfaceFiles, OnlyTrianglesWhoseEveryReachableTexelIsThereAreOpaqueEverywhere) {
  write_half_alpha((dir / "alpha.png").string());
  write("cut.mtl", "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl leaf\nKd 0.5 0.5 0.5\nmap_d alpha.png\n");
  auto s = Scene::load_obj_unlit(write(
      "cut.obj",
      "mtllib cut.mtl\nv -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\nusemtl floor\nf 1 4 3 2\n"
      "vt 0.6 0\nvt 0.9 0\nvt 0.9 1\nvt 0.6 1\nvt 0.1 0\nvt 0.4 0\nvt 0.4 1\nvt 0.1 1\n"
      "vt 0.45 0\nvt 0.45 1\nusemtl leaf\n"
      "v -3 1 -1\nv -2 1 -1\nv -2 1 1\nv -3 1 1\nf 5/1 8/4 7/3 6/2\n"      // solid half of the map
      "v -1 1 -1\nv 0 1 -1\nv 0 1 1\nv -1 1 1\nf 9/5 12/8 11/7 10/6\n"     // cut half
      "v 1 1 -1\nv 2 1 -1\nv 2 1 1\nv 1 1 1\nf 13/9 16/10 15/3 14/2\n"));  // reaching across the cut
  ASSERT_TRUE(s.ok()) << s.error().message;
  s->add_point_light({0, 10, 0}, {1, 1, 1});
  ASSERT_TRUE(s->finalize("cut").ok());
  ASSERT_EQ(s->triangles().size(), 8u);
  const std::vector<bool> expected{true, true, true, true, false, false, false, false};
  for (uint32_t t = 0; t < 8; ++t) EXPECT_EQ(s->opaque_everywhere(t), expected[t]) << "triangle " << t;
  RayTracer tracer(*s);
  // Straight down: the solid quad stops every ray at y = 1, the cut quad none, the mixed one where u >= 0.5.
  std::vector<Ray> down;
  for (float x : {-2.9f, -2.1f, -0.9f, -0.1f, 1.02f, 1.5f, 1.9f}) down.push_back(Ray{{x, 5, 0.3f}, {0, -1, 0}});
  std::vector<Hit> hits(down.size());
  tracer.intersect(down, hits);
  const std::vector<float> t_expected{4, 4, 5, 5, 5, 4, 4};
  for (size_t i = 0; i < down.size(); ++i) {
    ASSERT_TRUE(hits[i].valid()) << i;
    EXPECT_NEAR(hits[i].t, t_expected[i], 1e-4f) << "x " << down[i].origin.x;
    EXPECT_EQ(hits[i].triangle < 2, t_expected[i] == 5) << "x " << down[i].origin.x << ": the floor's or a quad's";
  }
  std::vector<uint8_t> blocked(down.size());
  for (Ray& r : down) r.tfar = 4.5f;
  tracer.occluded(down, blocked);
  for (size_t i = 0; i < down.size(); ++i) EXPECT_EQ(blocked[i], t_expected[i] == 4 ? 1 : 0) << "x " << down[i].origin.x;
}

// A floor at y = 0 and, at y = 1 facing down onto it, an emitting quad over x in [-1, 1] whose left half its alpha
// map cuts out.
Result<Scene> load_cut_out_emitter(const fs::path& dir) {
  write_half_alpha((dir / "alpha.png").string());
  std::ofstream(dir / "cut.mtl") << "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl leaf\nKd 0 0 0\nKe 3 3 3\nmap_d alpha.png\n";
  std::ofstream(dir / "cut.obj")
      << "mtllib cut.mtl\nv -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\nusemtl floor\nf 1 4 3 2\n"
         "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl leaf\nf 5/1 6/2 7/3 8/4\n";
  return Scene::load_obj((dir / "cut.obj").string());
}

// An emitting quad whose alpha map cuts its left half sends exactly what its right half would: its power counts
// only the part that is there, and light samples on the cut part bring nothing.
TEST_F(SurfaceFiles, ACutOutEmitterLightsLikeItsOpaquePart) {
  auto s = load_cut_out_emitter(dir);
  ASSERT_TRUE(s.ok()) << s.error().message;
  double power = 0;
  for (uint32_t t : s->emitters()) power += s->emitted_power(t);
  EXPECT_NEAR(power / (kPi * 3 * 4 / 2), 1.0, 0.05) << "half of pi Le A";
  RayTracer tracer(*s);
  ShadingPoints pts;
  std::vector<Vec3> where{{-1.5f, 0, 0.3f}, {-0.4f, 0, -0.2f}, {0.3f, 0, 0.5f}, {1.6f, 0, -0.7f}};
  for (size_t i = 0; i < where.size(); ++i)
    pts.push_back(where[i], {0, 1, 0}, {0, 1, 0}, s->material_of(0), sample_key(i, 0), 0);
  auto op = create_lightop(*find_lightop_kind("direct"), ParamTable(Value::Map{{"light_samples", 1 << 16}}, "direct"));
  LocalInputs none;
  run_to_completion(op->setup(SceneContext{&*s, &tracer}, none));
  std::vector<RGB> out(pts.size());
  run_to_completion(op->shade(pts, out, none));
  const std::vector<Vec3> right_half{{0, 1, -1}, {1, 1, -1}, {1, 1, 1}, {0, 1, 1}};
  for (size_t i = 0; i < pts.size(); ++i) {
    const double expected = 0.5 / M_PI * (M_PI * 3 * test::form_factor(pts.position[i], {0, 1, 0}, right_half));
    EXPECT_NEAR(out[i].y / expected, 1.0, 0.02) << "x " << pts.position[i].x;
  }
}

// Light samples on that emitter land where it may be there, and weighted by their density they still add up to
// exactly the part that is there. The quad's diagonal splits the cut unevenly: uniform samples brought light in a
// quarter of one triangle and three quarters of the other; restricted, in more than 70 % of each.
TEST_F(SurfaceFiles, LightSamplesOnACutOutEmitterAvoidItsCutPart) {
  auto s = load_cut_out_emitter(dir);
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_EQ(s->emitters().size(), 2u);
  const EmitterCutouts& cut = s->emitter_cutouts();
  double sampled = 0, emitting = 0;  // over the quad (area 4)
  for (size_t e = 0; e < 2; ++e) {
    ASSERT_TRUE(cut.restricted(e)) << e;
    const uint32_t tri = s->emitters()[e];
    sampled += cut.sampled_area(e);
    Rng rng(sample_key(e, 0), 99);
    const int n = 1 << 16;
    int lit = 0;
    double power = 0;
    for (int i = 0; i < n; ++i) {
      const LightSample ls = light_sample_at(*s, e, 1.0f, rng.uniform2());
      const Vec3 b = s->barycentrics(tri, ls.point);
      EXPECT_NEAR(b.x + b.y + b.z, 1.0f, 1e-5f);
      EXPECT_EQ(ls.radiance.y > 0, s->opaque(tri, b));
      lit += ls.radiance.y > 0 ? 1 : 0;
      power += ls.radiance.y > 0 ? 1.0 / ls.pdf_area : 0.0;
    }
    EXPECT_GT(lit, n * 70 / 100) << "triangle " << e;
    emitting += power / n;
  }
  // The cells from texel centre 7 to the edge at 15.5 (the opaque half and the blend into it), and the half-texel
  // strip at u = 0 that wraps round to texel 15: 9 of the 16 texels' width.
  EXPECT_NEAR(sampled / 4, 9.0 / 16.0, 1e-3);
  EXPECT_NEAR(emitting / 2, 1.0, 0.01) << "half the quad emits";
}

// Vertex normals, texture coordinates and texels survive the trip to a host: the shipped bytes, and the mapped
// image made from them, give the same detail bit for bit.
TEST_F(SurfaceFiles, SurfaceDetailTravelsInTheShippedSceneAndItsImage) {
  write_random_texture((dir / "tex.png").string());
  write_half_alpha((dir / "alpha.png").string());
  write("sphere.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\nmap_Kd tex.png\nmap_d alpha.png\n");
  std::string obj = sphere_obj({0, 0, 0}, 1, 12, 6, false, "grey");
  // Texture coordinates on a second object (the sphere has none: its faces keep the flat Kd).
  obj += "v 3 0 0\nv 4 0 0\nv 4 1 0\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.9 0.8\nf -3/-3 -2/-2 -1/-1\n";
  auto s = Scene::load_obj(write("sphere.obj", obj));
  ASSERT_TRUE(s.ok()) << s.error().message;
  ASSERT_TRUE(s->has_uvs() && s->has_shading_normals() && s->has_cutouts());
  const std::string bytes = scene_to_bytes(*s);
  std::ofstream(dir / "shipped", std::ios::binary) << bytes;
  const std::string hash = content_hash(bytes);
  auto shipped = scene_from_bytes(bytes, "shipped");
  ASSERT_TRUE(shipped.ok()) << shipped.error().message;
  auto mapped = load_shared_scene((dir / "shipped").string(), hash, "mapped");
  ASSERT_TRUE(mapped.ok()) << mapped.error().message;
  ASSERT_TRUE(mapped->shares_storage());
  EXPECT_EQ(scene_to_bytes(*shipped), bytes);
  EXPECT_EQ(scene_to_bytes(*mapped), bytes);
  for (const Scene* other : {&*shipped, &*mapped}) {
    ASSERT_EQ(other->triangle_count(), s->triangle_count());
    for (uint32_t t = 0; t < s->triangle_count(); ++t) {
      const Vec3 b{0.2f, 0.3f, 0.5f};
      EXPECT_EQ(other->shading_normal(t, b), s->shading_normal(t, b));
      EXPECT_EQ(other->albedo(t, b), s->albedo(t, b));
      EXPECT_EQ(other->opaque(t, b), s->opaque(t, b));
    }
    for (uint32_t t : s->emitters()) EXPECT_EQ(other->emitted_power(t), s->emitted_power(t));
  }
  // The last triangle is textured: its albedo is the texture's, not the flat 0.5.
  EXPECT_NE(s->albedo(static_cast<uint32_t>(s->triangle_count() - 1), {0.3f, 0.3f, 0.4f}), (RGB{0.5f, 0.5f, 0.5f}));
}

// Vertex normals that only repeat the faces' are dropped (they would cost memory and time for nothing); one bent
// normal keeps them all.
TEST_F(SurfaceFiles, VertexNormalsThatRepeatTheFacesAreDropped) {
  write("quad.mtl", "newmtl textured\nKd 0.5 0.5 0.5\n");
  const std::string quad = "mtllib quad.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvn 0 1 0\nvn 0.1 1 0\n"
                           "usemtl textured\n";
  auto flat = Scene::load_obj_unlit(write("flat.obj", quad + "f 1//1 4//1 3//1 2//1\n"));
  ASSERT_TRUE(flat.ok()) << flat.error().message;
  EXPECT_FALSE(flat->has_shading_normals());
  auto bent = Scene::load_obj_unlit(write("bent.obj", quad + "f 1//1 4//1 3//2 2//1\n"));
  ASSERT_TRUE(bent.ok()) << bent.error().message;
  EXPECT_TRUE(bent->has_shading_normals());
}

TEST_F(SurfaceFiles, AnUnreadableTextureLeavesTheMaterialFlat) {
  write("quad.mtl", "newmtl textured\nKd 0.25 0.5 0.75\nmap_Kd missing.png\n");
  auto s = Scene::load_obj_unlit(write("quad.obj", kTexturedQuad));
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_TRUE(s->textures().empty());
  EXPECT_EQ(s->albedo(0, {0.3f, 0.3f, 0.4f}), (RGB{0.25f, 0.5f, 0.75f}));
}

}  // namespace
}  // namespace lf
