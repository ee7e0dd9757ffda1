// libFuzzer target: OBJ loading (tinyobjloader behind Scene's OBJ reader, then our checks and triangulation), the
// one parser the director runs on a file a user names. The input is the OBJ and, for any `mtllib` it names, the
// MTL too, so MTL parsing is reached as well. Parsed from memory (the same conversion as a file, without
// textures): writing two files per input made this target ten times slower than the others.
#include <cstddef>
#include <cstdint>
#include <string>

#include "render/scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  auto scene = lf::Scene::parse_obj_unlit(bytes, bytes, "fuzz.obj");
  if (scene) (void)scene->finalize("scene file 'fuzz.obj'");
  return 0;
}
