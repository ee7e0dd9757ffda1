// The script's tables as the readers take them, with no Lua: ranges, defaults, the rules between fields, and the
// image and camera as an actor reads them back from CONFIG.
#include "farm/spec_readers.hpp"

#include "render/scene/scene.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace lf {
namespace {

namespace fs = std::filesystem;

ParamTable table(Value::Map m, const char* owner) { return ParamTable(std::move(m), owner); }

// The message of the ParamError `fn` throws ("" when it throws none).
template <class Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}

TEST(ImageReader, DefaultsRangesAndAdaptiveSamplingRules) {
  const ImageSpec d = ImageSpec::read(table({}, "image"));
  EXPECT_EQ(d.width, 256);
  EXPECT_EQ(d.shade_spp, 0);  // every sample shaded
  EXPECT_EQ(d.adaptive_spp, 64) << "adaptive sampling is on by default, up to 16 x spp";
  EXPECT_EQ(ImageSpec::read(table({{"spp", 4}, {"adaptive_spp", 0}}, "image")).adaptive_spp, 0) << "0 turns it off";
  EXPECT_EQ(ImageSpec::read(table({{"spp", 1}}, "image")).adaptive_spp, 0) << "one lit sample has no spread";
  EXPECT_EQ(ImageSpec::read(table({{"spp", 8}, {"shade_spp", 1}}, "image")).adaptive_spp, 0);
  EXPECT_EQ(ImageSpec::read(table({{"spp", 8}, {"time_limit", 5}}, "image")).adaptive_spp, 0)
      << "a time-limited frame's passes take every pixel's next spp samples";
  EXPECT_EQ(ImageSpec::read(table({{"spp", 1024}}, "image")).adaptive_spp, 4096);
  const ImageSpec all = ImageSpec::read(table({{"spp", 8}, {"shade_spp", 8}}, "image"));
  EXPECT_EQ(all.shade_spp, 0) << "shade_spp = spp is the plain mean";
  EXPECT_NE(error_of([] { ImageSpec::read(table({{"width", 0}}, "image")); }).find("width"), std::string::npos);
  EXPECT_NE(error_of([] { ImageSpec::read(table({{"spp", 4}, {"shade_spp", 5}}, "image")); }).find("shade_spp"),
            std::string::npos);
  EXPECT_DOUBLE_EQ(ImageSpec::read(table({{"adaptive_threshold", 0.1}}, "image")).adaptive_threshold, 0.1);
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"adaptive_spp", 0}, {"adaptive_threshold", 0.1}}, "image")); }),
            "image: adaptive_threshold needs adaptive sampling, which adaptive_spp = 0 turns off");
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"spp", 1}, {"adaptive_threshold", 0.1}}, "image")); }),
            "image: adaptive_threshold needs adaptive sampling, which needs shade_spp (or spp) of at least 2 (a "
            "pixel's spread needs two samples)");
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"time_limit", 5}, {"adaptive_threshold", 0.1}}, "image")); }),
            "image: adaptive_threshold needs adaptive sampling, which time_limit turns off");
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"spp", 8}, {"adaptive_spp", 12.5}}, "image")); }),
            "image: parameter 'adaptive_spp' must be 0 (off) or an integer in [9, 65536], got 12.5");
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"spp", 8}, {"shade_spp", 1}, {"adaptive_spp", 8}}, "image")); }),
            "image: adaptive_spp needs shade_spp (or spp) of at least 2 (a pixel's spread needs two samples)");
  EXPECT_EQ(error_of([] { ImageSpec::read(table({{"spp", 8}, {"adaptive_spp", 8}}, "image")); }),
            "image: parameter 'adaptive_spp' must be 0 (off) or an integer in [9, 65536], got 8");
  // Past spp: the next samples of each pixel's sequence.
  EXPECT_EQ(ImageSpec::read(table({{"spp", 8}, {"adaptive_spp", 64}}, "image")).adaptive_spp, 64);
  EXPECT_NE(error_of([] { ImageSpec::read(table({{"tonemap", "filmic"}}, "image")); }).find("filmic"), std::string::npos);
  const ImageSpec adaptive =
      ImageSpec::read(table({{"spp", 64}, {"shade_spp", 4}, {"adaptive_spp", 32}, {"adaptive_threshold", 0.02}}, "image"));
  EXPECT_EQ(adaptive.adaptive_spp, 32);
  EXPECT_DOUBLE_EQ(adaptive.adaptive_threshold, 0.02);
}

