#include "render/image.hpp"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace lf {

namespace fs = std::filesystem;

static std::string extension_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

static bool is_float_format(const std::string& ext) { return ext == ".exr"; }

Status check_output_path(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext != ".exr" && ext != ".png" && ext != ".tif" && ext != ".tiff")
    return make_error("output '" + path + "': unsupported image format '" + ext + "' (use .exr, .png or .tif)");
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return make_error("output '" + path + "': directory '" + dir.string() + "' does not exist");
  // Creating a probe file is the only check that holds for root and for odd file systems alike.
  fs::path probe = dir / (".lightfarm-probe-" + std::to_string(::getpid()));
  int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0)
    return make_error("output '" + path + "': directory '" + dir.string() + "' is not writable (" +
                      std::strerror(errno) + ")");
  ::close(fd);
  ::unlink(probe.c_str());
  if (fs::is_directory(path, ec)) return make_error("output '" + path + "' is a directory");
  return Ok{};
}

static float to_srgb(float linear) {
  linear = std::clamp(linear, 0.0f, 1.0f);
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

Status write_image(const Image& image, const std::string& path) {
  if (auto st = check_output_path(path); !st) return st;
  const std::string ext = extension_of(path);
  fs::path target(path);
  fs::path temp = target.parent_path() /
                  ("." + target.stem().string() + ".partial-" + std::to_string(::getpid()) + target.extension().string());

  auto out = OIIO::ImageOutput::create(temp.string());
  if (!out) return make_error("output '" + path + "': no writer for '" + ext + "'");
  const bool linear = is_float_format(ext);
  OIIO::ImageSpec spec(image.width, image.height, 3, linear ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", linear ? "Linear" : "sRGB");
  if (!out->open(temp.string(), spec)) {
    std::string why = out->geterror();
    return make_error("cannot write '" + path + "': " + why);
  }
  bool ok;
  if (linear) {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.pixels.data());
  } else {
    std::vector<unsigned char> bytes(image.pixels.size() * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i) {
      bytes[3 * i] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(image.pixels[i].x)));
      bytes[3 * i + 1] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(image.pixels[i].y)));
      bytes[3 * i + 2] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(image.pixels[i].z)));
    }
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  ok = out->close() && ok;
  std::error_code ec;
  if (!ok) {
    std::string why = out->geterror();
    fs::remove(temp, ec);
    return make_error("cannot write '" + path + "': " + why);
  }
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    return make_error("cannot write '" + path + "': " + ec.message());
  }
  return Ok{};
}

Result<Image> read_image(const std::string& path) {
  OIIO::ImageBuf buf(path);
  if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) return make_error("cannot read '" + path + "': " + buf.geterror());
  const auto& spec = buf.spec();
  if (spec.nchannels < 3) return make_error("'" + path + "' has fewer than 3 channels");
  Image img(spec.width, spec.height);
  std::vector<float> data(static_cast<size_t>(spec.width) * spec.height * spec.nchannels);
  buf.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, data.data());
  const bool srgb = extension_of(path) != ".exr";
  auto decode = [&](float v) {
    if (!srgb) return v;
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
  };
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    const float* p = &data[i * spec.nchannels];
    img.pixels[i] = {decode(p[0]), decode(p[1]), decode(p[2])};
  }
  return img;
}

}  // namespace lf
