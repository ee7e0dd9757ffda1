#include "render/images/image.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <vector>

#include "core/private_dir.hpp"

namespace lf {

bool all_black(const Image& image) {
  for (const RGB& p : image.pixels)
    if (!is_black(p)) return false;
  return true;
}

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

namespace {
// A Display read once per image, not per pixel: the exposure's factor and the curve.
struct ToneCurve {
  enum class Kind { clamp, reinhard, aces } kind = Kind::clamp;
  float scale = 1;
  explicit ToneCurve(const Display& d)
      : kind(d.tonemap == "reinhard" ? Kind::reinhard : d.tonemap == "aces" ? Kind::aces : Kind::clamp),
        scale(std::exp2(d.exposure)) {}
  float operator()(float linear) const {
    const float v = std::max(0.0f, linear * scale);
    switch (kind) {
      case Kind::reinhard: return v / (1.0f + v);
      case Kind::aces:  // Narkowicz 2015: a fit of the ACES reference rendering transform, per channel.
        return std::clamp((v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f), 0.0f, 1.0f);
      case Kind::clamp: break;
    }
    return std::min(v, 1.0f);
  }
};
}  // namespace

float display_value(float linear, const Display& display) { return ToneCurve(display)(linear); }

static float to_srgb(float linear) { return srgb_encode(std::clamp(linear, 0.0f, 1.0f)); }

float display_srgb(float linear, const Display& display) { return to_srgb(ToneCurve(display)(linear)); }

namespace {
// Opens the first of a module's usual places that loads: $`env`, beside the executable (build/ for the lightfarm
// binary), where an install puts it (../LIBDIR/lightfarm from bin/: the Debian package's
// /usr/lib/lightfarm), ../lib from it, where this build put it. `what` lists every failure
// otherwise.
void* open_module(const char* env, const char* name, const char* build_path, std::string& what) {
  std::vector<std::string> candidates;
  if (const char* set = std::getenv(env)) candidates.push_back(set);
  std::error_code ec;
  auto exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    candidates.push_back((exe.parent_path() / name).string());
    candidates.push_back((exe.parent_path() / ".." / LIGHTFARM_MODULE_DIR / name).string());
    candidates.push_back((exe.parent_path() / ".." / "lib" / name).string());
  }
  candidates.push_back(build_path);
  std::string tried;
  for (const auto& path : candidates) {
    if (void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
    tried += std::string("\n  ") + ::dlerror();
  }
  what = std::string("cannot load the image module ") + name + ":" + tried;
  return nullptr;
}

// The OpenImageIO module (image_oiio.cpp), loaded on first use.
struct ImageModule {
  using WriteFn = int (*)(const char*, int, int, int, const float*, const unsigned char*, const char*,
                          const char* const*, char*, size_t);
  using ReadFn = int (*)(const char*, float**, int*, int*, char*, size_t);
  using ReadTexelsFn = int (*)(const char*, unsigned char**, int*, int*, int*, int*, char*, size_t);
  using ReadNotesFn = int (*)(const char*, const char*, char*, size_t, char*, size_t);
  WriteFn write = nullptr;
  ReadFn read = nullptr;
  ReadTexelsFn read_texels = nullptr;
  ReadNotesFn read_notes = nullptr;
  std::string error;
};

const ImageModule& image_module() {
  static const ImageModule module = [] {
    ImageModule m;
    void* handle = open_module("LIGHTFARM_IMAGEIO_MODULE", LIGHTFARM_IMAGEIO_NAME, LIGHTFARM_IMAGEIO_BUILD_PATH, m.error);
    if (!handle) return m;
    m.write = reinterpret_cast<ImageModule::WriteFn>(::dlsym(handle, "lightfarm_imageio_write_annotated"));
    m.read = reinterpret_cast<ImageModule::ReadFn>(::dlsym(handle, "lightfarm_imageio_read"));
    m.read_texels = reinterpret_cast<ImageModule::ReadTexelsFn>(::dlsym(handle, "lightfarm_imageio_read_texels"));
    m.read_notes = reinterpret_cast<ImageModule::ReadNotesFn>(::dlsym(handle, "lightfarm_imageio_read_notes"));
    if (!m.write || !m.read || !m.read_texels || !m.read_notes) {
      m = ImageModule{};
      m.error = std::string("the image module ") + LIGHTFARM_IMAGEIO_NAME + " lacks its entry points";
    }
    return m;
  }();
  return module;
}

// The EXR and PNG writer (image_exr_png.cpp): what a farm's image needs, without OpenImageIO's load.
struct ExrPngModule {
  using WriteFn = int (*)(const char*, int, int, int, const float*, const unsigned char*, const char* const*, char*, size_t);
  WriteFn write = nullptr;
  std::string error;
};

const ExrPngModule& exr_png_module() {
  static const ExrPngModule module = [] {
    ExrPngModule m;
    void* handle = open_module("LIGHTFARM_EXR_PNG_MODULE", LIGHTFARM_EXR_PNG_NAME, LIGHTFARM_EXR_PNG_BUILD_PATH, m.error);
    if (!handle) return m;
    m.write = reinterpret_cast<ExrPngModule::WriteFn>(::dlsym(handle, "lightfarm_exr_png_write_annotated"));
    if (!m.write) m.error = std::string("the image module ") + LIGHTFARM_EXR_PNG_NAME + " lacks its entry point";
    return m;
  }();
  return module;
}

bool written_without_oiio(const std::string& ext) { return ext == ".exr" || ext == ".png"; }
}  // namespace

void preload_image_writer(const std::string& path) {
  if (written_without_oiio(extension_of(path))) {
    (void)exr_png_module();
  } else {
    (void)image_module();
  }
}

namespace {

// The file is on disk (fsync) and, for PNG, ends with its IEND chunk.
Status check_written(const std::string& file, const std::string& ext) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return make_error(std::strerror(errno));
  Status result = Ok{};
  if (::fsync(fd) != 0) result = make_error(std::string("cannot flush it to disk: ") + std::strerror(errno));
  if (result && ext == ".png") {
    static const unsigned char kIend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xAE, 0x42, 0x60, 0x82};
    unsigned char tail[12] = {};
    const off_t size = ::lseek(fd, 0, SEEK_END);
    if (size < 12 || ::pread(fd, tail, 12, size - 12) != 12 || std::memcmp(tail, kIend, 12) != 0)
      result = make_error("the PNG came out incomplete (disk full or file size limit?)");
  }
  ::close(fd);
  return result;
}

}  // namespace

