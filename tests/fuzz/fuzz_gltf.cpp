// libFuzzer target: glTF loading (tinygltf as Debian builds it, then our reading of its accessors, node tree,
// materials and lights) and the catalogue the script reads (cameras, and each animated camera's views over its
// animation), the other parser the director runs on a file a user names. Parsed from memory, as a .glb when the
// input starts with its magic, else as JSON.
#include <cstddef>
#include <cstdint>
#include <string>

#include "render/scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  auto scene = lf::Scene::parse_gltf_unlit("fuzz.gltf", &bytes);
  if (scene) (void)scene->finalize("scene file 'fuzz.gltf'");
  if (auto catalogue = lf::Scene::catalogue_gltf("fuzz.gltf", &bytes); catalogue)
    for (size_t c = 0; c < catalogue->cameras.size() && c < 4; ++c)
      if (catalogue->cameras[c].animated)
        (void)lf::Scene::gltf_camera_views("fuzz.gltf", c, {-1, 0, 0.5, catalogue->cameras[c].animation_seconds, 1e9}, &bytes);
  return 0;
}
