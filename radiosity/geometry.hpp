#pragma once
// Planar convex polygons (triangles and quads) as radiosity meshes them, and the point-to-polygon form factor.
#include <array>
#include <cstdint>
#include <vector>

#include "render/math.hpp"

namespace lf::radiosity {

struct Polygon {
  std::array<Vec3, 4> v{};
  int count = 3;  // 3 or 4; a quad is planar and convex, corners in order
  Vec3 normal() const;  // unit, from the winding: the side that receives and emits
  float area() const;
  Vec3 centroid() const;  // of the corners (the area centroid for triangles and parallelograms)
  float max_edge() const;
};

// Four children that tile the polygon: corner-to-midpoint for triangles, the bilinear split for quads.
std::array<Polygon, 4> split4(const Polygon& p);
// A k x k tiling (k*k children): a bilinear grid for quads, the barycentric grid for triangles.
std::vector<Polygon> tile(const Polygon& p, int k);
// A quad as a ku x kv bilinear grid (ku along v0->v1, kv along v0->v3).
std::vector<Polygon> tile_quad(const Polygon& p, int ku, int kv);
// Points at which an element's received light is sampled: the 2x2 Gauss-Legendre points of a quad (its corners
// pulled 1/sqrt(3) of the way from the centroid), the 3-point rule of a triangle (halfway).
std::vector<Vec3> sample_points(const Polygon& p);

// The form factor from a differential area at x with unit normal n to polygon q (Lambert's contour integral),
// with q clipped to the half-space above x's tangent plane. Zero when x is behind q.
double point_to_polygon(Vec3 x, Vec3 n, const Polygon& q);

}  // namespace lf::radiosity
