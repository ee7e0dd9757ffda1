#include "render/lights/emitter_cutouts.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "render/scene/scene.hpp"

namespace lf {

namespace {

struct Polygon {
  std::array<double, 8> x, y;  // a triangle cut by four half-planes has at most 7 corners
  int n = 0;
};

// The triangle (x, y) clipped to the square [i, i + 1] x [j, j + 1] (Sutherland and Hodgman): a convex polygon.
Polygon clip_to_cell(const double* x, const double* y, int64_t i, int64_t j) {
  Polygon buffers[2];
  Polygon* p = &buffers[0];
  Polygon* out = &buffers[1];
  for (int k = 0; k < 3; ++k) {
    p->x[k] = x[k];
    p->y[k] = y[k];
  }
  p->n = 3;
  // Each edge of the square as "inside when sign * (coordinate - bound) >= 0".
  const struct {
    bool along_x;
    double bound, sign;
  } edges[4] = {{true, static_cast<double>(i), 1},
                {true, static_cast<double>(i + 1), -1},
                {false, static_cast<double>(j), 1},
                {false, static_cast<double>(j + 1), -1}};
  for (const auto& e : edges) {
    auto side = [&](int k) { return e.sign * ((e.along_x ? p->x[k] : p->y[k]) - e.bound); };
    bool all_inside = true;
    for (int k = 0; k < p->n && all_inside; ++k) all_inside = side(k) >= 0;
    if (all_inside) continue;  // the polygon as it is
    out->n = 0;
    for (int k = 0; k < p->n; ++k) {
      const int next = (k + 1) % p->n;
      const double a = side(k), b = side(next);
      if (a >= 0) {
        out->x[out->n] = p->x[k];
        out->y[out->n] = p->y[k];
        ++out->n;
      }
      if ((a >= 0) != (b >= 0)) {
        const double t = a / (a - b);
        out->x[out->n] = p->x[k] + (p->x[next] - p->x[k]) * t;
        out->y[out->n] = p->y[k] + (p->y[next] - p->y[k]) * t;
        ++out->n;
      }
    }
    std::swap(p, out);
    if (p->n < 3) return Polygon{};
  }
  return *p;
}

double area_of(const Polygon& p) {
  double twice = 0;
  for (int k = 0; k < p.n; ++k) {
    const int next = (k + 1) % p.n;
    twice += p.x[k] * p.y[next] - p.x[next] * p.y[k];
  }
  return std::abs(twice) / 2;
}

// A triangle whose box in texel space holds more cells than this (a coverage map tiled many times over it) is
// sampled whole, as before.
constexpr int64_t kMostCells = 1 << 16;

}  // namespace

EmitterCutouts::EmitterCutouts(const Scene& scene) {
  const auto& emitters = scene.emitters();
  slot_.assign(emitters.size(), -1);
  if (!scene.has_uvs()) return;
  for (size_t e = 0; e < emitters.size(); ++e) {
    const uint32_t tri = emitters[e];
    const Material& m = scene.material(scene.material_of(tri));
    if (m.alpha_map < 0) continue;
    const Texture& tex = scene.textures()[static_cast<size_t>(m.alpha_map)];
    if (tex.width == 0 || tex.height == 0) continue;
    // Texel space as the bilinear lookup has it: texel centres at integers, y = 0 the top row.
    Emitter em;
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = scene.corner_uv(tri, k);
      em.x[k] = static_cast<double>(uv.u) * tex.width - 0.5;
      em.y[k] = (1.0 - static_cast<double>(uv.v)) * tex.height - 0.5;
    }
    const double a = em.x[1] - em.x[0], b = em.x[2] - em.x[0], c = em.y[1] - em.y[0], d = em.y[2] - em.y[0];
    const double det = a * d - b * c;
    const double texel_area = std::abs(det) / 2;
    if (!std::isfinite(det) || texel_area < 1e-9) continue;
    em.to_barycentric[0] = d / det;
    em.to_barycentric[1] = -b / det;
    em.to_barycentric[2] = -c / det;
    em.to_barycentric[3] = a / det;
    const double x0 = std::floor(std::min({em.x[0], em.x[1], em.x[2]})), x1 = std::floor(std::max({em.x[0], em.x[1], em.x[2]}));
    const double y0 = std::floor(std::min({em.y[0], em.y[1], em.y[2]})), y1 = std::floor(std::max({em.y[0], em.y[1], em.y[2]}));
    if (!((x1 - x0 + 1) * (y1 - y0 + 1) <= static_cast<double>(kMostCells))) continue;
    // Which texels reach coverage 1/2, over the box and one texel beyond (a cell's far corners).
    const auto ix0 = static_cast<int64_t>(x0), iy0 = static_cast<int64_t>(y0);
    const auto columns = static_cast<int64_t>(x1 - x0) + 2, rows = static_cast<int64_t>(y1 - y0) + 2;
    std::vector<uint8_t> there(static_cast<size_t>(columns * rows));
    for (int64_t r = 0; r < rows; ++r)
      for (int64_t c = 0; c < columns; ++c) there[static_cast<size_t>(r * columns + c)] = tex.texel(ix0 + c, iy0 + r, 0) >= 0.5f;
    // The same grid's points against the triangle's edges (functions positive inside, whatever its winding in texel
    // space): bit k set where the point is on the inner side of edge k. A cell reads its four corners.
    const double orient = det > 0 ? 1.0 : -1.0;
    std::vector<uint8_t> sides(there.size());
    for (int64_t r = 0; r < rows; ++r)
      for (int64_t c = 0; c < columns; ++c) {
        const double px = static_cast<double>(ix0 + c), py = static_cast<double>(iy0 + r);
        uint8_t bits = 0;
        for (int k = 0; k < 3; ++k) {
          const int n = (k + 1) % 3;
          if (orient * ((em.x[n] - em.x[k]) * (py - em.y[k]) - (em.y[n] - em.y[k]) * (px - em.x[k])) >= 0) bits |= 1u << k;
        }
        sides[static_cast<size_t>(r * columns + c)] = bits;
      }
    std::vector<std::pair<Cell, double>> kept;
    double total = 0;
    for (int64_t r = 0; r + 1 < rows; ++r)
      for (int64_t c = 0; c + 1 < columns; ++c) {
        const size_t at = static_cast<size_t>(r * columns + c), below = at + static_cast<size_t>(columns);
        if (!(there[at] || there[at + 1] || there[below] || there[below + 1])) continue;
        const int64_t i = ix0 + c, j = iy0 + r;
        // A cell wholly inside the triangle is all there to sample; one wholly outside an edge is not; the rest are
        // clipped.
        const uint8_t all = sides[at] & sides[at + 1] & sides[below] & sides[below + 1];
        const uint8_t any = sides[at] | sides[at + 1] | sides[below] | sides[below + 1];
        if (any != 7) continue;  // every corner outside one edge
        const bool inside = all == 7;
        const double cell_area = inside ? 1.0 : area_of(clip_to_cell(em.x, em.y, i, j));
        if (!(cell_area > 0)) continue;
        kept.push_back({Cell{static_cast<int32_t>(i), static_cast<int32_t>(j), 0, inside}, cell_area});
        total += cell_area;
      }
    // Nothing can be there (the emitter has no power and is never picked), or all of it may be: sample it whole.
    if (kept.empty() || total >= texel_area * (1 - 1e-9)) continue;
    em.first = static_cast<uint32_t>(cells_.size());
    em.count = static_cast<uint32_t>(kept.size());
    em.area = static_cast<float>(static_cast<double>(scene.area(tri)) * total / texel_area);
    double running = 0;
    for (auto& [cell, cell_area] : kept) {
      running += cell_area;
      cell.cdf = static_cast<float>(running / total);
      cells_.push_back(cell);
    }
    cells_.back().cdf = 1.0f;
    slot_[e] = static_cast<int32_t>(emitters_.size());
    emitters_.push_back(em);
  }
}

