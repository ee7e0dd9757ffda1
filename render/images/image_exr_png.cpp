// The two formats a farm writes most, with their reference libraries (OpenEXR, libpng), built as a module the
// director loads to write its image. OpenImageIO (image_oiio.cpp) writes these too, but loading Debian's build of it
// means some 250 shared libraries and 154k symbol lookups: 0.4-0.6 CPU-seconds of every farm (docs/decisions.md,
// "The image module loads beside the render"). This module loads in a few milliseconds; OpenImageIO stays for every
// other format and for reading.
//
// A plain C interface, like image_oiio.cpp, so the module and its loader share no C++ ABI details.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

namespace {

void set_error(char* err, size_t len, const std::string& what) {
  if (len) std::snprintf(err, len, "%s", what.c_str());
}

// Linear float RGB, ZIP-compressed (OpenEXR's default, and what OpenImageIO wrote).
int write_exr(const char* path, int width, int height, const float* rgb, const char* const* notes, char* err,
              size_t err_len) {
  try {
    Imf::Header header(width, height);
    for (const char* const* n = notes; n && n[0] && n[1]; n += 2) header.insert(n[0], Imf::StringAttribute(n[1]));
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer frame;
    const size_t pixel = 3 * sizeof(float), row = pixel * static_cast<size_t>(width);
    char* base = const_cast<char*>(reinterpret_cast<const char*>(rgb));  // OpenEXR's Slice takes char*; it only reads
    frame.insert("R", Imf::Slice(Imf::FLOAT, base, pixel, row));
    frame.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), pixel, row));
    frame.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), pixel, row));
    Imf::OutputFile file(path, header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
    return 0;
  } catch (const std::exception& e) {
    set_error(err, err_len, e.what());
    return 1;
  }
}

struct PngErrors {
  char message[256] = "libpng failed";
};

[[noreturn]] void png_failed(png_structp png, png_const_charp message) {
  auto* errors = static_cast<PngErrors*>(png_get_error_ptr(png));
  std::snprintf(errors->message, sizeof errors->message, "%s", message);
  png_longjmp(png, 1);
}

void png_warned(png_structp, png_const_charp) {}

// libpng's own writer says only "Write Error"; this one says why (a full disk: "No space left on device").
void png_write_data(png_structp png, png_bytep data, size_t length) {
  if (std::fwrite(data, 1, length, static_cast<FILE*>(png_get_io_ptr(png))) != length) png_error(png, std::strerror(errno));
}

void png_flush_data(png_structp png) {
  if (std::fflush(static_cast<FILE*>(png_get_io_ptr(png))) != 0) png_error(png, std::strerror(errno));
}

// 8-bit sRGB RGB. No C++ object lives across the setjmp: libpng reports errors by longjmp.
int write_png(const char* path, int width, int height, const unsigned char* rgb, const char* const* notes, char* err,
              size_t err_len) {
  // tEXt chunks; libpng keeps pointers to the strings until the info is written, and they outlive it here.
  png_text texts[8] = {};
  int text_count = 0;
  for (const char* const* n = notes; n && n[0] && n[1] && text_count < 8; n += 2, ++text_count) {
    texts[text_count].compression = PNG_TEXT_COMPRESSION_NONE;
    texts[text_count].key = const_cast<char*>(n[0]);
    texts[text_count].text = const_cast<char*>(n[1]);
  }
  FILE* file = std::fopen(path, "wb");
  if (!file) {
    set_error(err, err_len, std::strerror(errno));
    return 1;
  }
  PngErrors errors;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, png_failed, png_warned);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_write_struct(&png, nullptr);
    std::fclose(file);
    set_error(err, err_len, "libpng: out of memory");
    return 1;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    set_error(err, err_len, errors.message);
    return 1;
  }
  png_set_write_fn(png, file, png_write_data, png_flush_data);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  if (text_count > 0) png_set_text(png, info, texts, text_count);
  png_write_info(png, info);
  const size_t row = 3 * static_cast<size_t>(width);
  for (int y = 0; y < height; ++y) png_write_row(png, rgb + row * static_cast<size_t>(y));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(file) != 0) {
    set_error(err, err_len, std::strerror(errno));
    return 1;
  }
  return 0;
}

}  // namespace

extern "C" {

// Writes width*height RGB pixels to `path`: an EXR of `floats` if `as_float`, else a PNG of `bytes`, with `notes`
// (key, value, key, value, ..., null; may be null) as string attributes or tEXt chunks. 0 on success.
int lightfarm_exr_png_write_annotated(const char* path, int width, int height, int as_float, const float* floats,
                                     const unsigned char* bytes, const char* const* notes, char* err, size_t err_len) {
  return as_float ? write_exr(path, width, height, floats, notes, err, err_len)
                  : write_png(path, width, height, bytes, notes, err, err_len);
}
}
