#pragma once
// Deterministic sampling (DESIGN §4). Every random number is a function of (pixel, sample index, stream, draw
// number) and nothing else, so an image does not depend on which process computed which tile or in which order.
#include <cstdint>

namespace lf {

constexpr uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// The key a shading point carries: which pixel sample it belongs to.
constexpr uint64_t sample_key(uint64_t pixel_index, uint64_t sample_index) {
  return splitmix64(pixel_index * 0x100000001b3ull ^ splitmix64(sample_index + 0x51ed27ull));
}

// A counter-based generator: PCG32 seeded from the key and a stream id. Consumers choose distinct streams
// (the camera, each LightOp kind) so their numbers are independent.
class Rng {
 public:
  constexpr Rng(uint64_t key, uint64_t stream)
      : state_(splitmix64(key ^ splitmix64(stream))), inc_((splitmix64(stream + 1) << 1) | 1u) {
    next();
  }
  constexpr uint32_t next() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
  }
  // Uniform in [0, 1).
  constexpr float uniform() { return static_cast<float>(next() >> 8) * 0x1p-24f; }

 private:
  uint64_t state_;
  uint64_t inc_;
};

// Streams in use; a new consumer takes a new number.
namespace streams {
inline constexpr uint64_t camera = 1;
inline constexpr uint64_t direct = 2;
inline constexpr uint64_t pathtrace = 3;
inline constexpr uint64_t specular = 4;
inline constexpr uint64_t photons = 5;
inline constexpr uint64_t irradiance = 6;
inline constexpr uint64_t light_check = 7;  // render/light_checks.cpp
}  // namespace streams

}  // namespace lf
