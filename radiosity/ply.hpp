#pragma once
// The converged solution as a mesh: element corners shared within a surface, each vertex the area-weighted mean
// of the elements around it (the usual way to display radiosity smoothly), and a PLY writer for it.
#include <string>
#include <vector>

#include "core/result.hpp"
#include "radiosity/mesh.hpp"
#include "radiosity/solver.hpp"
#include "render/caches/radiosity_field.hpp"

namespace lf::radiosity {

// Cohen et al.'s ambient term for showing a solution that has not converged: the unshot power spread evenly and
// reflected as often as the average reflectance says, B + rho * ambient, ambient = mean unshot / (1 - mean rho).
// It only changes what is shown; none of it is shot. Returns the ambient radiosity added.
RGB add_ambient(const Mesh& mesh, std::vector<Element>& elements);
// `elements`: every leaf element of the solution (any order).
RadiosityField vertex_field(const Mesh& mesh, const std::vector<Element>& elements);
// Binary little-endian PLY: float x y z, float radiosity_r/g/b (B, emission included), and uchar red/green/blue
// for viewers (B/pi clamped to [0,1], sRGB-encoded). Written to a temporary name and renamed: never half a file.
Status write_ply(const RadiosityField& field, const std::string& path);

}  // namespace lf::radiosity
