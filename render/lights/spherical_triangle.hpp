#pragma once
// Uniform sampling of the solid angle a triangle subtends at a point (Arvo, "Stratified Sampling of Spherical
// Triangles", SIGGRAPH 1995). A light sample drawn this way has density 1 / solid angle in directions, so a point
// close to a small light (a torch next to a wall) no longer gets the 1 / d^2 weight that a uniform point on the
// light's area gives it. Computed in double: the sphere's angles lose float precision on small triangles.
#include <optional>

#include "render/math.hpp"

namespace lf {

// The solid angle triangle (p0, p1, p2) subtends at x, as the sampler below measures it (the spherical excess
// alpha + beta + gamma - pi): 0 when x lies in the triangle's plane or on a corner.
double spherical_triangle_solid_angle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2);

// Below this solid angle a light sample takes a uniform point on the triangle's area instead: the spherical excess
// loses its precision to cancellation there, and a light that small looks like a point, whose area samples are
// already as good.
inline constexpr double kMinSampledSolidAngle = 1e-4;

// The direction from x towards the triangle for the uniform numbers (u, v), uniform over its solid angle `omega`
// (spherical_triangle_solid_angle's). Nullopt when omega < kMinSampledSolidAngle.
std::optional<Vec3> sample_spherical_triangle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2, float u, float v, double& omega);

}  // namespace lf
