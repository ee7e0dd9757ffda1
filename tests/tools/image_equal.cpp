// image_equal A B: exit 0 when two images hold the same pixels bit for bit (metadata such as capDate ignored),
// 1 when they differ (prints how many pixels and the largest difference), 2 when one cannot be read.
#include <cmath>
#include <cstdio>
#include <cstring>

#include "render/images/image.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: image_equal A B\n");
    return 2;
  }
  auto a = lf::read_image(argv[1]);
  auto b = lf::read_image(argv[2]);
  if (!a || !b) {
    std::fprintf(stderr, "image_equal: %s\n", (!a ? a.error() : b.error()).message.c_str());
    return 2;
  }
  if (a->width != b->width || a->height != b->height) {
    std::printf("sizes differ: %dx%d vs %dx%d\n", a->width, a->height, b->width, b->height);
    return 1;
  }
  size_t differ = 0;
  double largest = 0;
  for (size_t i = 0; i < a->pixels.size(); ++i) {
    if (std::memcmp(&a->pixels[i], &b->pixels[i], sizeof(lf::RGB)) == 0) continue;
    ++differ;
    for (int c = 0; c < 3; ++c) largest = std::max(largest, static_cast<double>(std::fabs(a->pixels[i][c] - b->pixels[i][c])));
  }
  if (differ == 0) return 0;
  std::printf("%zu of %zu pixels differ (largest difference %g)\n", differ, a->pixels.size(), largest);
  return 1;
}
