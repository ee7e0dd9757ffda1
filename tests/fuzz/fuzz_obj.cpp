// libFuzzer target: OBJ loading (tinyobjloader behind Scene::load_obj, then our checks and triangulation), the
// one parser the director runs on a file a user names. The input is the OBJ; its `mtllib` may name fuzz.mtl,
// which holds the same bytes, so MTL parsing is reached too.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "render/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = "/tmp/lightfarm-fuzz-obj-" + std::to_string(::getpid());
  static const bool made = (std::system(("mkdir -p " + dir).c_str()), true);
  (void)made;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::ofstream(dir + "/fuzz.obj", std::ios::binary | std::ios::trunc) << bytes;
  std::ofstream(dir + "/fuzz.mtl", std::ios::binary | std::ios::trunc) << bytes;
  (void)lf::Scene::load_obj(dir + "/fuzz.obj");
  return 0;
}