TEST(ImageReader, CONFIGCarriesWhatTheScriptSaidAndRefusesWhatItCouldNot) {
  const ImageSpec a = ImageSpec::read(table({{"width", 320}, {"height", 200}, {"spp", 64}, {"shade_spp", 4},
                                             {"adaptive_spp", 32}, {"exposure", 1.5}, {"tonemap", "aces"},
                                             {"sampler", "independent"}, {"output", "x.png"}},
                                            "image"));
  auto back = ImageSpec::from_value(a.to_value());
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->to_value(), a.to_value());
  EXPECT_EQ(back->shaded_per_pixel(), 4);
  const ImageSpec off = ImageSpec::read(table({{"spp", 16}, {"adaptive_spp", 0}}, "image"));
  EXPECT_EQ(ImageSpec::from_value(off.to_value())->adaptive_spp, 0) << "adaptive sampling turned off stays off";
  Value::Map bad = a.to_value().as_map();
  bad["spp"] = int64_t{0};
  auto refused = ImageSpec::from_value(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::bad_request);
  EXPECT_NE(refused.error().message.find("spp"), std::string::npos) << refused.error().message;
  bad = a.to_value().as_map();
  bad["colour"] = "red";
  EXPECT_FALSE(ImageSpec::from_value(bad).ok()) << "an unknown field is refused, not ignored";
}

TEST(CameraReader, DegenerateViewsAreRefusedInTheScriptAndInCONFIG) {
  const CameraSpec c = CameraSpec::read(table({{"eye", Value::Array{0, 1, 5}}, {"at", Value::Array{0, 1, 0}}}, "camera"));
  EXPECT_EQ(c.eye[2], 5);
  EXPECT_DOUBLE_EQ(c.fov, 39.3);
  EXPECT_EQ(error_of([] { CameraSpec::read(table({{"eye", Value::Array{1, 1, 1}}, {"at", Value::Array{1, 1, 1}}}, "camera")); }),
            "camera: eye and at are the same point");
  EXPECT_EQ(error_of([] {
              CameraSpec::read(table({{"eye", Value::Array{0, 0, 0}}, {"at", Value::Array{0, 5, 0}}}, "camera"));
            }),
            "camera: up is parallel to the viewing direction");
  EXPECT_NE(error_of([] { CameraSpec::read(table({{"fov", 180}}, "camera")); }).find("fov"), std::string::npos);
  auto back = CameraSpec::from_value(c.to_value());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->to_value(), c.to_value());
  Value::Map same = c.to_value().as_map();
  same["at"] = same["eye"];
  EXPECT_FALSE(CameraSpec::from_value(same).ok());
}

struct FileReaders : ::testing::Test {
  fs::path dir = fs::temp_directory_path() / ("spec-readers-" + std::to_string(::getpid()));
  void SetUp() override {
    fs::create_directories(dir / "sub");
    std::ofstream(dir / "sub" / "room.obj") << "v 0 0 0\n";
    std::ofstream(dir / "ssh.conf") << "Host *\n";
  }
  void TearDown() override { fs::remove_all(dir); }
};

TEST_F(FileReaders, SceneFilesAreTakenFromTheScriptsFolder) {
  const SceneSpec s = read_scene(table({{"file", "sub/room.obj"}}, "scene"), dir);
  EXPECT_EQ(s.file, (dir / "sub" / "room.obj").string());
  EXPECT_EQ(read_scene(table({{"builtin", "cornell"}}, "scene"), dir).builtin, "cornell");
  EXPECT_EQ(error_of([&] { read_scene(table({{"file", "gone.obj"}}, "scene"), dir); }),
            "scene file '" + (dir / "gone.obj").string() + "' not found");
  EXPECT_EQ(error_of([&] { read_scene(table({}, "scene"), dir); }),
            "scene needs exactly one of builtin = \"cornell\" or file = \"path.obj\"");
  EXPECT_NE(error_of([&] { read_scene(table({{"builtin", "teapot"}}, "scene"), dir); }).find("cornell"), std::string::npos);
}

