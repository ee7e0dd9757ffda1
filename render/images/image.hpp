#pragma once
// Images and how they reach disk. Format from the extension: .exr is linear float, .png/.tif 8-bit sRGB.
// A file is written to a temporary name beside the target and renamed, so a failed or interrupted write never
// leaves a half-written image under the requested name.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
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

// True when every pixel is exactly 0: nothing the camera saw was lit or emitting.
bool all_black(const Image& image);

// An error if the extension is not one we write, or the directory does not exist or is not writable.
Status check_output_path(const std::string& path);
// Writing a file whole: the temporary it goes to first (.STEM.partial-PID.EXT beside it, renamed into place), and
// the removal of such temporaries beside `target` whose writer no longer runs (a process SIGKILLed while writing
// cannot remove its own).
std::string partial_path(const std::string& target);
void sweep_stale_partials(const std::string& target);
// `bytes` to `target` that way; false (and no temporary left) if it could not be written.
bool write_file_whole(const std::string& target, std::string_view bytes);
// How an 8-bit output shows linear radiance: scaled by 2^exposure, then mapped to [0, 1] per channel by the tone
// map ("clamp": min(v, 1); "reinhard": v / (1 + v); "aces": Narkowicz's fit of the ACES filmic curve), then sRGB.
// Float outputs (EXR) ignore it: they keep the linear values.
struct Display {
  float exposure = 0;
  std::string tonemap = "clamp";
};
// One linear channel value as the display maps it, before sRGB encoding (in [0, 1]).
float display_value(float linear, const Display& display);
// The same, sRGB-encoded: what an 8-bit output stores, over 255.
float display_srgb(float linear, const Display& display);

// Text kept in the file beside the pixels (EXR string attributes, PNG tEXt chunks), e.g. {"lightfarm:samples",
// "64"}: what produced the image.
using ImageNotes = std::vector<std::pair<std::string, std::string>>;
Status write_image(const Image& image, const std::string& path, const Display& display = {}, const ImageNotes& notes = {});
// The notes an image file keeps whose names begin with `prefix` (read through OpenImageIO).
Result<ImageNotes> read_image_notes(const std::string& path, const std::string& prefix = "lightfarm:");
Result<Image> read_image(const std::string& path);  // linear RGB (sRGB files are decoded)
// An image file's pixels as 8-bit texels, every channel, top row first, for textures. `linear` when the file held
// floats (EXR, HDR): their values are then linear, clamped to [0, 1], not sRGB-encoded.
struct Texels {
  int width = 0, height = 0, channels = 0;
  bool linear = false;
  std::vector<uint8_t> bytes;
};
Result<Texels> read_texels(const std::string& path);
// Loads the module write_image will use for `path` now, on this thread: for .exr and .png OpenEXR and libpng
// (image_exr_png.cpp), else OpenImageIO and its ~250 libraries. The director calls it on a background thread while
// its actors render, so writing the image later costs only the write.
void preload_image_writer(const std::string& path);

}  // namespace lf
