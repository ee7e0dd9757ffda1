// Loading a big glTF file against the same geometry as OBJ: Lost Empire (225k triangles, ../shared/scenes) as its
// OBJ, and as a .glb this bench writes with tinygltf from the loaded scene (one primitive per material, positions,
// normals where the scene has them, u32 indices; flat-coloured materials, so no texture decoding on either side:
// the OBJ side is parsed from its text without textures too). Goal: a user's glTF file loads in no more time than
// the same geometry as OBJ. Prints min / median / max over --runs, interleaved, and writes JSON.
//
//   build/bench/gltf_load_bench [--runs N] [--json FILE]
#include <tiny_gltf.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "bench/bench_util.hpp"
#include "render/scene/scene.hpp"

namespace {

// The scene's triangles as a .glb: one primitive per material, every corner its own vertex (as the scene keeps it).
bool write_glb(const lf::Scene& s, const std::string& path) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  tinygltf::Buffer buffer;
  tinygltf::Mesh mesh;
  auto view = [&](const void* data, size_t bytes) {
    const size_t offset = buffer.data.size();
    buffer.data.resize(offset + bytes);
    std::memcpy(buffer.data.data() + offset, data, bytes);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = offset;
    v.byteLength = bytes;
    model.bufferViews.push_back(v);
    return static_cast<int>(model.bufferViews.size() - 1);
  };
  auto accessor = [&](int view_index, int type, int component, size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view_index;
    a.type = type;
    a.componentType = component;
    a.count = count;
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size() - 1);
  };
  for (uint32_t m = 0; m < s.materials().size(); ++m) {
    std::vector<float> p, n;
    std::vector<uint32_t> idx;
    for (uint32_t t = 0; t < s.triangle_count(); ++t) {
      if (s.material_of(t) != m) continue;
      for (int c = 0; c < 3; ++c) {
        const lf::Vec3 v = s.vertex(t, c);
        p.insert(p.end(), {v.x, v.y, v.z});
        if (s.has_shading_normals()) {
          const lf::Vec3 k = s.corner_normal(t, c);
          n.insert(n.end(), {k.x, k.y, k.z});
        }
        idx.push_back(static_cast<uint32_t>(idx.size()));
      }
    }
    if (idx.empty()) continue;
    const lf::Material& mat = s.material(m);
    tinygltf::Material g;
    g.name = mat.name;
    g.pbrMetallicRoughness.baseColorFactor = {mat.kd.x, mat.kd.y, mat.kd.z, 1};
    model.materials.push_back(g);
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = static_cast<int>(model.materials.size() - 1);
    const size_t vertices = p.size() / 3;
    prim.attributes["POSITION"] = accessor(view(p.data(), p.size() * 4), TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, vertices);
    if (!n.empty())
      prim.attributes["NORMAL"] = accessor(view(n.data(), n.size() * 4), TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, vertices);
    prim.indices = accessor(view(idx.data(), idx.size() * 4), TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size());
    mesh.primitives.push_back(prim);
  }
  // Accessors need min/max for POSITION by the specification; the reader here does not use them.
  for (auto& prim : mesh.primitives) {
    tinygltf::Accessor& a = model.accessors[static_cast<size_t>(prim.attributes["POSITION"])];
    a.minValues = {-1e30, -1e30, -1e30};
    a.maxValues = {1e30, 1e30, 1e30};
  }
  model.buffers.push_back(buffer);
  model.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  tinygltf::TinyGLTF writer;
  return writer.WriteGltfSceneToFile(&model, path, true, true, false, true);
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/gltf_load_bench [--runs N] [--json FILE]",
                            {"--runs", "--json"});
  int runs = 5;
  std::string json = "bench-gltf-load.json";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--runs") runs = std::max(1, std::atoi(argv[i + 1]));
    if (std::string(argv[i]) == "--json") json = argv[i + 1];
  }
  const std::string obj = bench::shared_scene("lost_empire/lost_empire.obj");
  if (obj.empty()) return 0;
  std::ifstream obj_in(obj), mtl_in(obj.substr(0, obj.size() - 4) + ".mtl");
  std::stringstream obj_text, mtl_text;
  obj_text << obj_in.rdbuf();
  mtl_text << mtl_in.rdbuf();
  auto scene = lf::Scene::parse_obj_unlit(obj_text.str(), mtl_text.str(), obj);
  if (!scene) return std::fprintf(stderr, "%s\n", scene.error().message.c_str()), 1;
  const std::string glb = (bench::fs::temp_directory_path() / ("lightfarm-bench-" + std::to_string(::getpid()) + ".glb")).string();
  if (!write_glb(*scene, glb)) return std::fprintf(stderr, "cannot write %s\n", glb.c_str()), 1;
  std::printf("Lost Empire: %zu triangles; OBJ %.1f MB of text, glb %.1f MB\n", scene->triangle_count(),
              static_cast<double>(obj_text.str().size()) / 1e6, static_cast<double>(bench::fs::file_size(glb)) / 1e6);
  std::vector<double> obj_s, gltf_s, ratio;
  uint32_t gltf_triangles = 0;
  for (int r = 0; r < runs; ++r) {
    // Both from the disk's cache: the OBJ's text read and parsed, the .glb read and converted.
    const double a = bench::seconds_of([&] {
      std::ifstream in(obj);
      std::stringstream text;
      text << in.rdbuf();
      (void)lf::Scene::parse_obj_unlit(text.str(), mtl_text.str(), obj);
    });
    const double b = bench::seconds_of([&] {
      auto s = lf::Scene::load_gltf_unlit(glb);
      gltf_triangles = s ? s->triangle_count() : 0;
    });
    obj_s.push_back(a);
    gltf_s.push_back(b);
    ratio.push_back(b / a);
  }
  bench::fs::remove(glb);
  if (gltf_triangles != scene->triangle_count()) return std::fprintf(stderr, "the .glb read back wrong\n"), 1;
  const auto o = bench::spread(obj_s), g = bench::spread(gltf_s), q = bench::spread(ratio);
  std::printf("OBJ  %.3f s (%.3f-%.3f)\nglTF %.3f s (%.3f-%.3f)\nglTF / OBJ %.2f (%.2f-%.2f) over %d interleaved runs (goal <= 1)\n",
              o.median, o.min, o.max, g.median, g.min, g.max, q.median, q.min, q.max, runs);
  const lf::Value doc = lf::Value::Map{{"triangles", static_cast<int64_t>(gltf_triangles)}, {"obj_seconds", o.to_value()},
                                       {"gltf_seconds", g.to_value()}, {"ratio", q.to_value()}, {"runs", runs}};
  std::ofstream(json) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", json.c_str());
  return 0;
}