TEST_F(FileReaders, HostsNeedAnAddressAndTheirSshConfig) {
  const HostSpec h = read_host("h1", table({{"launcher", "ssh"}, {"address", "10.0.0.2"}, {"ssh_config", "ssh.conf"}}, "host"), dir);
  EXPECT_EQ(h.ssh_config, (dir / "ssh.conf").string());
  EXPECT_TRUE(h.remote());
  EXPECT_TRUE(h.ssh_name.empty()) << "reached at its address unless named";
  EXPECT_EQ(read_host("h1", table({{"launcher", "ssh"}, {"address", "10.0.0.2"}, {"ssh_name", "gpu1"}}, "host"), dir).ssh_name,
            "gpu1");
  EXPECT_NE(error_of([&] { read_host("s1", table({{"launcher", "slurm"}, {"address", "10.0.0.3"}, {"ssh_name", "x"}}, "host"), dir); })
                .find("ssh_name"),
            std::string::npos)
      << "only ssh hosts are reached by ssh";
  EXPECT_EQ(read_host("l2", table({}, "host"), dir).address, "127.0.0.1");
  EXPECT_EQ(error_of([&] { read_host("h1", table({{"launcher", "ssh"}}, "host"), dir); }),
            "host 'h1': an ssh host needs address = \"...\" (where its actors listen and ssh reaches it)");
  EXPECT_EQ(error_of([&] { read_host("s1", table({{"launcher", "slurm"}}, "host"), dir); }),
            "host 's1': a slurm host needs address = \"...\" (where its actors listen)");
  EXPECT_EQ(error_of([&] { read_host("local", table({}, "host"), dir); }), "host 'local' is this machine; give another name");
  EXPECT_NE(error_of([&] { read_host("h1", table({{"user", "me"}}, "host"), dir); }).find("user"), std::string::npos)
      << "ssh's settings on a local host are a mistake, not ignored";
}

TEST(MaterialReader, ChangesAreCheckedAgainstTheSceneAndItsRules) {
  const std::vector<std::string> names{"floor", "wall"};
  const Value change = read_material_change("floor", table({{"kd", Value::Array{0.5, 0.5, 0.5}}, {"ns", 20}}, "m"), names);
  EXPECT_EQ(change.find("name")->as_string(), "floor");
  EXPECT_EQ(change.find("ns")->as_double(), 20);
  EXPECT_EQ(error_of([&] { read_material_change("roof", table({}, "m"), names); }),
            "material 'roof' is not in the scene (its materials: floor, wall)");
  EXPECT_EQ(error_of([&] { read_material_change("wall", table({{"kd", Value::Array{2, 0, 0}}}, "m"), names); }),
            "material 'wall': kd must be between 0 and 1 in each channel");
  EXPECT_NE(error_of([&] {
              read_material_change("wall", table({{"kd", Value::Array{0.8, 0.8, 0.8}}, {"ks", Value::Array{0.5, 0.5, 0.5}}}, "m"),
                                   names);
            }),
            "")
      << "kd + ks above 1 would make light";
}

// glTF's model from the script: metallic, roughness or base_color make a material metal_rough; the lobes of the
// other models do not mix with it, and each parameter keeps to its range.
TEST(MaterialReader, MetalRoughFromItsParameters) {
  const std::vector<std::string> names{"ball"};
  const Value change = read_material_change(
      "ball", table({{"metallic", 1}, {"roughness", 0.25}, {"base_color", Value::Array{0.9, 0.7, 0.3}}}, "m"), names);
  Scene probe;
  probe.add_material({"ball", {0.5f, 0.5f, 0.5f}, {}, Material::Type::glossy, {0.3f, 0.3f, 0.3f}, 20});
  ASSERT_TRUE(probe.apply_material_overrides(Value::Array{change}).ok());
  const Material& m = probe.material(0);
  EXPECT_EQ(m.type, Material::Type::metal_rough);
  EXPECT_EQ(m.metallic, 1.0f);
  EXPECT_EQ(m.roughness, 0.25f);
  EXPECT_EQ(m.kd, (RGB{0.9f, 0.7f, 0.3f}));
  EXPECT_TRUE(is_black(m.ks)) << "the Phong lobe it replaces is gone";
  EXPECT_EQ(error_of([&] { read_material_change("ball", table({{"roughness", 1.5}}, "m"), names); }),
            "m: parameter 'roughness' must be in [0, 1], got 1.5");
  EXPECT_EQ(error_of([&] { read_material_change("ball", table({{"type", "glossy"}, {"metallic", 1}}, "m"), names); }),
            "material 'ball': metallic, roughness, base_color and transmission belong to type \"metal_rough\"");
  EXPECT_EQ(error_of([&] { read_material_change("ball", table({{"roughness", 0.5}, {"ks", Value::Array{0.1, 0.1, 0.1}}}, "m"), names); }),
            "material 'ball': a metal_rough material takes base_color, metallic and roughness, not kd, ks, ns or mirror");
}

