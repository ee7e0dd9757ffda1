#include "radiosity/ply.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <tuple>

namespace lf::radiosity {

RGB add_ambient(const Mesh& mesh, std::vector<Element>& elements) {
  double area = 0;
  std::array<double, 3> unshot{0, 0, 0}, rho{0, 0, 0};
  for (const auto& e : elements) {
    if (!e.leaf) continue;
    const double a = e.polygon.area();
    const RGB r = mesh.patches[e.patch].reflectance;
    area += a;
    for (int c = 0; c < 3; ++c) {
      unshot[static_cast<size_t>(c)] += a * e.unshot[c];
      rho[static_cast<size_t>(c)] += a * r[c];
    }
  }
  if (area <= 0) return {};
  RGB ambient;
  float* out[3] = {&ambient.x, &ambient.y, &ambient.z};
  for (size_t c = 0; c < 3; ++c) *out[c] = static_cast<float>(unshot[c] / area / std::max(1e-3, 1.0 - rho[c] / area));
  for (auto& e : elements)
    if (e.leaf) e.radiosity += mesh.patches[e.patch].reflectance * ambient;
  return ambient;
}

RadiosityField vertex_field(const Mesh& mesh, const std::vector<Element>& elements) {
  RadiosityField f;
  // Corners meet exactly where elements share them (they come from the same midpoint arithmetic), so exact keys
  // per surface find the neighbours.
  std::map<std::tuple<uint32_t, float, float, float>, uint32_t> index;
  std::vector<double> weight;
  std::vector<std::array<double, 3>> sum;
  for (const auto& e : elements) {
    if (!e.leaf) continue;
    const Patch& patch = mesh.patches[e.patch];
    const double area = e.polygon.area();
    uint32_t corner[4];
    for (int i = 0; i < e.polygon.count; ++i) {
      const Vec3 v = e.polygon.v[static_cast<size_t>(i)];
      auto [it, fresh] = index.try_emplace({patch.surface, v.x, v.y, v.z}, static_cast<uint32_t>(f.position.size()));
      if (fresh) {
        f.position.push_back(v);
        f.emission.push_back(patch.emission);
        weight.push_back(0);
        sum.push_back({0, 0, 0});
      }
      corner[i] = it->second;
      weight[it->second] += area;
      sum[it->second][0] += area * e.radiosity.x;
      sum[it->second][1] += area * e.radiosity.y;
      sum[it->second][2] += area * e.radiosity.z;
    }
    f.triangles.push_back({corner[0], corner[1], corner[2]});
    if (e.polygon.count == 4) f.triangles.push_back({corner[0], corner[2], corner[3]});
  }
  f.radiosity.resize(f.position.size());
  for (size_t i = 0; i < f.position.size(); ++i)
    f.radiosity[i] = {static_cast<float>(sum[i][0] / weight[i]), static_cast<float>(sum[i][1] / weight[i]),
                      static_cast<float>(sum[i][2] / weight[i])};
  return f;
}

static unsigned char srgb8(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  const float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
  return static_cast<unsigned char>(std::lround(s * 255));
}

Status write_ply(const RadiosityField& field, const std::string& path) {
  // A name of this write alone: two farms (or two threads) writing the same PLY never share a temporary file; the
  // last rename wins whole.
  static std::atomic<uint64_t> writes{0};
  const std::string temp = path + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(writes++);
  {
    std::ofstream out(temp, std::ios::binary);
    if (!out) return make_error("cannot write '" + path + "'");
    out << "ply\nformat binary_little_endian 1.0\ncomment lightfarm radiosity solution\n"
        << "element vertex " << field.position.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "property float radiosity_r\nproperty float radiosity_g\nproperty float radiosity_b\n"
        << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        << "element face " << field.triangles.size() << "\nproperty list uchar uint vertex_indices\nend_header\n";
    for (size_t i = 0; i < field.position.size(); ++i) {
      const Vec3 p = field.position[i], b = field.radiosity[i];
      const float values[6] = {p.x, p.y, p.z, b.x, b.y, b.z};
      out.write(reinterpret_cast<const char*>(values), sizeof values);
      const unsigned char rgb[3] = {srgb8(b.x / kPi), srgb8(b.y / kPi), srgb8(b.z / kPi)};
      out.write(reinterpret_cast<const char*>(rgb), 3);
    }
    for (const auto& t : field.triangles) {
      const unsigned char three = 3;
      out.write(reinterpret_cast<const char*>(&three), 1);
      out.write(reinterpret_cast<const char*>(t.data()), 3 * sizeof(uint32_t));
    }
    out.close();
    if (!out) {
      std::remove(temp.c_str());
      return make_error("cannot write '" + path + "' (disk full?)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::remove(temp.c_str());
    return make_error("cannot write '" + path + "': " + ec.message());
  }
  return Ok{};
}

}  // namespace lf::radiosity
