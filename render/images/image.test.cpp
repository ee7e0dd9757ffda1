#include "render/images/image.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace lf {

namespace fs = std::filesystem;

class ImageTest : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    dir = fs::temp_directory_path() / ("lightfarm-image-test-" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  size_t files_in_dir() const {
    return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
  }
};

static Image gradient() {
  Image img(8, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 8; ++x) img.at(x, y) = {x / 7.0f, y / 3.0f, 2.0f};
  return img;
}

TEST_F(ImageTest, ExrKeepsLinearFloats) {
  Image img = gradient();
  auto path = (dir / "a.exr").string();
  ASSERT_TRUE(write_image(img, path).ok());
  auto back = read_image(path);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->pixels, img.pixels);  // values above 1 survive in EXR
  EXPECT_EQ(files_in_dir(), 1u);        // no temporary left beside it
}

// Exposure and tone maps change 8-bit outputs only: each as its closed form, read back through sRGB decoding.
TEST_F(ImageTest, ExposureAndToneMapsShapePngsAndLeaveExrLinear) {
  EXPECT_FLOAT_EQ(display_value(0.2f, {1, "clamp"}), 0.4f);
  EXPECT_FLOAT_EQ(display_value(0.8f, {1, "clamp"}), 1.0f);
  EXPECT_FLOAT_EQ(display_value(1.0f, {0, "reinhard"}), 0.5f);
  EXPECT_FLOAT_EQ(display_value(1.5f, {1, "reinhard"}), 0.75f);
  EXPECT_NEAR(display_value(1.0f, {0, "aces"}), 2.54f / 3.16f, 1e-6f);
  EXPECT_FLOAT_EQ(display_value(100.0f, {0, "aces"}), 1.0f);
  EXPECT_FLOAT_EQ(display_value(-3.0f, {2, "reinhard"}), 0.0f);
  Image img(3, 1);
  img.pixels = {{0.2f, 0.2f, 0.2f}, {1.0f, 1.0f, 1.0f}, {3.0f, 3.0f, 3.0f}};
  struct Case {
    Display display;
    std::array<float, 3> expect;
  };
  for (const Case& c : {Case{{1, "clamp"}, {0.4f, 1.0f, 1.0f}}, Case{{0, "reinhard"}, {0.2f / 1.2f, 0.5f, 0.75f}},
                        Case{{-1, "reinhard"}, {0.1f / 1.1f, 0.5f / 1.5f, 0.6f}}}) {
    const auto path = (dir / ("t-" + c.display.tonemap + ".png")).string();
    ASSERT_TRUE(write_image(img, path, c.display).ok());
    auto back = read_image(path);
    ASSERT_TRUE(back.ok());
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(back->pixels[static_cast<size_t>(i)].y, c.expect[static_cast<size_t>(i)], 0.006f)
        << c.display.tonemap << " exposure " << c.display.exposure << " pixel " << i;
  }
  const auto exr = (dir / "t.exr").string();
  ASSERT_TRUE(write_image(img, exr, {3, "aces"}).ok());
  auto linear = read_image(exr);
  ASSERT_TRUE(linear.ok());
  EXPECT_EQ(linear->pixels, img.pixels);
}

TEST_F(ImageTest, PngIsSrgbEncodedAndClamped) {
  Image img = gradient();
  auto path = (dir / "a.png").string();
  ASSERT_TRUE(write_image(img, path).ok());
  auto back = read_image(path);
  ASSERT_TRUE(back.ok());
  for (size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_NEAR(back->pixels[i].x, img.pixels[i].x, 0.01f);
    EXPECT_NEAR(back->pixels[i].z, 1.0f, 1e-6f);  // 2.0 clamps to white
  }
}

// A farm's image (EXR or PNG) is written without loading OpenImageIO, whose ~250 libraries cost 0.4-0.6 CPU-s
// to load; a TIFF still goes through it, and all three read back the same pixels. The writes happen in a fresh run
// of this test binary (this test alone), so that what this process loaded earlier does not count.
TEST_F(ImageTest, ExrAndPngAreWrittenWithoutOpenImageIOAndTiffWithIt) {
  auto loaded_oiio = [] {
    std::ifstream maps("/proc/self/maps");
    std::string line;
    while (std::getline(maps, line))
      if (line.find("libOpenImageIO") != std::string::npos) return true;
    return false;
  };
  if (const char* fresh = std::getenv("LIGHTFARM_IMAGE_TEST_DIR")) {
    const fs::path into(fresh);
    ASSERT_FALSE(loaded_oiio());
    preload_image_writer((into / "w.exr").string());
    ASSERT_TRUE(write_image(gradient(), (into / "w.exr").string()).ok());
    ASSERT_TRUE(write_image(gradient(), (into / "w.png").string()).ok());
    EXPECT_FALSE(loaded_oiio()) << "OpenImageIO was loaded to write EXR or PNG";
    ASSERT_TRUE(write_image(gradient(), (into / "w.tif").string()).ok());
    EXPECT_TRUE(loaded_oiio()) << "the TIFF did not go through OpenImageIO";
    return;
  }
  const std::string command = "LIGHTFARM_IMAGE_TEST_DIR=" + dir.string() +
                              " /proc/" + std::to_string(::getpid()) + "/exe --gtest_filter=" +
                              "ImageTest.ExrAndPngAreWrittenWithoutOpenImageIOAndTiffWithIt > " +
                              (dir / "fresh.log").string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream log(dir / "fresh.log");
  const std::string text((std::istreambuf_iterator<char>(log)), {});
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << text;
  const Image img = gradient();
  auto from_exr = read_image((dir / "w.exr").string()), from_png = read_image((dir / "w.png").string()),
       from_tif = read_image((dir / "w.tif").string());
  ASSERT_TRUE(from_exr.ok() && from_png.ok() && from_tif.ok());
  EXPECT_EQ(from_exr->pixels, img.pixels);
  EXPECT_EQ(from_png->pixels, from_tif->pixels);  // the same 8-bit sRGB values, whichever library wrote them
}

TEST_F(ImageTest, BadPathsAreRefusedUpFrontAndWriteNothing) {
  EXPECT_EQ(check_output_path((dir / "a.bmp").string()).error().message,
            "output '" + (dir / "a.bmp").string() + "': unsupported image format '.bmp' (use .exr, .png or .tif)");
  auto missing = (dir / "no" / "such" / "a.png").string();
  EXPECT_NE(write_image(gradient(), missing).error().message.find("does not exist"), std::string::npos);
  // /proc refuses new files even to root.
  auto r = write_image(gradient(), "/proc/lightfarm-test.png");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("is not writable"), std::string::npos) << r.error().message;
  EXPECT_EQ(files_in_dir(), 0u);
}

}  // namespace lf
