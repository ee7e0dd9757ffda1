#pragma once
// The radiosity mesh: a scene's triangles merged back into the quads they were built from (surfaces), surfaces
// cut into patches (the shooters), patches into elements (the receivers). Patches are what ring nodes own.
#include <cstdint>
#include <vector>

#include "core/result.hpp"
#include "radiosity/geometry.hpp"
#include "render/scene/scene.hpp"

namespace lf::radiosity {

struct Surface {
  Polygon polygon;
  uint32_t material = 0;
};

struct Patch {
  Polygon polygon;
  uint32_t surface = 0;
  RGB reflectance;   // the material's Kd (mirrors and glass count as their diffuse part: radiosity is diffuse)
  RGB emission;      // radiosity emitted, pi * Ke (Ke is radiance)
  int element_tiles = 1;  // the patch starts as element_tiles^2 elements
  int element_count() const { return element_tiles * element_tiles; }
};

struct MeshSettings {
  float patch_size = 0;    // longest patch edge; 0: a tenth of the scene's size
  float element_size = 0;  // longest element edge; 0: half the patch size
};

struct Mesh {
  std::vector<Surface> surfaces;
  std::vector<Patch> patches;
  Vec3 lo, hi;          // bounds of the scene
  float epsilon = 1e-4f;  // ray offset, small against the scene
  size_t element_count() const;
  double emitted_power() const;   // sum of area * average(emission)
  double mean_emission() const;       // emitted power / total area: the scene's radiosity scale
};

Result<Mesh> build_mesh(const Scene& scene, const MeshSettings& settings);

// Static load balancing of radiosity samples (Stürzlinger et al. §5.1): splits the patches with the most elements until
// none holds more than a quarter of a node's share, so that whole patches can be dealt out evenly.
void split_for_balance(Mesh& mesh, int nodes);
// Which node computes each patch: contiguous runs of equal patch counts (`balanced` false, the plain scheme), or
// largest-first onto the node with the fewest elements (`balanced` true).
// With `rings`, nodes are numbered ring x (nodes / rings) + position.
std::vector<int> assign_patches(const Mesh& mesh, int nodes, bool balanced, int rings = 1);

}  // namespace lf::radiosity
