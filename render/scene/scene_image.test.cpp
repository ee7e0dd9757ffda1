// The host-shared scene image: a mapped image is the same scene bit for bit and traces the same hits; actors that
// start together make it once and map one file; damaged images are refused with a message and remade.
#include "render/scene/scene_image.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "render/images/image.hpp"
#include "render/scene/scene_file.hpp"
#include "render/tracing/tracer.hpp"

namespace lf {
namespace {

namespace fs = std::filesystem;

template <class T>
bool same_bits(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

Scene glass_with_point_light() {
  auto s = Scene::builtin_unlit("cornell_glass");
  s->add_point_light({0.1f, 1.2f, 0.3f}, {4, 5, 6});
  EXPECT_TRUE(s->finalize("test").ok());
  return std::move(*s);
}

struct ImageDir : ::testing::Test {
  fs::path dir = fs::temp_directory_path() / ("lightfarm-image-" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  // Writes the shipped form of `s` as the director would, returning its hash.
  std::string ship(const Scene& s, const fs::path& path) {
    const std::string bytes = scene_to_bytes(s);
    std::ofstream(path, std::ios::binary) << bytes;
    return content_hash(bytes);
  }
};

TEST_F(ImageDir, AMappedImageIsTheSameSceneBitForBit) {
  const Scene s = glass_with_point_light();
  const auto path = dir / "glass.image";
  std::ofstream(path, std::ios::binary) << SceneImage::encode(s, "0123456789abcdef");
  auto m = SceneImage::map(path.string(), "0123456789abcdef", "x");
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_TRUE(m->shares_storage());
  EXPECT_FALSE(s.shares_storage());
  ASSERT_EQ(m->triangle_count(), s.triangle_count());
  ASSERT_EQ(m->vertices().size(), s.vertices().size());
  for (uint32_t t = 0; t < s.triangle_count(); ++t) {
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(same_bits(m->vertex(t, c), s.vertex(t, c)));
    EXPECT_TRUE(same_bits(m->normal(t), s.normal(t)));
    EXPECT_TRUE(same_bits(m->area(t), s.area(t)));
    EXPECT_TRUE(same_bits(m->emitter_probability_of_triangle(t), s.emitter_probability_of_triangle(t)));
    EXPECT_EQ(m->material_of(t), s.material_of(t));
  }
  ASSERT_EQ(m->materials().size(), s.materials().size());
  for (size_t i = 0; i < s.materials().size(); ++i) {
    EXPECT_EQ(m->materials()[i].name, s.materials()[i].name);
    EXPECT_EQ(m->materials()[i].type, s.materials()[i].type);
    EXPECT_TRUE(same_bits(m->materials()[i].kd, s.materials()[i].kd));
  }
  EXPECT_EQ(m->emitters(), s.emitters());
  ASSERT_EQ(m->point_lights().size(), 1u);
  EXPECT_TRUE(same_bits(m->point_lights()[0].position, s.point_lights()[0].position));
  for (float u : {0.0f, 0.3f, 0.77f, 0.999f}) {
    float pa = 0, pb = 0;
    EXPECT_EQ(m->pick_emitter(u, pa), s.pick_emitter(u, pb));
    EXPECT_TRUE(same_bits(pa, pb));
  }
  EXPECT_TRUE(same_bits(m->bounds().lo, s.bounds().lo));
  EXPECT_TRUE(same_bits(m->bounds().hi, s.bounds().hi));
  EXPECT_TRUE(same_bits(m->epsilon(), s.epsilon()));
  // Re-encoding the mapped scene gives the same image.
  EXPECT_EQ(SceneImage::encode(*m, "0123456789abcdef"), SceneImage::encode(s, "0123456789abcdef"));
}

// A job frame's material changes (Scene::with_material_changes), over a mapped scene and over one of its own
// arrays: the lights come out bit for bit as those of the scene loaded with the same changes (a farm of that frame
// alone), and the scene they were made over keeps its own.
TEST_F(ImageDir, MaterialChangesSettleTheLightsAsTheSceneLoadedWithThemWould) {
  const Value::Array changes{Value::Map{{"name", "light"}, {"emission", Value::Array{30.0, 27.0, 20.0}}},
                             Value::Map{{"name", "red"}, {"emission", Value::Array{0.5, 0.0, 0.0}}, {"kd", Value::Array{0.4, 0.0, 0.0}}}};
  auto loaded = Scene::builtin_unlit("cornell_glass");
  loaded->add_point_light({0.1f, 1.2f, 0.3f}, {4, 5, 6});
  ASSERT_TRUE(loaded->apply_material_overrides(changes).ok());
  ASSERT_TRUE(loaded->finalize("test").ok());
  const Scene own = glass_with_point_light();
  const auto path = dir / "glass.image";
  std::ofstream(path, std::ios::binary) << SceneImage::encode(own, "0123456789abcdef");
  auto mapped = SceneImage::map(path.string(), "0123456789abcdef", "x");
  ASSERT_TRUE(mapped.ok()) << mapped.error().message;
  const std::vector<uint32_t> emitters_before = mapped->emitters();
  for (const Scene* base : {&own, static_cast<const Scene*>(&*mapped)}) {
    auto changed = base->with_material_changes(changes, "frame 2");
    ASSERT_TRUE(changed.ok()) << changed.error().message;
    const Scene& c = **changed;
    EXPECT_EQ(c.shares_storage(), base->shares_storage());
    EXPECT_EQ(c.emitters(), loaded->emitters());
    EXPECT_GT(c.emitters().size(), base->emitters().size()) << "the red wall emits";
    for (uint32_t t = 0; t < c.triangle_count(); ++t)
      ASSERT_TRUE(same_bits(c.emitter_probability_of_triangle(t), loaded->emitter_probability_of_triangle(t))) << t;
    for (float u : {0.0f, 0.3f, 0.77f, 0.999f}) {
      float pa = 0, pb = 0;
      EXPECT_EQ(c.pick_emitter(u, pa), loaded->pick_emitter(u, pb));
      EXPECT_TRUE(same_bits(pa, pb));
    }
    for (size_t i = 0; i < c.materials().size(); ++i) {
      EXPECT_TRUE(same_bits(c.materials()[i].ke, loaded->materials()[i].ke)) << c.materials()[i].name;
      EXPECT_TRUE(same_bits(c.materials()[i].kd, loaded->materials()[i].kd)) << c.materials()[i].name;
    }
    EXPECT_TRUE(same_bits(c.vertex(5, 1), base->vertex(5, 1)));
  }
  EXPECT_EQ(mapped->emitters(), emitters_before);
  for (const Material& m : mapped->materials())
    if (m.name == "red") EXPECT_TRUE(is_black(m.ke)) << "the mapped scene's own materials changed";
  // A frame that turns every light off (the point light stays): still lit; without it, an error naming the frame.
  const Value::Array dark{Value::Map{{"name", "light"}, {"emission", Value::Array{0.0, 0.0, 0.0}}}};
  EXPECT_TRUE(mapped->with_material_changes(dark, "frame 3").ok());
  auto unlit = Scene::builtin("cornell");
  ASSERT_TRUE(unlit.ok());
  auto refused = unlit->with_material_changes(dark, "frame 3");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().message.rfind("frame 3: the scene has no light", 0), 0u) << refused.error().message;
  EXPECT_EQ(unlit->with_material_changes({Value::Map{{"name", "mist"}}}, "frame 4").error().message,
            "frame 4: material 'mist' is not in the scene");
}

TEST_F(ImageDir, EmbreeOverTheMappedArraysFindsTheSameHits) {
  const Scene s = glass_with_point_light();
  const auto path = dir / "glass.image";
  std::ofstream(path, std::ios::binary) << SceneImage::encode(s, "0123456789abcdef");
  auto m = SceneImage::map(path.string(), "0123456789abcdef", "x");
  ASSERT_TRUE(m.ok());
  RayTracer own(s), shared(*m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Ray> rays(20000);
  for (auto& r : rays) {
    r.origin = {0.5f * u(rng), 1 + 0.5f * u(rng), 0.5f * u(rng)};
    r.direction = normalize(Vec3{u(rng), u(rng), u(rng)});
    r.tnear = 0;
    r.tfar = 1e30f;
  }
  std::vector<Hit> a(rays.size()), b(rays.size());
  own.intersect(rays, a);
  shared.intersect(rays, b);
  size_t hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(a[i].triangle, b[i].triangle);
    EXPECT_TRUE(same_bits(a[i].t, b[i].t));
    hits += a[i].valid();
  }
  EXPECT_GT(hits, rays.size() / 4);  // the box is open at the front
}

// A scene with cut-outs carries the tracer's opaque-first order in its image, so the actors of a host share it: a
// quad its alpha map cuts out entirely, the floor, a quad it leaves whole and one it cuts in half, in that order.
TEST_F(ImageDir, TheOpaqueFirstOrderIsInTheImageAndTracesTheSameHits) {
  Image alpha(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) alpha.at(x, y) = x < 8 ? RGB{0, 0, 0} : RGB{1, 1, 1};
  ASSERT_TRUE(write_image(alpha, (dir / "alpha.png").string()).ok());
  std::ofstream(dir / "cut.mtl") << "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl leaf\nKd 0.5 0.5 0.5\nmap_d alpha.png\n";
  std::ofstream(dir / "cut.obj")
      << "mtllib cut.mtl\nvt 0.6 0\nvt 0.9 0\nvt 0.9 1\nvt 0.6 1\nvt 0.1 0\nvt 0.4 0\nvt 0.4 1\nvt 0.1 1\nvt 0.45 0\nvt 0.45 1\n"
         "usemtl leaf\nv -1 1 -1\nv 0 1 -1\nv 0 1 1\nv -1 1 1\nf 1/5 4/8 3/7 2/6\n"            // cut out
         "usemtl floor\nv -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\nf 5 8 7 6\n"
         "usemtl leaf\nv -3 1 -1\nv -2 1 -1\nv -2 1 1\nv -3 1 1\nf 9/1 12/4 11/3 10/2\n"        // whole
         "v 1 1 -1\nv 2 1 -1\nv 2 1 1\nv 1 1 1\nf 13/9 16/10 15/3 14/2\n";                     // cut in half
  auto s = Scene::load_obj_unlit((dir / "cut.obj").string());
  ASSERT_TRUE(s.ok()) << s.error().message;
  s->add_point_light({0, 10, 0}, {1, 1, 1});
  ASSERT_TRUE(s->finalize("cut").ok());
  EXPECT_TRUE(s->opaque_first().triangles.empty()) << "a scene of its own arrays: each tracer makes its own order";
  const auto path = dir / "cut.image";
  const std::string good = SceneImage::encode(*s, "0123456789abcdef");
  std::ofstream(path, std::ios::binary) << good;
  auto m = SceneImage::map(path.string(), "0123456789abcdef", "x");
  ASSERT_TRUE(m.ok()) << m.error().message;
  const auto& order = m->opaque_first();
  EXPECT_EQ(std::vector<uint32_t>(order.triangles.begin(), order.triangles.end()),
            (std::vector<uint32_t>{2, 3, 4, 5, 0, 1, 6, 7}));
  EXPECT_EQ(order.opaque, 4u);
  for (size_t i = 0; i < order.triangles.size(); ++i) EXPECT_EQ(order.corners[i], m->triangles()[order.triangles[i]]);

  // Straight down: the floor through the cut-out quad, the whole quad at y = 1, the halved one where u >= 0.5.
  RayTracer own(*s), shared(*m);
  std::vector<Ray> down;
  for (float x : {-2.9f, -2.1f, -0.9f, -0.1f, 1.02f, 1.5f, 1.9f, 3.0f}) down.push_back(Ray{{x, 5, 0.3f}, {0, -1, 0}});
  std::vector<Hit> a(down.size()), b(down.size());
  own.intersect(down, a);
  shared.intersect(down, b);
  const std::vector<float> t_expected{4, 4, 5, 5, 5, 4, 4, 5};
  for (size_t i = 0; i < down.size(); ++i) {
    ASSERT_TRUE(b[i].valid()) << i;
    EXPECT_NEAR(b[i].t, t_expected[i], 1e-4f) << "x " << down[i].origin.x;
    EXPECT_EQ(a[i].triangle, b[i].triangle) << i;
    EXPECT_TRUE(same_bits(a[i].t, b[i].t)) << i;
  }
  std::vector<uint8_t> blocked(down.size());
  for (Ray& r : down) r.tfar = 4.5f;
  shared.occluded(down, blocked);
  for (size_t i = 0; i < down.size(); ++i) EXPECT_EQ(blocked[i], t_expected[i] == 4 ? 1 : 0) << "x " << down[i].origin.x;

  // An order that lists a triangle twice is refused, not traced.
  uint64_t order_at = 0;
  // The offsets begin 120 bytes in (see DamagedImagesAreRefusedAndRemade); the order's is the tenth.
  std::memcpy(&order_at, good.data() + 120 + 8 * 9, 8);
  ASSERT_LT(order_at + 8, good.size());
  std::string twice = good;
  std::memcpy(twice.data() + order_at, good.data() + order_at + 4, 4);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << twice;
  auto refused = SceneImage::map(path.string(), "0123456789abcdef", "x");
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("the opaque-first order"), std::string::npos) << refused.error().message;
}

TEST_F(ImageDir, ActorsStartingTogetherMakeTheImageOnceAndMapOneFile) {
  const Scene s = glass_with_point_light();
  const auto shipped = dir / "scene";
  const std::string hash = ship(s, shipped);
  // Four processes at once, as the actors of one host start.
  std::vector<pid_t> children;
  for (int i = 0; i < 4; ++i) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      auto scene = load_shared_scene(shipped.string(), hash, "x");
      ::_exit(scene.ok() && scene->shares_storage() && scene->triangle_count() == s.triangle_count() ? 0 : 1);
    }
    children.push_back(pid);
  }
  for (pid_t pid : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  }
  // One image, no temporary left behind, and a later actor maps that same file.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"scene", "scene.image", "scene.lock"}));
  struct stat before {};
  ASSERT_EQ(::stat((dir / "scene.image").c_str(), &before), 0);
  auto later = load_shared_scene(shipped.string(), hash, "x");
  ASSERT_TRUE(later.ok());
  EXPECT_TRUE(later->shares_storage());
  struct stat after {};
  ASSERT_EQ(::stat((dir / "scene.image").c_str(), &after), 0);
  EXPECT_EQ(before.st_ino, after.st_ino);
}

