#pragma once
// A radiosity solution as a triangle mesh with values at the vertices: what the `radiosity` LightOp interpolates
// and what a farm's radiosity ring publishes to it (as bytes: the layout below, little-endian, checked on read).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "render/math.hpp"

namespace lf {

struct RadiosityField {
  std::vector<Vec3> position;
  std::vector<RGB> radiosity;  // B at the vertex, emission included
  std::vector<RGB> emission;   // E of the surface the vertex belongs to
  std::vector<std::array<uint32_t, 3>> triangles;

  // "LFRF" u32 version=1, u32 vertex count, u32 triangle count, then f32 position[3v], radiosity[3v],
  // emission[3v], u32 triangles[3t].
  std::string to_bytes() const;
  static Result<RadiosityField> from_bytes(const std::string& bytes);
};

}  // namespace lf