// camera { gltf = ... }: the scene file's camera by name or index, which the table's keys then change; without a
// glTF scene before it, or naming no camera of the file, an error that says what there is.
TEST(CameraReader, AGltfFilesCameraByNameOrIndex) {
  SceneSpec scene;
  scene.file = std::string(LIGHTFARM_SOURCE_DIR) + "/../shared/scenes/gltf/balls.glb";
  if (!std::ifstream(scene.file)) GTEST_SKIP() << "no " << scene.file;
  // Blender's camera at (0, -5.5, 2.6), z up, is (0, 2.6, 5.5) in the file (y up); its 40 degrees across 16:9 are
  // yfov 0.404 rad.
  const CameraSpec named = read_camera(table({{"gltf", "Camera"}}, "camera"), scene);
  EXPECT_NEAR(named.eye[1], 2.6, 1e-4);
  EXPECT_NEAR(named.eye[2], 5.5, 1e-4);
  EXPECT_NEAR(named.fov, 0.404 * 180 / 3.14159265, 0.1);
  EXPECT_LT(named.at[2], named.eye[2]) << "it looks into the scene, down its -z";
  const CameraSpec first = read_camera(table({{"gltf", 0}, {"fov", 30}}, "camera"), scene);
  EXPECT_EQ(first.eye, named.eye);
  EXPECT_EQ(first.fov, 30) << "the table's own keys change the file's camera";
  EXPECT_EQ(error_of([&] { read_camera(table({{"gltf", "Cam"}}, "camera"), scene); }),
            "camera: the scene file has no camera 'Cam' (its cameras: Camera)");
  EXPECT_EQ(error_of([&] { read_camera(table({{"gltf", 1}}, "camera"), scene); }),
            "camera: the scene file has 1 camera(s), so no camera 1 (its cameras: Camera)");
  EXPECT_NE(error_of([&] { read_camera(table({{"gltf", "Camera"}}, "camera"), SceneSpec{}); }).find("needs scene { file"),
            std::string::npos);
}

TEST(LightReader, OneShapeAndNoNegativeLight) {
  EXPECT_NO_THROW(read_light(Value::Map{{"point", Value::Array{0, 1, 0}}, {"intensity", Value::Array{1, 1, 1}}}));
  EXPECT_EQ(error_of([] { read_light(Value::Map{{"point", Value::Array{0, 1, 0}}, {"sphere", Value::Array{0, 0, 0}}}); }),
            "light needs exactly one of quad, sphere or point");
  EXPECT_EQ(error_of([] { read_light(Value::Map{{"point", Value::Array{0, 1, 0}}, {"intensity", Value::Array{-1, 1, 1}}}); }),
            "light: intensity must not be negative");
  EXPECT_NE(error_of([] { read_light(Value::Map{{"spot", Value::Array{0, 1, 0}}}); }).find("unknown parameter 'spot'"),
            std::string::npos);
}

