// The OpenImageIO half of render/images/image.cpp, built as a module that only processes writing or reading images load
// (dlopen). Debian's OpenImageIO pulls in some 250 shared libraries (OpenCV, ffmpeg, GStreamer, ...): loading
// them in every actor process cost ~0.2 s of start-up each and nothing else needs them.
//
// A plain C interface, so the module and its loader agree without sharing C++ ABI details.
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

// Writes width*height RGB pixels: as float if `as_float`, else as 8-bit from `bytes`, with `notes` (key, value, ...,
// null; may be null) as string attributes. 0 on success.
int lightfarm_imageio_write_annotated(const char* path, int width, int height, int as_float, const float* floats,
                                      const unsigned char* bytes, const char* colorspace, const char* const* notes,
                                      char* err, size_t err_len) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) {
    set_error(err, err_len, "no writer for this file name");
    return 1;
  }
  OIIO::ImageSpec spec(width, height, 3, as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", colorspace);
  for (const char* const* n = notes; n && n[0] && n[1]; n += 2) spec.attribute(n[0], n[1]);
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

// The file's string attributes whose names begin with `prefix`, as "name=value" lines, into out (cut at out_len).
int lightfarm_imageio_read_notes(const char* path, const char* prefix, char* out, size_t out_len, char* err,
                                 size_t err_len) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    set_error(err, err_len, OIIO::geterror());
    return 1;
  }
  std::string lines;
  for (const auto& a : in->spec().extra_attribs)
    if (a.type() == OIIO::TypeDesc::STRING && a.name().string().rfind(prefix, 0) == 0)
      lines += a.name().string() + "=" + a.get_string() + "\n";
  in->close();
  if (out_len) std::snprintf(out, out_len, "%s", lines.c_str());
  return 0;
}

// Reads the first three channels as floats (as stored: no colour conversion). The caller frees *pixels with free().
int lightfarm_imageio_read(const char* path, float** pixels, int* width, int* height, char* err, size_t err_len) {
  // ImageInput, not ImageBuf: no image cache, so a file rewritten since an earlier read is read as it is now (the
  // cache kept the old size of a file written again at another size, and the copy overran).
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    set_error(err, err_len, OIIO::geterror());
    return 1;
  }
  const OIIO::ImageSpec spec = in->spec();
  if (spec.nchannels < 3 || spec.width <= 0 || spec.height <= 0) {
    set_error(err, err_len, spec.nchannels < 3 ? "fewer than 3 channels" : "an empty image");
    return 1;
  }
  const size_t n = static_cast<size_t>(spec.width) * spec.height;
  auto* rgb = static_cast<float*>(std::malloc(n * 3 * sizeof(float)));
  if (!rgb || !in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, rgb)) {
    std::free(rgb);
    set_error(err, err_len, "cannot read its pixels: " + in->geterror());
    return 1;
  }
  in->close();
  *pixels = rgb;
  *width = spec.width;
  *height = spec.height;
  return 0;
}

// Reads every channel as 8-bit (as stored, no colour conversion; float files are clamped to [0, 1]). The caller
// frees *texels with free().
int lightfarm_imageio_read_texels(const char* path, unsigned char** texels, int* width, int* height, int* channels,
                                  int* is_float, char* err, size_t err_len) {
  // ImageInput, not ImageBuf: no image cache, so a file rewritten since an earlier read is read as it is now.
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    set_error(err, err_len, OIIO::geterror());
    return 1;
  }
  const OIIO::ImageSpec spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) {
    set_error(err, err_len, "an empty image");
    return 1;
  }
  const size_t n = static_cast<size_t>(spec.width) * spec.height * spec.nchannels;
  auto* out = static_cast<unsigned char*>(std::malloc(n));
  if (!out || !in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, out)) {
    std::free(out);
    set_error(err, err_len, "cannot read its pixels: " + in->geterror());
    return 1;
  }
  in->close();
  *texels = out;
  *width = spec.width;
  *height = spec.height;
  *channels = spec.nchannels;
  *is_float = spec.format.is_floating_point() ? 1 : 0;
  return 0;
}
}
