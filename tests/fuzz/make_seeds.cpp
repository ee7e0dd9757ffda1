// Writes the fuzz targets' seed corpora (tests/fuzz/corpus/TARGET/): one valid input of each kind each target
// reads, so that fuzzing starts from the accepted formats rather than from nothing. Run by hand after a format
// changes: build-fuzz/tests/fuzz/make_seeds tests/fuzz/corpus
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "actors/codecs/ring_codec.hpp"
#include "actors/codecs/shade_codec.hpp"
#include "actors/runtime/actor_config.hpp"
#include "actors/runtime/hello.hpp"
#include "render/scene/scene_file.hpp"
#include "render/scene/scene_image.hpp"
#include "transport/message.hpp"

namespace fs = std::filesystem;

namespace {

fs::path g_root;

void seed(const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(g_root / target);
  std::ofstream(g_root / target / name, std::ios::binary) << bytes;
}

// fuzz_wire's input: one byte saying where the header ends, the header frame, the body frame.
void wire_seed(const std::string& name, const lf::wire::Message& m) {
  const std::string header = lf::wire::encode_header(m.header), body = lf::wire::encode_body(m.body);
  seed("wire", name, std::string(1, static_cast<char>(header.size())) + header + body);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds CORPUS_DIR\n");
    return 2;
  }
  g_root = argv[1];
  using namespace lf;

  ShadingPoints pts;
  for (uint32_t i = 0; i < 3; ++i)
    pts.push_back({0.1f * i, 1, 0}, {0, 1, 0}, {0, 0, 1}, i % 2, 1000 + i, i);
  wire_seed("shade_request", wire::make_request("renderer-0", wire::Op::shade, encode_shade_request(pts, 0, 3), 7));
  Value lean = encode_shade_request(pts, 0, 3);  // as a lean input gets it: normals and materials from the scene
  lean.as_map().erase("nrm");
  lean.as_map().erase("m");
  wire_seed("shade_request_lean", wire::make_request("renderer-0", wire::Op::shade, lean, 8));
  // A renderer's: distances along camera rays for positions, a tile's sample indices for keys.
  lean.as_map().erase("p");
  lean.as_map().erase("k");
  lean.as_map()["o"] = floats_to_bytes(std::vector<float>{0, 1, 3});
  lean.as_map()["t"] = floats_to_bytes(std::vector<float>{1.5f, 2, 2.5f});
  lean.as_map()["tile"] = Value::Array{int64_t{0}, int64_t{0}, int64_t{16}, int64_t{16}, int64_t{4}};
  lean.as_map()["s"] = u32_to_bytes(std::vector<uint32_t>{0, 5, 1023});
  wire_seed("shade_request_camera", wire::make_request("renderer-0", wire::Op::shade, lean, 9));
  lean.as_map()["fold"] = true;  // answered one value a pixel
  wire_seed("shade_request_folded", wire::make_request("renderer-0", wire::Op::shade, lean, 10));
  const std::vector<RGB> light{{1, 2, 3}, {4, 5, 6}};
  wire_seed("shade_reply", wire::make_reply("direct", 7, encode_radiance(light), 2));
  wire_seed("hello", wire::make(wire::MsgType::hello, "direct", my_hello("direct", "tcp://127.0.0.1:5000").to_value()));
  ActorConfig config;
  config.params = Value::Map{{"light_samples", int64_t{2}}};
  config.scene.builtin = "cornell";
  config.inputs.push_back({"photonmap", "tcp://127.0.0.1:5001", 4, ""});
  config.pool = PoolPlace{"direct", 0, 2};
  wire_seed("config", wire::make(wire::MsgType::config, "director", config.to_value()));
  wire_seed("poll", wire::make_request("ring0.1", wire::Op::unknown, ring::encode_poll(radiosity::PollRequest{}), 3));
  wire_seed("shooter_report", wire::make(wire::MsgType::reply, "ring0.0", ring::encode_shooter_report(radiosity::ShooterReport{}), 4));
  radiosity::Element element;
  element.patch = 3;
  element.depth = 1;
  element.polygon.count = 4;
  element.radiosity = {0.5f, 0.25f, 0.125f};
  radiosity::ShooterReport checkpointed;
  checkpointed.epoch = 1;
  checkpointed.iteration = 9;
  checkpointed.candidate = radiosity::Candidate{3, 1.5, RGB{1, 1, 1}};
  checkpointed.checkpoint = std::vector{element, element};
  wire_seed("shooter_checkpoint", wire::make_request("ring0.0", wire::Op::ring_shooter, ring::encode_shooter_report(checkpointed), 5));
  wire_seed("rollback", wire::make(wire::MsgType::rollback, "director", ring::encode_rollback({2, 9, {element}})));
  radiosity::SamplePacket packet;
  packet.origin = 1;
  packet.epoch = 2;
  packet.route = 6;
  packet.points = {{0, 1, 0}};
  packet.normals = {{0, 0, 1}};
  packet.visible = {0xff};
  wire_seed("packet", wire::make_request("ring0.1", wire::Op::ring_visit, ring::encode_packet(packet, 1), 6));

