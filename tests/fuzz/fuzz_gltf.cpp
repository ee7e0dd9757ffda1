// libFuzzer target: glTF loading (tinygltf as Debian builds it, then our reading of its accessors, node tree,
// materials and lights), the other parser the director runs on a file a user names. Parsed from memory, as a .glb
// when the input starts with its magic, else as JSON.
#include <cstddef>
#include <cstdint>
#include <string>

#include "render/scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  auto scene = lf::Scene::parse_gltf_unlit("fuzz.gltf", &bytes);
  if (scene) (void)scene->finalize("scene file 'fuzz.gltf'");
  return 0;
}
