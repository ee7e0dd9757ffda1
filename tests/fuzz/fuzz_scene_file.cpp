// libFuzzer target: the scene's binary forms, which actors read from their host's cache: the shipped form
// (scene_from_bytes) and the mapped scene image (SceneImage::map, given the same bytes as a file). Both must refuse
// damaged bytes with a message, never read out of bounds.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "render/scene/scene_file.hpp"
#include "render/scene/scene_image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  (void)lf::scene_from_bytes(bytes, "fuzz");
  static const std::string path = "/tmp/lightfarm-fuzz-image-" + std::to_string(::getpid());
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  // The image names the scene it was made for: the seeds are made for this hash.
  (void)lf::SceneImage::map(path, "00000000fuzz0000", "fuzz");
  return 0;
}