std::string partial_path(const std::string& target) {
  const fs::path t(target);
  return (t.parent_path() / ("." + t.stem().string() + ".partial-" + std::to_string(::getpid()) + t.extension().string()))
      .string();
}

void sweep_stale_partials(const std::string& target_path) {
  const fs::path target(target_path);
  const std::string head = "." + target.stem().string() + ".partial-", ext = target.extension().string();
  std::error_code ec;
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= head.size() + ext.size() || name.rfind(head, 0) != 0 || !name.ends_with(ext)) continue;
    if (owner_is_gone(std::string_view(name).substr(head.size(), name.size() - head.size() - ext.size()))) {
      std::error_code rm;
      fs::remove(it->path(), rm);
    }
  }
}

bool write_file_whole(const std::string& target, std::string_view bytes) {
  const std::string temporary = partial_path(target);
  bool written = false;
  {
    std::ofstream f(temporary, std::ios::binary | std::ios::trunc);
    written = static_cast<bool>(f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()))) &&
              static_cast<bool>(f.flush());
  }
  std::error_code ec;
  if (written) fs::rename(temporary, target, ec);
  if (!written || ec) fs::remove(temporary, ec);
  return written && !ec;
}

Status write_image(const Image& image, const std::string& path, const Display& display, const ImageNotes& notes) {
  if (auto st = check_output_path(path); !st) return st;
  const std::string ext = extension_of(path);
  const bool light = written_without_oiio(ext);
  if (light ? !exr_png_module().write : !image_module().write)
    return make_error(light ? exr_png_module().error : image_module().error);
  fs::path target(path);
  sweep_stale_partials(path);
  fs::path temp = partial_path(path);
  const bool linear = is_float_format(ext);
  std::vector<unsigned char> bytes;
  if (!linear) {
    const ToneCurve curve(display);
    bytes.resize(image.pixels.size() * 3);
    for (size_t i = 0; i < image.pixels.size(); ++i) {
      bytes[3 * i] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(curve(image.pixels[i].x))));
      bytes[3 * i + 1] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(curve(image.pixels[i].y))));
      bytes[3 * i + 2] = static_cast<unsigned char>(std::lround(255.0f * to_srgb(curve(image.pixels[i].z))));
    }
  }
  char err[512] = {0};
  const auto* floats = reinterpret_cast<const float*>(image.pixels.data());
  std::vector<const char*> note_strings;
  for (const auto& [key, value] : notes) note_strings.insert(note_strings.end(), {key.c_str(), value.c_str()});
  note_strings.push_back(nullptr);
  const int rc = light ? exr_png_module().write(temp.c_str(), image.width, image.height, linear ? 1 : 0, floats,
                                                bytes.data(), note_strings.data(), err, sizeof err)
                       : image_module().write(temp.c_str(), image.width, image.height, linear ? 1 : 0, floats,
                                              bytes.data(), linear ? "Linear" : "sRGB", note_strings.data(), err, sizeof err);
  std::error_code ec;
  if (rc != 0) {
    fs::remove(temp, ec);
    return make_error("cannot write '" + path + "': " + err);
  }
  // Some writers (PNG) report success on a full disk: check that the file is whole and on disk before it
  // replaces anything, so a failed write keeps the previous image.
  if (auto st = check_written(temp.string(), ext); !st) {
    fs::remove(temp, ec);
    return make_error("cannot write '" + path + "': " + st.error().message);
  }
  fs::rename(temp, target, ec);
  if (ec) {
    const std::string why = ec.message();  // before remove() overwrites ec
    fs::remove(temp, ec);
    return make_error("cannot write '" + path + "': " + why);
  }
  return Ok{};
}

