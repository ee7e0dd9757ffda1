#pragma once
// Images and how they reach disk. Format from the extension: .exr is linear float, .png/.tif 8-bit sRGB.
// A file is written to a temporary name beside the target and renamed, so a failed or interrupted write never
// leaves a half-written image under the requested name.
#include <string>
#include <vector>

#include "core/result.hpp"
#include "render/math.hpp"

namespace lf {

struct Image {
  int width = 0, height = 0;
  std::vector<RGB> pixels;  // row-major, top row first
  Image() = default;
  Image(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h) {}
  RGB& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
  const RGB& at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
};

// An error if the extension is not one we write, or the directory does not exist or is not writable.
Status check_output_path(const std::string& path);
Status write_image(const Image& image, const std::string& path);
Result<Image> read_image(const std::string& path);  // linear RGB (sRGB files are decoded)
// Loads the image module (OpenImageIO and its ~250 libraries) now, on this thread. The director calls it on a
// background thread while its actors start, so writing the image later costs only the write.
void preload_image_io();

}  // namespace lf