  auto cornell = Scene::builtin("cornell");
  seed("scene_file", "cornell.lfscene", scene_to_bytes(*cornell));
  seed("scene_file", "cornell.image", SceneImage::encode(*cornell, "00000000fuzz0000"));
  // Every field the shipped forms carry: a texture of each kind (colour, one channel, linear data), a microfacet
  // material with all its maps and transmission, texture coordinates and tangents, an environment map with a sun, a
  // spot light.
  Scene rich;
  auto texture = [&rich](uint32_t channels, bool linear) {
    Texture t;
    t.path = "t" + std::to_string(rich.textures().size());
    t.width = t.height = 2;
    t.channels = channels;
    t.linear = linear;
    t.owned.assign(4 * channels, 200);
    t.build_pyramid();
    return static_cast<int32_t>(rich.add_texture(std::move(t)));
  };
  Material m{"rich", {0.5f, 0.5f, 0.5f}, {1, 1, 1}};
  m.type = Material::Type::metal_rough;
  m.kd_map = texture(3, false);
  m.alpha_map = texture(1, false);
  m.metallic_map = texture(1, false);
  m.roughness_map = texture(1, false);
  m.normal_map = texture(3, true);
  m.emission_map = texture(3, false);
  m.transmission = 0.5f;
  m.ior = 1.33f;
  rich.add_material(m);
  const Vec2 uv[3] = {{0, 0}, {1, 0}, {0, 1}};
  const CornerTangent tangents[3] = {{{1, 0, 0}, 1}, {{1, 0, 0}, 1}, {{1, 0, 0}, -1}};
  rich.add_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0, {nullptr, uv, tangents});
  Environment sky(2, 1, {{1, 1, 1}, {2, 2, 2}}, 1.5f, 0.5f);
  sky.set_sun({{0, 1, 0}, 0.01f, {3, 3, 3}});
  rich.set_environment(std::move(sky));
  PointLight spot{{0, 0, 1}, {1, 1, 1}};
  spot.cos_inner = 0.9f;
  spot.cos_outer = 0.5f;
  rich.add_point_light(spot);
  if (auto st = rich.finalize("rich"); !st) {
    std::fprintf(stderr, "%s\n", st.error().message.c_str());
    return 1;
  }
  seed("scene_file", "rich.lfscene", scene_to_bytes(rich));
  seed("scene_file", "rich.image", SceneImage::encode(rich, "00000000fuzz0001"));

  seed("obj", "room.obj",
       "mtllib fuzz.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
       "newmtl white\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\nillum 2\nNs 10\nKs 0.1 0.1 0.1\n"
       "usemtl white\nf 1 2 3 4\nf 8 7 6 5\nusemtl light\nf 5 6 2 1\nvt 0 0\nvn 0 1 0\nf 1/1/1 2/1/1 3/1/1\n");

  seed("script", "pool.lua",
       "scene { builtin = \"cornell\" }\nimage { width = 64, height = 64, spp = param(\"spp\", 4) }\n"
       "local d = multiplexer { lightop \"direct\" { light_samples = 2 }, replicas = 3 }\n"
       "renderers { count = 2, lighting = d }\n");
  seed("script", "glass.lua",
       "scene { builtin = \"cornell_glass\" }\nlight { point = {0, 1.5, 0}, intensity = {1, 1, 1} }\n"
       "local c = multiplexer { lightop \"photonmap\" { photons = 1000 }, replicas = 2 }\n"
       "local s = lightop \"combine\" { inputs = { lightop \"direct\" {}, c } }\n"
       "local h = host \"h1\" { launcher = \"ssh\", address = \"10.0.0.1\" }\n"
       "renderers { count = 1, lighting = s }\nfarm { security = \"none\", heartbeat_timeout = 2 }\n");
  seed("script", "radiosity.lua",
       "scene { builtin = \"cornell\" }\nradiosity { rings = 2, nodes_per_ring = 2 }\n"
       "renderers { count = 1, lighting = lightop \"radiosity\" {} }\n");
  std::printf("wrote seeds under %s\n", g_root.c_str());
  return 0;
}