TEST(ShapeReader, APlaneOrASphereWithAMaterialOfItsOwnOrTheScenes) {
  std::vector<std::string> names{"white", "red"};
  const ShapeRead ground = read_shape("ground", Value::Map{{"plane", Value::Array{0, 0, 0}}, {"kd", Value::Array{0.2, 0.2, 0.2}}}, names);
  EXPECT_EQ(ground.shape.find("name")->as_string(), "ground");
  EXPECT_EQ(*ground.shape.find("normal"), (Value(Value::Array{0.0, 1.0, 0.0}))) << "up by default";
  ASSERT_TRUE(ground.material_change.has_value());
  EXPECT_EQ(ground.material_change->find("name")->as_string(), "ground");
  EXPECT_EQ(names.back(), "ground") << "later material \"ground\" { } changes find it";
  const ShapeRead ball = read_shape("ball", Value::Map{{"sphere", Value::Array{0, 1, 0}}, {"radius", 0.5}, {"material", "red"}}, names);
  EXPECT_EQ(ball.shape.find("material")->as_string(), "red");
  EXPECT_FALSE(ball.material_change.has_value());
  const ShapeRead plain = read_shape("plain", Value::Map{{"sphere", Value::Array{0, 1, 0}}, {"radius", 0.5}}, names);
  EXPECT_FALSE(plain.material_change.has_value()) << "grey, as the scene makes it";
  auto why = [&](Value::Map table) { return error_of([&] { read_shape("s", table, names); }); };
  EXPECT_EQ(why({{"radius", 1}}), "shape 's' needs exactly one of plane or sphere");
  EXPECT_EQ(why({{"plane", Value::Array{0, 0, 0}}, {"sphere", Value::Array{0, 0, 0}}}), "shape 's' needs exactly one of plane or sphere");
  EXPECT_EQ(why({{"sphere", Value::Array{0, 0, 0}}}), "shape 's': a sphere needs a radius");
  EXPECT_NE(why({{"sphere", Value::Array{0, 0, 0}}, {"radius", -1}}), "");
  EXPECT_EQ(why({{"plane", Value::Array{0, 0, 0}}, {"normal", Value::Array{0, 0, 0}}}), "shape 's': normal must not be {0, 0, 0}");
  EXPECT_EQ(why({{"plane", Value::Array{0, 0, 0}}, {"material", "chrome"}}), "shape 's': material 'chrome' is not in the scene");
  EXPECT_EQ(why({{"plane", Value::Array{0, 0, 0}}, {"material", "red"}, {"kd", Value::Array{1, 0, 0}}}),
            "shape 's': give material = \"red\" or the material's own parameters (kd, ...), not both");
  EXPECT_EQ(error_of([&] { read_shape("red", Value::Map{{"plane", Value::Array{0, 0, 0}}}, names); }),
            "shape 'red': the scene already has a material 'red'; name the shape otherwise, or give material = \"red\"");
  EXPECT_NE(why({{"plane", Value::Array{0, 0, 0}}, {"kd", Value::Array{2, 0, 0}}}).find("kd must be between 0 and 1"),
            std::string::npos);
}

TEST(FarmSettings, RangesAndChoices) {
  FarmSpec spec;
  read_farm_settings(table({{"heartbeat_timeout", 3}, {"security", "none"}}, "farm"), spec);
  EXPECT_EQ(spec.heartbeat_timeout, 3);
  EXPECT_EQ(spec.security, "none");
  EXPECT_EQ(spec.request_timeout, 120) << "unchanged";
  EXPECT_NE(error_of([&] { read_farm_settings(table({{"heartbeat_timeout", 0.1}}, "farm"), spec); }).find("heartbeat_timeout"),
            std::string::npos);
  EXPECT_NE(error_of([&] { read_farm_settings(table({{"security", "tls"}}, "farm"), spec); }).find("tls"), std::string::npos);
  EXPECT_EQ(error_of([&] { read_farm_settings(table({{"director_address", "0.0.0.0"}}, "farm"), spec); }),
            "farm: director_address '0.0.0.0' is no address the actors can reach; give this machine's address on the "
            "hosts' network (or leave it out: it is found from the route to the first remote host)");
  EXPECT_NO_THROW(read_farm_settings(table({{"director_address", "10.0.0.1"}}, "farm"), spec));
}

TEST(FarmSettings, SecurityOffAcrossHostsIsAWarning) {
  FarmSpec spec;
  spec.security = "none";
  EXPECT_TRUE(spec.setting_warnings().empty()) << "one machine: nothing crosses a network";
  HostSpec remote;
  remote.name = "h1";
  remote.launcher = "ssh";
  remote.address = "10.0.0.2";
  spec.hosts.push_back(remote);
  ActorSpec a;
  a.kind = "renderer";
  a.name = "renderer-0";
  a.host = "h1";
  spec.actors.push_back(a);
  ASSERT_TRUE(spec.has_remote_hosts());
  ASSERT_EQ(spec.setting_warnings().size(), 1u);
  EXPECT_NE(spec.setting_warnings()[0].find("neither authenticated nor encrypted"), std::string::npos);
  spec.security = "curve";
  EXPECT_TRUE(spec.setting_warnings().empty());
}

}  // namespace
}  // namespace lf