TEST_F(ImageDir, DamagedImagesAreRefusedAndRemade) {
  const Scene s = glass_with_point_light();
  const auto shipped = dir / "scene";
  const std::string hash = ship(s, shipped);
  ASSERT_TRUE(load_shared_scene(shipped.string(), hash, "x").ok());
  const auto image = dir / "scene.image";
  std::string good;
  {
    std::ifstream in(image, std::ios::binary);
    good.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto refused = [&](const std::string& bytes, const std::string& expect) {
    std::ofstream(image, std::ios::binary | std::ios::trunc) << bytes;
    auto m = SceneImage::map(image.string(), hash, "x");
    ASSERT_FALSE(m.ok()) << expect;
    EXPECT_NE(m.error().message.find(expect), std::string::npos) << m.error().message;
  };
  refused(good.substr(0, good.size() / 2), "is damaged");
  refused(good.substr(0, 10), "shorter than its header");
  std::string wrong_version = good;
  wrong_version[12] = 99;
  refused(wrong_version, "not an image of this version");
  // A vertex index far outside the vertex array: the first triangle's first corner.
  std::string bad_index = good;
  uint64_t triangles_at = 0;
  // magic, byte order, version, hash, 2 counts of 8 bytes, 7 of 4 and 4 bytes of padding, the texel bytes, bounds
  // and epsilon, 4 bytes of padding, then the offsets: the second is the triangles'.
  std::memcpy(&triangles_at, good.data() + 8 + 4 + 4 + 16 + 8 + 8 + 4 * 7 + 4 + 8 + 4 * 7 + 4 + 8, 8);
  ASSERT_LT(triangles_at, good.size());
  const uint32_t huge = 0x7fffffff;
  std::memcpy(bad_index.data() + triangles_at, &huge, 4);
  refused(bad_index, "a vertex index");
  EXPECT_FALSE(SceneImage::map(image.string(), "fedcba9876543210", "x").ok());  // made for another scene

  // load_shared_scene remakes a damaged image rather than failing the actor.
  std::ofstream(image, std::ios::binary | std::ios::trunc) << good.substr(0, 100);
  auto remade = load_shared_scene(shipped.string(), hash, "x");
  ASSERT_TRUE(remade.ok()) << remade.error().message;
  EXPECT_TRUE(remade->shares_storage());
  EXPECT_EQ(fs::file_size(image), good.size());
  // A shipped file that does not match its hash is still refused.
  fs::remove(image);
  std::ofstream(shipped, std::ios::binary | std::ios::app) << "x";
  auto forged = load_shared_scene(shipped.string(), hash, "x");
  ASSERT_FALSE(forged.ok());
  EXPECT_NE(forged.error().message.find("does not match its hash"), std::string::npos);
}

}  // namespace
}  // namespace lf
