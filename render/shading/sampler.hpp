#pragma once
// Deterministic sampling. Every random number is a function of (pixel, sample index, stream, draw
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

struct Uniform2 {
  float u, v;
};

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
  // Two in a row (the interface Sampler shares, where a pair is one 2D point).
  constexpr Uniform2 uniform2() {
    const float u = uniform();
    const float v = uniform();
    return {u, v};
  }

 private:
  uint64_t state_;
  uint64_t inc_;
};

// Which numbers the camera, direct light and path tracing draw (image { sampler }): independent PCG32 numbers, or
// Owen-scrambled Sobol points (Burley 2020, "Practical Hash-based Owen Scrambling"): per pixel and per dimension a
// hash-seeded nested uniform scramble of Sobol's first two dimensions, with the sample index shuffled per dimension
// (padding), so that every dimension and every 2D pair is stratified over a pixel's samples and dimensions do not
// correlate. Both are pure functions of (pixel, sample index, stream, dimension): images stay layout-independent.
enum class SamplerKind : uint8_t { independent, sobol };

namespace sobol {

// Bit reversal by bytes: each byte reversed from a table, the bytes swapped. A point of the sequence takes three or
// four reversals, and the shift-and-mask version was the larger part of a path tracer's sampling cost.
struct ReversedBytes {
  uint8_t byte[256] = {};
  constexpr ReversedBytes() {
    for (uint32_t v = 0; v < 256; ++v) {
      uint32_t r = 0;
      for (int b = 0; b < 8; ++b) r |= ((v >> b) & 1u) << (7 - b);
      byte[v] = static_cast<uint8_t>(r);
    }
  }
};
inline constexpr ReversedBytes reversed_bytes{};

constexpr uint32_t reverse_bits(uint32_t x) {
  const auto& t = reversed_bytes.byte;
  return (uint32_t{t[x & 0xffu]} << 24) | (uint32_t{t[(x >> 8) & 0xffu]} << 16) | (uint32_t{t[(x >> 16) & 0xffu]} << 8) |
         uint32_t{t[x >> 24]};
}

// A bijection of 32-bit words in which each bit depends only on the bits below it (Laine and Karras; the constants
// of Burley's improved hash): applied to bit-reversed values it is a nested uniform (Owen) scramble.
constexpr uint32_t laine_karras(uint32_t x, uint32_t seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}

constexpr uint32_t owen_scramble(uint32_t x, uint32_t seed) { return reverse_bits(laine_karras(reverse_bits(x), seed)); }

// Sobol's first two dimensions as 32-bit fractions: van der Corput, and the one whose direction numbers follow
// v <- v ^ (v >> 1).
constexpr uint32_t dimension0(uint32_t i) { return reverse_bits(i); }
constexpr uint32_t dimension1(uint32_t i) {
  uint32_t r = 0;
  for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
    if (i & 1u) r ^= v;
  return r;
}

// The three 32-bit scrambling seeds of one dimension (the index's shuffle, then Sobol dimension 0's and dimension
// 1's), from one splitmix64 of the dimension's seed: its high and low halves, and the high half of its product with
// an odd constant (a multiplier of Steele and Vigna's tables). One hash instead of three per point: hashing was a
// third of the sampler's instructions.
struct DimensionSeeds {
  uint32_t shuffle, first, second;
};
constexpr DimensionSeeds dimension_seeds(uint64_t seed) {
  const uint64_t h = splitmix64(seed);
  return {static_cast<uint32_t>(h >> 32), static_cast<uint32_t>(h), static_cast<uint32_t>((h * 0xd1342543de82ef95ull) >> 32)};
}
constexpr float to_unit(uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }
// to_unit(reverse_bits(x)) with three byte lookups: the 24 bits a float keeps are x's low 24 reversed.
constexpr float reversed_to_unit(uint32_t x) {
  const auto& t = reversed_bytes.byte;
  return static_cast<float>((uint32_t{t[x & 0xffu]} << 16) | (uint32_t{t[(x >> 8) & 0xffu]} << 8) |
                            uint32_t{t[(x >> 16) & 0xffu]}) *
         0x1p-24f;
}

// reverse_bits(dimension1(i)), by bytes: dimension 1 is linear over GF(2) in the bits of i (each set bit XORs in its
// direction number), so four 256-entry tables give it in four lookups instead of a loop over i's bits.
struct ReversedDimension1 {
  uint32_t byte[4][256] = {};
  constexpr ReversedDimension1() {
    for (int b = 0; b < 4; ++b)
      for (uint32_t v = 0; v < 256; ++v) byte[b][v] = reverse_bits(dimension1(v << (8 * b)));
  }
  constexpr uint32_t operator()(uint32_t i) const {
    return byte[0][i & 0xffu] ^ byte[1][(i >> 8) & 0xffu] ^ byte[2][(i >> 16) & 0xffu] ^ byte[3][i >> 24];
  }
};
inline constexpr ReversedDimension1 reversed_dimension1{};

// Point `index` of the scrambled sequence for `seed` (one per pixel and dimension): a 1D value, or a 2D point.
// owen_scramble(dimension0(s)) is reverse_bits(laine_karras(s)) (reversal undoes itself), and dimension 1 comes
// reversed from its tables: the same numbers as scrambling the plain dimensions, with three reversals fewer. The
// _of_reversed forms take reverse_bits(index), which a Sampler computes once for all its dimensions.
constexpr float point1_of_reversed(uint32_t reversed_index, uint64_t seed) {
  const DimensionSeeds k = dimension_seeds(seed);
  const uint32_t shuffled = reverse_bits(laine_karras(reversed_index, k.shuffle));
  return reversed_to_unit(laine_karras(shuffled, k.first));
}
constexpr Uniform2 point2_of_reversed(uint32_t reversed_index, uint64_t seed) {
  const DimensionSeeds k = dimension_seeds(seed);
  const uint32_t shuffled = reverse_bits(laine_karras(reversed_index, k.shuffle));
  return {reversed_to_unit(laine_karras(shuffled, k.first)),
          reversed_to_unit(laine_karras(reversed_dimension1(shuffled), k.second))};
}
constexpr float point1(uint32_t index, uint64_t seed) { return point1_of_reversed(reverse_bits(index), seed); }
constexpr Uniform2 point2(uint32_t index, uint64_t seed) { return point2_of_reversed(reverse_bits(index), seed); }

}  // namespace sobol

