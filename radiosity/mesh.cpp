#include "radiosity/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>

namespace lf::radiosity {

size_t Mesh::element_count() const {
  size_t n = 0;
  for (const auto& p : patches) n += static_cast<size_t>(p.element_count());
  return n;
}

double Mesh::emitted_power() const {
  double sum = 0;
  for (const auto& p : patches) sum += static_cast<double>(p.polygon.area()) * average(p.emission);
  return sum;
}

double Mesh::mean_emission() const {
  double area = 0;
  for (const auto& p : patches) area += p.polygon.area();
  return area > 0 ? emitted_power() / area : 0;
}

static int tiles_for(float edge, float size) { return std::max(1, static_cast<int>(std::ceil(edge / size - 1e-3f))); }

Result<Mesh> build_mesh(const Scene& scene, const MeshSettings& settings) {
  Mesh mesh;
  if (scene.triangle_count() == 0) return make_error("the scene has no triangles");
  mesh.lo = mesh.hi = scene.vertices()[0];
  for (const auto& v : scene.vertices()) {
    mesh.lo = {std::min(mesh.lo.x, v.x), std::min(mesh.lo.y, v.y), std::min(mesh.lo.z, v.z)};
    mesh.hi = {std::max(mesh.hi.x, v.x), std::max(mesh.hi.y, v.y), std::max(mesh.hi.z, v.z)};
  }
  const float size = length(mesh.hi - mesh.lo);
  mesh.epsilon = std::max(1e-4f * size, 1e-6f);
  const float patch_size = settings.patch_size > 0 ? settings.patch_size : 0.1f * size;
  const float element_size = settings.element_size > 0 ? settings.element_size : 0.5f * patch_size;

  // Scene::add_quad stores a quad a-b-c-d as (a, b, c) then (a, c, d): find those pairs again.
  for (uint32_t t = 0; t < scene.triangle_count(); ++t) {
    const uint32_t m = scene.material_of(t);
    Polygon p{{scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2), Vec3{}}, 3};
    if (scene.area(t) <= 0) continue;
    if (t + 1 < scene.triangle_count() && scene.material_of(t + 1) == m && scene.vertex(t + 1, 0) == p.v[0] &&
        scene.vertex(t + 1, 1) == p.v[2] && dot(scene.normal(t), scene.normal(t + 1)) > 0.99999f) {
      p.v[3] = scene.vertex(t + 1, 2);
      p.count = 4;
      ++t;
    }
    mesh.surfaces.push_back({p, m});
  }
  for (uint32_t s = 0; s < mesh.surfaces.size(); ++s) {
    const Surface& surface = mesh.surfaces[s];
    const Material& material = scene.material(surface.material);
    const Polygon& q = surface.polygon;
    std::vector<Polygon> pieces;
    if (q.count == 4) {
      pieces = tile_quad(q, tiles_for(length(q.v[1] - q.v[0]), patch_size), tiles_for(length(q.v[3] - q.v[0]), patch_size));
    } else {
      pieces = tile(q, tiles_for(q.max_edge(), patch_size));
    }
    for (const auto& piece : pieces) {
      Patch p;
      p.polygon = piece;
      p.surface = s;
      // A metal_rough base is no Lambert lobe: the solution leaves it to the `glossy` op.
      p.reflectance = material.type == Material::Type::metal_rough ? RGB{} : material.kd;
      p.emission = scene.mean_emission(material) * kPi;
      p.element_tiles = tiles_for(piece.max_edge(), element_size);
      mesh.patches.push_back(p);
    }
  }
  return mesh;
}

void split_for_balance(Mesh& mesh, int nodes) {
  if (nodes <= 1) return;
  const size_t cap = std::max<size_t>(4, mesh.element_count() / (4 * static_cast<size_t>(nodes)));
  std::vector<Patch> out;
  std::vector<Patch> work(mesh.patches.rbegin(), mesh.patches.rend());
  // Depth-first in patch order, so children stay where their parent was in the list.
  while (!work.empty()) {
    Patch p = work.back();
    work.pop_back();
    if (static_cast<size_t>(p.element_count()) <= cap || p.element_tiles < 2) {
      out.push_back(p);
      continue;
    }
    auto children = split4(p.polygon);
    for (int i = 3; i >= 0; --i) {
      Patch c = p;
      c.polygon = children[static_cast<size_t>(i)];
      c.element_tiles = (p.element_tiles + 1) / 2;
      work.push_back(c);
    }
  }
  mesh.patches = std::move(out);
}

std::vector<int> assign_patches(const Mesh& mesh, int nodes, bool balanced, int rings) {
  const size_t n = mesh.patches.size();
  std::vector<int> owner(n, 0);
  if (nodes <= 1) return owner;
  if (!balanced) {
    for (size_t p = 0; p < n; ++p) owner[p] = static_cast<int>(p * static_cast<size_t>(nodes) / n);
    return owner;
  }
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return mesh.patches[a].element_count() > mesh.patches[b].element_count();
  });
  // Ties go to the lowest rank, which takes the rings in turn at each position (rank = position x rings + ring):
  // neighbouring patches of equal size then go to the same position of different rings, so that each ring's
  // patches lie where the others' do and the rings' packets need about as many rays in every shot.
  if (rings < 1 || nodes % rings != 0) rings = 1;
  const int length = nodes / rings;
  using Load = std::pair<size_t, int>;  // elements, rank: the lightest node first
  std::priority_queue<Load, std::vector<Load>, std::greater<>> loads;
  for (int i = 0; i < nodes; ++i) loads.push({0, i});
  for (size_t p : order) {
    auto [elements, rank] = loads.top();
    loads.pop();
    owner[p] = (rank % rings) * length + rank / rings;
    loads.push({elements + static_cast<size_t>(mesh.patches[p].element_count()), rank});
  }
  return owner;
}

}  // namespace lf::radiosity