Result<ImageNotes> read_image_notes(const std::string& path, const std::string& prefix) {
  const auto& module = image_module();
  if (!module.read_notes) return make_error(module.error);
  std::vector<char> text(1 << 16);
  char err[512] = {0};
  if (module.read_notes(path.c_str(), prefix.c_str(), text.data(), text.size(), err, sizeof err) != 0)
    return make_error("cannot read '" + path + "': " + err);
  ImageNotes notes;
  std::string_view rest(text.data());
  for (size_t end; (end = rest.find('\n')) != std::string_view::npos; rest.remove_prefix(end + 1)) {
    const std::string_view line = rest.substr(0, end);
    const size_t eq = line.find('=');
    if (eq != std::string_view::npos) notes.emplace_back(std::string(line.substr(0, eq)), std::string(line.substr(eq + 1)));
  }
  return notes;
}

Result<Image> read_image(const std::string& path) {
  const auto& module = image_module();
  if (!module.read) return make_error(module.error);
  float* data = nullptr;
  int w = 0, h = 0;
  char err[512] = {0};
  if (module.read(path.c_str(), &data, &w, &h, err, sizeof err) != 0)
    return make_error("cannot read '" + path + "': " + err);
  Image img(w, h);
  const bool srgb = extension_of(path) != ".exr";
  auto decode = [&](float v) { return srgb ? srgb_decode(v) : v; };
  for (size_t i = 0; i < img.pixels.size(); ++i)
    img.pixels[i] = {decode(data[3 * i]), decode(data[3 * i + 1]), decode(data[3 * i + 2])};
  std::free(data);
  return img;
}

Result<Texels> read_texels(const std::string& path) {
  const auto& module = image_module();
  if (!module.read_texels) return make_error(module.error);
  unsigned char* data = nullptr;
  int w = 0, h = 0, c = 0, is_float = 0;
  char err[512] = {0};
  if (module.read_texels(path.c_str(), &data, &w, &h, &c, &is_float, err, sizeof err) != 0)
    return make_error("cannot read '" + path + "': " + err);
  Texels t;
  t.width = w;
  t.height = h;
  t.channels = c;
  t.linear = is_float != 0;
  t.bytes.assign(data, data + static_cast<size_t>(w) * h * c);
  std::free(data);
  return t;
}

}  // namespace lf