// The key of a pixel sample under the Sobol sampler: a hash of the pixel above, the sample index in the low 24 bits
// (so a LightOp finds its place in the pixel's sequence; at most 16 M samples per pixel).
constexpr uint64_t sobol_sample_key(uint64_t pixel_index, uint64_t sample_index) {
  return (splitmix64(pixel_index * 0x100000001b3ull + 0x51ed27ull) & ~0xffffffull) | (sample_index & 0xffffffull);
}
constexpr uint64_t pixel_sample_key(SamplerKind kind, uint64_t pixel_index, uint64_t sample_index) {
  return kind == SamplerKind::sobol ? sobol_sample_key(pixel_index, sample_index) : sample_key(pixel_index, sample_index);
}

// The numbers one consumer (a stream) draws for one pixel sample, dimension by dimension. Independent: the stream's
// PCG32 numbers in order, exactly as Rng(key, stream + (sub << 32)) gives them. Sobol: `sub` of `subs` (several paths per camera
// sample take consecutive points of the pixel's sequence), each draw the next dimension; at_dimension() starts a
// fixed slot (a path's bounce), so that a skipped draw does not shift the dimensions of those after it.
class Sampler {
 public:
  constexpr Sampler(SamplerKind kind, uint64_t key, uint64_t stream, uint32_t sub = 0, uint32_t subs = 1)
      : rng_(key, stream + (static_cast<uint64_t>(sub) << 32)),
        kind_(kind),
        reversed_index_(sobol::reverse_bits(static_cast<uint32_t>(key & 0xffffffu) * subs + sub)),
        seed_(splitmix64((key >> 24) ^ splitmix64(stream ^ 0x2545f4914f6cdd1dull))) {}
  constexpr void at_dimension(uint32_t d) { dimension_ = d; }
  constexpr bool low_discrepancy() const { return kind_ == SamplerKind::sobol; }
  constexpr float uniform() {
    if (kind_ == SamplerKind::independent) return rng_.uniform();
    return sobol::point1_of_reversed(reversed_index_, seed_ + dimension_++);
  }
  constexpr Uniform2 uniform2() {
    if (kind_ == SamplerKind::independent) return rng_.uniform2();
    return sobol::point2_of_reversed(reversed_index_, seed_ + dimension_++);
  }

 private:
  Rng rng_;
  SamplerKind kind_;
  uint32_t reversed_index_;  // the sample's index in the pixel's sequence, bit-reversed
  uint64_t seed_;
  uint32_t dimension_ = 0;
};

// Streams in use; a new consumer takes a new number.
namespace streams {
inline constexpr uint64_t camera = 1;
inline constexpr uint64_t direct = 2;
inline constexpr uint64_t pathtrace = 3;
inline constexpr uint64_t specular = 4;
inline constexpr uint64_t photons = 5;
inline constexpr uint64_t irradiance = 6;
inline constexpr uint64_t light_check = 7;  // render/lights/light_checks.cpp
inline constexpr uint64_t glossy = 8;
inline constexpr uint64_t outline = 9;  // the extra seen samples of pixels on a light's outline (emitter_edges.hpp)
}  // namespace streams

}  // namespace lf
