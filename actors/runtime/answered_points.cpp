#include "actors/runtime/answered_points.hpp"

namespace lf {

AnsweredPoints answered_points(const ShadingPoints& points, const std::vector<Material>& materials, const AnswerEnds& ends) {
  AnsweredPoints out;
  // Whether the answer reaches each material, decided once per material a request holds: -1 not yet.
  std::vector<int8_t> reached(materials.size(), -1);
  auto reaches = [&](uint32_t m) {
    if (m >= materials.size()) return true;  // the receiver refuses it, as it would have
    if (reached[m] < 0) reached[m] = ends.reaches(materials[m]) ? 1 : 0;
    return reached[m] == 1;
  };
  size_t first_left_out = 0;
  while (first_left_out < points.size() && reaches(points.material[first_left_out])) ++first_left_out;
  if (first_left_out == points.size()) return out;
  out.all = false;
  out.points.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    if (i >= first_left_out && !reaches(points.material[i])) continue;
    out.index.push_back(static_cast<uint32_t>(i));
    if (points.triangle.empty())
      out.points.push_back(points.position[i], points.normal[i], points.wo[i], points.material[i], points.key[i]);
    else
      out.points.push_back(points.position[i], points.normal[i], points.wo[i], points.material[i], points.key[i],
                           points.triangle[i]);
  }
  return out;
}

}  // namespace lf
