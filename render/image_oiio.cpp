// The OpenImageIO half of render/image.cpp, built as a module that only processes writing or reading images load
// (dlopen). Debian's OpenImageIO pulls in some 250 shared libraries (OpenCV, ffmpeg, GStreamer, ...): loading
// them in every actor process cost ~0.2 s of start-up each and nothing else needs them.
//
// A plain C interface, so the module and its loader agree without sharing C++ ABI details.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {
void set_error(char* err, size_t len, const std::string& what) {
  if (len) std::snprintf(err, len, "%s", what.c_str());
}
}  // namespace

extern "C" {

// Writes width*height RGB pixels: as float if `as_float`, else as 8-bit from `bytes`. 0 on success.
int lightfarm_imageio_write(const char* path, int width, int height, int as_float, const float* floats,
                            const unsigned char* bytes, const char* colorspace, char* err, size_t err_len) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) {
    set_error(err, err_len, "no writer for this file name");
    return 1;
  }
  OIIO::ImageSpec spec(width, height, 3, as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", colorspace);
  if (!out->open(path, spec)) {
    set_error(err, err_len, out->geterror());
    return 1;
  }
  bool ok = as_float ? out->write_image(OIIO::TypeDesc::FLOAT, floats) : out->write_image(OIIO::TypeDesc::UINT8, bytes);
  ok = out->close() && ok;
  if (!ok) {
    set_error(err, err_len, out->geterror());
    return 1;
  }
  return 0;
}

// Reads the first three channels as floats (as stored: no colour conversion). The caller frees *pixels with free().
int lightfarm_imageio_read(const char* path, float** pixels, int* width, int* height, char* err, size_t err_len) {
  OIIO::ImageBuf buf(path);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
    set_error(err, err_len, buf.geterror());
    return 1;
  }
  const auto& spec = buf.spec();
  if (spec.nchannels < 3) {
    set_error(err, err_len, "fewer than 3 channels");
    return 1;
  }
  const size_t n = static_cast<size_t>(spec.width) * spec.height;
  std::vector<float> all(n * spec.nchannels);
  buf.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, all.data());
  auto* rgb = static_cast<float*>(std::malloc(n * 3 * sizeof(float)));
  for (size_t i = 0; i < n; ++i) std::memcpy(rgb + 3 * i, &all[i * spec.nchannels], 3 * sizeof(float));
  *pixels = rgb;
  *width = spec.width;
  *height = spec.height;
  return 0;
}

// Reads every channel as 8-bit (as stored, no colour conversion; float files are clamped to [0, 1]). The caller
// frees *texels with free().
int lightfarm_imageio_read_texels(const char* path, unsigned char** texels, int* width, int* height, int* channels,
                                  int* is_float, char* err, size_t err_len) {
  OIIO::ImageBuf buf(path);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::UINT8)) {
    set_error(err, err_len, buf.geterror());
    return 1;
  }
  const auto& spec = buf.spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    set_error(err, err_len, "an empty image");
    return 1;
  }
  const size_t n = static_cast<size_t>(spec.width) * spec.height * spec.nchannels;
  auto* out = static_cast<unsigned char*>(std::malloc(n));
  if (!out || !buf.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, out)) {
    std::free(out);
    set_error(err, err_len, "cannot convert its pixels to 8 bits");
    return 1;
  }
  *texels = out;
  *width = spec.width;
  *height = spec.height;
  *channels = spec.nchannels;
  *is_float = spec.format.is_floating_point() ? 1 : 0;
  return 0;
}
}