Vec3 EmitterCutouts::barycentrics(size_t e, Uniform2 uv) const {
  const Emitter& em = emitters_[static_cast<size_t>(slot_[e])];
  // The cell, by area, and where u fell within its share.
  const Cell* first = cells_.data() + em.first;
  const Cell* last = first + em.count;
  const Cell* cell = std::upper_bound(first, last, uv.u, [](float u, const Cell& c) { return u < c.cdf; });
  if (cell == last) --cell;
  const float below = cell == first ? 0.0f : (cell - 1)->cdf;
  double r = cell->cdf > below ? (static_cast<double>(uv.u) - below) / (static_cast<double>(cell->cdf) - below) : 0.0;
  r = std::clamp(r, 0.0, 1.0);
  // A whole cell: a uniform point in its square. Else the triangle of the cell's polygon (a fan from its first
  // corner), by area, and a uniform point in it.
  double qx = em.x[0], qy = em.y[0];
  const Polygon p = cell->whole ? Polygon{} : clip_to_cell(em.x, em.y, cell->i, cell->j);
  if (cell->whole) {
    qx = cell->i + r;
    qy = cell->j + static_cast<double>(uv.v);
  } else if (p.n >= 3) {
    double fan_total = 0;
    std::array<double, 8> fan{};
    for (int k = 1; k + 1 < p.n; ++k) {
      fan[static_cast<size_t>(k)] = std::abs((p.x[k] - p.x[0]) * (p.y[k + 1] - p.y[0]) - (p.x[k + 1] - p.x[0]) * (p.y[k] - p.y[0]));
      fan_total += fan[static_cast<size_t>(k)];
    }
    int k = 1;
    double target = r * fan_total;
    while (k + 2 < p.n && target > fan[static_cast<size_t>(k)]) target -= fan[static_cast<size_t>(k++)];
    const double s = fan[static_cast<size_t>(k)] > 0 ? std::clamp(target / fan[static_cast<size_t>(k)], 0.0, 1.0) : 0.0;
    const double su = std::sqrt(s), v = uv.v;
    const double w0 = 1 - su, w1 = su * (1 - v), w2 = su * v;
    qx = p.x[0] * w0 + p.x[k] * w1 + p.x[k + 1] * w2;
    qy = p.y[0] * w0 + p.y[k] * w1 + p.y[k + 1] * w2;
  }
  const double dx = qx - em.x[0], dy = qy - em.y[0];
  const double b1 = std::clamp(em.to_barycentric[0] * dx + em.to_barycentric[1] * dy, 0.0, 1.0);
  const double b2 = std::clamp(em.to_barycentric[2] * dx + em.to_barycentric[3] * dy, 0.0, 1.0 - b1);
  return {static_cast<float>(1 - b1 - b2), static_cast<float>(b1), static_cast<float>(b2)};
}

}  // namespace lf
