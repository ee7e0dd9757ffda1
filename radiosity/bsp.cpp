#include "radiosity/bsp.hpp"

#include "radiosity/solver.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

namespace lf::radiosity {

bool Box::overlaps(const Box& b, float slack) const {
  for (int a = 0; a < 3; ++a)
    if (lo[a] > b.hi[a] + slack || b.lo[a] > hi[a] + slack) return false;
  return true;
}

Box bounds(const Polygon& p) {
  Box b{p.v[0], p.v[0]};
  for (int i = 1; i < p.count; ++i) {
    const Vec3 v = p.v[static_cast<size_t>(i)];
    b.lo = {std::min(b.lo.x, v.x), std::min(b.lo.y, v.y), std::min(b.lo.z, v.z)};
    b.hi = {std::max(b.hi.x, v.x), std::max(b.hi.y, v.y), std::max(b.hi.z, v.z)};
  }
  return b;
}

static Vec3 with(Vec3 v, int axis, float value) {
  if (axis == 0) v.x = value;
  if (axis == 1) v.y = value;
  if (axis == 2) v.z = value;
  return v;
}

int GlobalBsp::build_node(const Mesh& mesh, const std::vector<uint32_t>& surfaces, Box box, int depth, int max_depth) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  if (depth == max_depth) {
    nodes_[static_cast<size_t>(index)].leaf = static_cast<int>(leaves_.size());
    leaves_.push_back(surfaces);
    leaf_box_.push_back(box);
    return index;
  }
  const Vec3 extent = box.hi - box.lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  // Planes through the middle: the dealing of leaves, not their shape, balances the positions.
  const float split = 0.5f * (box.lo[axis] + box.hi[axis]);
  Box left = box, right = box;
  left.hi = with(left.hi, axis, split);
  right.lo = with(right.lo, axis, split);
  std::vector<uint32_t> in_left, in_right;
  for (uint32_t s : surfaces) {
    const Box b = bounds(mesh.surfaces[s].polygon);
    if (b.overlaps(left, slack_)) in_left.push_back(s);
    if (b.overlaps(right, slack_)) in_right.push_back(s);
  }
  const int l = build_node(mesh, in_left, left, depth + 1, max_depth);
  const int r = build_node(mesh, in_right, right, depth + 1, max_depth);
  Node& n = nodes_[static_cast<size_t>(index)];
  n.axis = axis;
  n.split = split;
  n.left = l;
  n.right = r;
  return index;
}

// The shots a tree is tried with: the brightest emitters (the first shooters) and, area-weighted with a fixed
// seed, some lit surfaces (the later ones).
static std::vector<Shooter> trial_shooters(const Mesh& mesh) {
  constexpr size_t kEmitters = 4, kReflectors = 4;
  std::vector<uint32_t> order(mesh.patches.size());
  std::iota(order.begin(), order.end(), 0u);
  auto power = [&](uint32_t p) { return mesh.patches[p].polygon.area() * average(mesh.patches[p].emission); };
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return power(a) > power(b); });
  std::vector<Shooter> out;
  for (size_t i = 0; i < order.size() && i < kEmitters && power(order[i]) > 0; ++i)
    out.push_back(make_shooter(mesh, order[i], mesh.patches[order[i]].emission, 16));
  std::vector<double> cdf;
  double total = 0;
  for (const auto& p : mesh.patches) cdf.push_back(total += p.polygon.area() * average(p.reflectance));
  std::mt19937 rng(20261205);
  for (size_t i = 0; i < kReflectors && total > 0; ++i) {
    const double x = std::uniform_real_distribution<double>(0, total)(rng);
    const auto p = static_cast<uint32_t>(std::min<size_t>(
        static_cast<size_t>(std::lower_bound(cdf.begin(), cdf.end(), x) - cdf.begin()), cdf.size() - 1));
    out.push_back(make_shooter(mesh, p, mesh.patches[p].reflectance, 16));
  }
  return out;
}

GlobalBsp GlobalBsp::build(const Mesh& mesh, int positions, bool balanced, std::span<const int> patch_nodes) {
  const int base = positions <= 1 ? 0 : static_cast<int>(std::ceil(std::log2(static_cast<double>(positions))));
  std::vector<uint32_t> all(mesh.surfaces.size());
  std::iota(all.begin(), all.end(), 0u);
  const float slack = 4 * mesh.epsilon;
  const Box root{mesh.lo - Vec3{slack, slack, slack}, mesh.hi + Vec3{slack, slack, slack}};
  std::vector<GlobalBsp> trees;
  std::vector<ShotEstimate> estimates;
  std::vector<uint32_t> probe_end;
  const auto probe =
      balanced ? probe_segments(mesh, kProbeSegments, &probe_end) : std::vector<std::pair<Vec3, Vec3>>{};
  const auto shooters = balanced && positions > 1 ? trial_shooters(mesh) : std::vector<Shooter>{};
  // A deeper tree lets leaves be dealt, and each shot's home leaves be chosen, more evenly, but a ray then crosses
  // more positions and is cast more often (and every node stores the tree, Stürzlinger et al. §5.2): try each depth
  // and keep the one whose busiest position has the least work, over a few trial shots as each would be planned.
  const int deepest = balanced ? base + 6 : base;
  // Where each patch's elements are, which each shot's probe starts from (plan_shot), the same for every shot.
  std::vector<std::vector<Vec3>> element_centres;
  if (balanced && positions > 1)
    for (const Patch& patch : mesh.patches) {
      element_centres.emplace_back();
      for (const Polygon& e : tile(patch.polygon, patch.element_tiles)) element_centres.back().push_back(e.centroid());
    }
  for (int depth = base; depth <= deepest; ++depth) {
    GlobalBsp t;
    t.positions_ = positions;
    t.depth_ = depth;
    t.balanced_ = balanced;
    t.patch_node_.assign(patch_nodes.begin(), patch_nodes.end());
    t.element_centres_ = element_centres;
    for (int node : patch_nodes) t.rings_ = std::max(t.rings_, node / positions + 1);
    t.slack_ = slack;
    t.build_node(mesh, all, root, 0, depth);
    t.owner_.assign(t.leaves_.size(), 0);
    if (balanced) {
      // Which probe segments cross each leaf. A segment stands for a ray of a shot from the surface it ends on,
      // which a leaf holding only surfaces on or behind that surface's plane cannot block (plan_shot).
      std::vector<std::vector<uint32_t>> crossing(t.leaves_.size());
      for (uint32_t k = 0; k < probe.size(); ++k)
        t.walk_blocking(mesh, probe[k].first, probe[k].second, probe_end[k],
                        [&](size_t leaf) { crossing[leaf].push_back(k); });
      std::vector<size_t> order(t.leaves_.size());
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(),
                       [&](size_t a, size_t b) { return crossing[a].size() > crossing[b].size(); });
      // Largest leaf first, to the position that ends up least loaded; a segment costs a position once however
      // many of its leaves it crosses, so neighbouring leaves tend to join the same position.
      std::vector<uint64_t> seen(probe.size(), 0);
      std::vector<size_t> load(static_cast<size_t>(positions), 0);
      for (size_t leaf : order) {
        int pick = 0;
        size_t pick_after = SIZE_MAX, pick_added = SIZE_MAX;
        for (int p = 0; p < positions; ++p) {
          size_t added = 0;
          for (uint32_t k : crossing[leaf]) added += (seen[k] >> p & 1) ? 0 : 1;
          const size_t after = load[static_cast<size_t>(p)] + added;
          if (after < pick_after || (after == pick_after && added < pick_added)) {
            pick = p;
            pick_after = after;
            pick_added = added;
          }
        }
        t.owner_[leaf] = pick;
        load[static_cast<size_t>(pick)] = pick_after;
        for (uint32_t k : crossing[leaf]) seen[k] |= uint64_t{1} << pick;
      }
    } else {
      for (size_t leaf = 0; leaf < t.leaves_.size(); ++leaf) t.owner_[leaf] = static_cast<int>(leaf % static_cast<size_t>(positions));
    }
    t.held_.assign(static_cast<size_t>(positions), {});
    for (size_t leaf = 0; leaf < t.leaves_.size(); ++leaf)
      for (uint32_t s : t.leaves_[leaf]) t.held_[static_cast<size_t>(t.owner_[leaf])].push_back(s);
    for (auto& h : t.held_) {
      std::sort(h.begin(), h.end());
      h.erase(std::unique(h.begin(), h.end()), h.end());
    }
    ShotEstimate sum;
    for (const Shooter& shooter : shooters) {
      ShotEstimate e;
      t.plan_shot(mesh, shooter.polygon, shooter.targets, &e);
      sum.busiest += e.busiest;
      sum.mean += e.mean;
    }
    if (!shooters.empty()) trees.push_back(std::move(t)), estimates.push_back(sum);
    else if (trees.empty()) trees.push_back(std::move(t));  // unbalanced: one depth
  }
  // The most even tree whose busiest position works at most a quarter more than the least busy tree's: idle nodes
  // cost a farm as much as busy ones, and the estimate of a coarse tree leaves little room to even it.
  size_t pick = 0;
  for (size_t i = 1; i < estimates.size(); ++i)
    if (estimates[i].busiest < estimates[pick].busiest) pick = i;
  const double limit = estimates.empty() ? 0 : 1.25 * estimates[pick].busiest;
  for (size_t i = 0; i < estimates.size(); ++i)
    if (estimates[i].busiest <= limit &&
        estimates[i].busiest * estimates[pick].mean < estimates[pick].busiest * estimates[i].mean)
      pick = i;
  return std::move(trees[pick]);
}

int GlobalBsp::position_of_point(Vec3 p) const {
  int n = 0;
  while (nodes_[static_cast<size_t>(n)].axis >= 0) {
    const Node& node = nodes_[static_cast<size_t>(n)];
    n = p[node.axis] <= node.split ? node.left : node.right;
  }
  return owner_[static_cast<size_t>(nodes_[static_cast<size_t>(n)].leaf)];
}

template <class Visit>
void GlobalBsp::walk(int index, Vec3 a, Vec3 d, float t0, float t1, Visit&& visit) const {
  const Node& n = nodes_[static_cast<size_t>(index)];
  if (n.axis < 0) {
    // A leaf that holds no surface can block nothing, so nobody need test the segment there.
    if (!leaves_[static_cast<size_t>(n.leaf)].empty()) visit(n.leaf);
    return;
  }
  const float o = a[n.axis], dir = d[n.axis];
  // Left holds coordinates <= split + slack, right >= split - slack; visit each side the segment reaches.
  auto side = [&](int child, bool below, float plane) {
    float lo = t0, hi = t1;
    if (dir == 0) {
      if (below ? o > plane : o < plane) return;
    } else {
      const float t = (plane - o) / dir;
      if ((dir > 0) == below)
        hi = std::min(hi, t);
      else
        lo = std::max(lo, t);
    }
    if (lo <= hi) walk(child, a, d, lo, hi, visit);
  };
  side(n.left, true, n.split + slack_);
  side(n.right, false, n.split - slack_);
}

uint64_t GlobalBsp::route(Vec3 a, Vec3 b) const {
  uint64_t bits = 0;
  walk(0, a, b - a, 0.0f, 1.0f, [&](int leaf) { bits |= uint64_t{1} << owner_[static_cast<size_t>(leaf)]; });
  return bits;
}

Crossing GlobalBsp::cross(Vec3 a, Vec3 b, const ShotPlan& shot) const {
  Crossing c;
  if (shot.inert_leaf.empty() || dot(shot.plane_normal, a) - shot.plane_offset < shot.clear) {
    c.positions = route(a, b);
    return c;
  }
  walk(0, a, b - a, 0.0f, 1.0f, [&](int leaf) {
    const size_t l = static_cast<size_t>(leaf);
    if (shot.inert_leaf[l]) return;
    if (!shot.home_leaf.empty() && shot.home_leaf[l])
      c.home = true;
    else
      c.positions |= uint64_t{1} << owner_[l];
  });
  return c;
}

// Segments end mesh.epsilon in front of the shooter's plane; a surface counts as behind it if no vertex is a quarter
// of that in front (and cross() routes statically a segment starting within three quarters of it): half an epsilon
// between the two, far more than a float's rounding at the scene's size.
static bool in_front(const Mesh& mesh, const Polygon& q, Vec3 n, float offset) {
  for (int i = 0; i < q.count; ++i)
    if (dot(n, q.v[static_cast<size_t>(i)]) - offset >= 0.25f * mesh.epsilon) return true;
  return false;
}

// Whether segment a-b crosses polygon q (a convex polygon, corners in order round its normal): the planning's own
// test, for a handful of surfaces per probe segment.
static bool segment_hits(const Polygon& q, Vec3 a, Vec3 b) {
  const Vec3 n = q.normal();
  const float da = dot(n, a - q.v[0]), db = dot(n, b - q.v[0]);
  if ((da > 0) == (db > 0) || da == db) return false;
  const Vec3 x = a + (b - a) * (da / (da - db));
  for (int i = 0; i < q.count; ++i) {
    const Vec3 from = q.v[static_cast<size_t>(i)], to = q.v[static_cast<size_t>((i + 1) % q.count)];
    if (dot(cross(to - from, x - from), n) < 0) return false;
  }
  return true;
}

bool GlobalBsp::leaf_can_block(const Mesh& mesh, size_t leaf, Vec3 n, float offset) const {
  for (uint32_t s : leaves_[leaf])
    if (in_front(mesh, mesh.surfaces[s].polygon, n, offset)) return true;
  return false;
}

template <class Visit>
void GlobalBsp::walk_blocking(const Mesh& mesh, Vec3 a, Vec3 b, uint32_t end_surface, Visit&& visit) const {
  const Polygon& end = mesh.surfaces[end_surface].polygon;
  const Vec3 n = end.normal();
  const float offset = dot(n, end.v[0]);
  walk(0, a, b - a, 0.0f, 1.0f, [&](int leaf) {
    if (leaf_can_block(mesh, static_cast<size_t>(leaf), n, offset)) visit(static_cast<size_t>(leaf));
  });
}

ShotPlan GlobalBsp::plan_shot(const Mesh& mesh, const Polygon& shooter, std::span<const Vec3> targets,
                              ShotEstimate* estimate) const {
  ShotPlan plan;
  if (targets.empty()) return plan;
  const Vec3 shooter_normal = shooter.normal();
  plan.plane_normal = shooter_normal;
  plan.plane_offset = dot(shooter_normal, shooter.v[0]);
  plan.clear = 0.75f * mesh.epsilon;
  std::vector<uint8_t> can_block(mesh.surfaces.size(), 0);
  for (size_t s = 0; s < mesh.surfaces.size(); ++s)
    can_block[s] = in_front(mesh, mesh.surfaces[s].polygon, plan.plane_normal, plan.plane_offset);
  plan.inert_leaf.assign(leaves_.size(), 1);
  for (size_t leaf = 0; leaf < leaves_.size(); ++leaf)
    for (uint32_t s : leaves_[leaf])
      if (can_block[s]) {
        plan.inert_leaf[leaf] = 0;
        break;
      }
  if (!balanced_ || positions_ < 2) return plan;
  const size_t P = static_cast<size_t>(positions_);
  // The probe: from patches facing the shooter to its sub-areas, weighted by the patch's elements (its samples).
  const size_t per_patch =
      std::clamp<size_t>(kProbeSegments / std::max<size_t>(1, mesh.patches.size()), 1, targets.size());
  std::vector<std::vector<uint32_t>> crossed_by(leaves_.size());  // per leaf: the probe segments crossing it
  std::vector<std::vector<uint32_t>> leaves_of;                    // per segment: the leaves it crosses
  std::vector<std::vector<uint32_t>> hits;                         // per segment: the surfaces that block it
  std::vector<std::vector<uint32_t>> hit_by(mesh.surfaces.size());  // per surface: the segments it blocks
  std::vector<double> weight;
  std::vector<uint32_t> home_of;  // per segment: the node whose packet carries it
  std::vector<uint32_t> tried(mesh.surfaces.size(), UINT32_MAX);
  for (size_t i = 0; i < mesh.patches.size(); ++i) {
    const Polygon& q = mesh.patches[i].polygon;
    const Vec3 n = q.normal();
    // From the patch's elements, where its samples are, in turn (not all from its centre: at 64 nodes that left a
    // node's estimate 0.1-0.15 off the rays it then cast).
    const std::vector<Vec3>* elements = i < element_centres_.size() ? &element_centres_[i] : nullptr;
    for (size_t j = 0; j < per_patch; ++j) {
      const Vec3 c = elements ? (*elements)[(i + j) % elements->size()] : q.centroid();
      const Vec3 t = targets[(i * per_patch + j) % targets.size()];
      if (dot(n, t - c) <= 0 || dot(shooter_normal, c - t) <= 0) continue;
      const Vec3 a = c + n * mesh.epsilon, b = t + shooter_normal * mesh.epsilon;
      const uint32_t k = static_cast<uint32_t>(weight.size());
      weight.push_back(static_cast<double>(mesh.patches[i].element_count()) / static_cast<double>(per_patch));
      home_of.push_back(static_cast<uint32_t>(i < patch_node_.size() ? static_cast<size_t>(patch_node_[i]) : k % P));
      leaves_of.emplace_back();
      hits.emplace_back();
      walk(0, a, b - a, 0.0f, 1.0f, [&](int leaf) {
        const size_t l = static_cast<size_t>(leaf);
        if (plan.inert_leaf[l]) return;
        crossed_by[l].push_back(k);
        leaves_of[k].push_back(static_cast<uint32_t>(l));
        // Whatever blocks the segment overlaps a leaf it crosses.
        for (uint32_t surface : leaves_[l]) {
          if (!can_block[surface] || tried[surface] == k) continue;
          tried[surface] = k;
          if (segment_hits(mesh.surfaces[surface].polygon, a, b)) hits[k].push_back(surface), hit_by[surface].push_back(k);
        }
      });
    }
  }
  // Which positions hold each surface (a position tests a segment against all it holds).
  std::vector<uint64_t> held_by(mesh.surfaces.size(), 0);
  for (size_t p = 0; p < P; ++p)
    for (uint32_t surface : held_[p]) held_by[surface] |= uint64_t{1} << p;
  // Surfaces held at home: at most as many as the fullest position holds, so no node holds more than twice that
  // (the ring exists to divide the scene).
  size_t budget = 0;
  for (const auto& h : held_) budget = std::max(budget, h.size());
  std::vector<uint32_t> home_uses(mesh.surfaces.size(), 0);  // per surface: the home leaves holding it
  size_t home_surfaces = 0;
  std::vector<uint8_t> at_home(leaves_.size(), 0);
  // Estimated work per position, as a ring does it: a packet's home tests a segment first (against its own
  // position's surfaces and, if it crosses a home leaf, the home leaves'); then each position it crosses, in ring
  // order, while nothing has blocked it. A segment blocked early costs the positions after it nothing, so where
  // the blockers are matters as much as where the segments go.
  std::vector<double> work(P * static_cast<size_t>(rings_), 0);  // per node: ring x P + position
  auto count = [&](size_t k, double sign) {
    uint64_t crossed = 0, blocked = 0;
    bool home_crossed = false, home_blocked = false;
    for (uint32_t l : leaves_of[k])
      if (at_home[l]) home_crossed = true;
      else crossed |= uint64_t{1} << owner_[l];
    for (uint32_t surface : hits[k]) {
      blocked |= held_by[surface];
      home_blocked = home_blocked || (home_crossed && home_uses[surface] > 0);
    }
    const size_t h = home_of[k] % P;
    double* ring = work.data() + (home_of[k] - h);
    const double w = sign * weight[k];
    if (crossed >> h & 1) ring[h] += w;
    if (home_crossed) ring[h] += w;
    if ((crossed & blocked) >> h & 1 || home_blocked) return;
    for (size_t step = 1; step < P; ++step) {
      const size_t q = (h + step) % P;
      if (!(crossed >> q & 1)) continue;
      ring[q] += w;
      if (blocked >> q & 1) return;
    }
  };
  for (size_t k = 0; k < weight.size(); ++k) count(k, 1);
  auto busiest = [&] { return static_cast<size_t>(std::max_element(work.begin(), work.end()) - work.begin()); };
  std::vector<uint32_t> stamp(weight.size(), UINT32_MAX);
  uint32_t moves = 0;
  std::vector<uint32_t> home_crossings(weight.size(), 0);  // per segment: the home leaves it crosses
  auto move = [&](size_t leaf, bool to_home) {
    // The segments whose count changes: those crossing the leaf, and those blocked by a surface that joins or
    // leaves the home set, among those tested at home at all.
    std::vector<uint32_t> touched;
    auto touch = [&](uint32_t k) {
      if (stamp[k] != moves) stamp[k] = moves, touched.push_back(k);
    };
    for (uint32_t k : crossed_by[leaf]) touch(k);
    for (uint32_t surface : leaves_[leaf])
      if (can_block[surface] && home_uses[surface] == (to_home ? 0u : 1u))
        for (uint32_t k : hit_by[surface])
          if (home_crossings[k] > 0) touch(k);
    ++moves;
    for (uint32_t k : touched) count(k, -1);
    at_home[leaf] = to_home;
    for (uint32_t k : crossed_by[leaf]) to_home ? ++home_crossings[k] : --home_crossings[k];
    for (uint32_t surface : leaves_[leaf]) {
      if (!can_block[surface]) continue;
      if (to_home && home_uses[surface]++ == 0) ++home_surfaces;
      if (!to_home && --home_uses[surface] == 0) --home_surfaces;
    }
    for (uint32_t k : touched) count(k, 1);
  };
  // Nodes' estimated work, busiest first: one plan beats another if it is lower at the first place they differ
  // (so relieving one of two equally busy positions counts).
  auto ranked = [&] {
    std::vector<double> r = work;
    std::sort(r.begin(), r.end(), std::greater<>());
    return r;
  };
  auto lower = [](const std::vector<double>& a, const std::vector<double>& b) {
    for (size_t i = 0; i < a.size(); ++i)
      if (std::abs(a[i] - b[i]) > 1e-9 * std::max(1.0, b[0])) return a[i] < b[i];
    return false;
  };
  plan.home_leaf.assign(leaves_.size(), 0);
  // Moves leaves home in this order and keeps the run of them that ranks lowest; false: none helped.
  auto best_run = [&](const std::vector<size_t>& leaves) {
    std::vector<double> best = ranked();
    size_t kept = 0, run = 0;
    for (; run < leaves.size(); ++run) {
      move(leaves[run], true);
      if (home_surfaces > budget) {
        ++run;
        break;
      }
      if (auto now = ranked(); lower(now, best)) best = std::move(now), kept = run + 1;
    }
    while (run > kept) move(leaves[--run], false);
    for (size_t i = 0; i < kept; ++i) plan.home_leaf[leaves[i]] = 1;
    return kept > 0;
  };
  auto busiest_first = [&](std::vector<size_t> leaves) {
    std::stable_sort(leaves.begin(), leaves.end(),
                     [&](size_t a, size_t b) { return crossed_by[a].size() > crossed_by[b].size(); });
    return leaves;
  };
  // First the leaves most segments cross, whoever owns them (the space around the shooter, which relieving one
  // position at a time cannot reach when several share it); then, while it helps, the busiest position's own.
  std::vector<size_t> all(leaves_.size());
  std::iota(all.begin(), all.end(), size_t{0});
  best_run(busiest_first(all));
  for (bool moved = true; moved;) {
    const size_t p = busiest() % P;
    std::vector<size_t> mine;
    for (size_t leaf = 0; leaf < leaves_.size(); ++leaf)
      if (!plan.home_leaf[leaf] && static_cast<size_t>(owner_[leaf]) == p && !crossed_by[leaf].empty())
        mine.push_back(leaf);
    moved = best_run(busiest_first(mine));
  }
  // Then single leaves either way while that ranks lower: the runs above never take a leaf back, and with blocking
  // in the estimate a leaf's worth depends on which others are at home. Two passes: four gained a few thousandths
  // of imbalance for 1.7x the planning.
  std::vector<size_t> crossed;
  for (size_t leaf = 0; leaf < leaves_.size(); ++leaf)
    if (!crossed_by[leaf].empty()) crossed.push_back(leaf);
  crossed = busiest_first(std::move(crossed));
  for (int pass = 0; pass < 2; ++pass) {
    bool improved = false;
    for (size_t leaf : crossed) {
      const bool to_home = !at_home[leaf];
      if (to_home) {  // over the cap whatever it would save: not worth recounting
        size_t joining = 0;
        for (uint32_t surface : leaves_[leaf]) joining += can_block[surface] && home_uses[surface] == 0;
        if (home_surfaces + joining > budget) continue;
      }
      const std::vector<double> before = ranked();
      move(leaf, to_home);
      if (lower(ranked(), before)) plan.home_leaf[leaf] = to_home, improved = true;
      else move(leaf, !to_home);
    }
    if (!improved) break;
  }
  for (size_t leaf = 0; leaf < leaves_.size(); ++leaf)
    if (plan.home_leaf[leaf])
      for (uint32_t s : leaves_[leaf])
        if (can_block[s]) plan.surfaces.push_back(s);
  if (estimate) {
    const auto r = ranked();
    estimate->busiest = r.front();
    estimate->mean = std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
    estimate->per_node = work;
  }
  std::sort(plan.surfaces.begin(), plan.surfaces.end());
  plan.surfaces.erase(std::unique(plan.surfaces.begin(), plan.surfaces.end()), plan.surfaces.end());
  return plan;
}

std::vector<size_t> GlobalBsp::probe_load(const Mesh& mesh, size_t first, size_t count) const {
  std::vector<uint32_t> ends;
  const auto probe = probe_segments(mesh, first + count, &ends);
  std::vector<size_t> load(static_cast<size_t>(positions_), 0);
  for (size_t k = first; k < probe.size(); ++k) {
    uint64_t bits = 0;
    walk_blocking(mesh, probe[k].first, probe[k].second, ends[k],
                  [&](size_t leaf) { bits |= uint64_t{1} << owner_[leaf]; });
    for (int p = 0; p < positions_; ++p) load[static_cast<size_t>(p)] += bits >> p & 1;
  }
  return load;
}

std::vector<std::pair<Vec3, Vec3>> probe_segments(const Mesh& mesh, size_t count, std::vector<uint32_t>* end_surface) {
  std::vector<double> cdf;
  double total = 0;
  for (const auto& s : mesh.surfaces) cdf.push_back(total += s.polygon.area());
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> u(0, 1);
  auto point_on = [&](size_t& surface) {
    surface = static_cast<size_t>(std::lower_bound(cdf.begin(), cdf.end(), u(rng) * total) - cdf.begin());
    surface = std::min(surface, cdf.size() - 1);
    const Polygon& p = mesh.surfaces[surface].polygon;
    const auto pieces = p.count == 4 ? std::vector<Polygon>{Polygon{{p.v[0], p.v[1], p.v[2], Vec3{}}, 3},
                                                            Polygon{{p.v[0], p.v[2], p.v[3], Vec3{}}, 3}}
                                     : std::vector<Polygon>{p};
    const Polygon& t = pieces[pieces.size() == 2 && u(rng) * p.area() > pieces[0].area() ? 1 : 0];
    double r1 = u(rng), r2 = u(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    return t.v[0] + (t.v[1] - t.v[0]) * static_cast<float>(r1) + (t.v[2] - t.v[0]) * static_cast<float>(r2);
  };
  // The lights shoot first and longest, so half the probe ends on an emitter (chosen by power).
  std::vector<double> light_cdf;
  double light_total = 0;
  for (const auto& p : mesh.patches) light_cdf.push_back(light_total += p.polygon.area() * average(p.emission));
  std::vector<std::pair<Vec3, Vec3>> out;
  for (size_t tries = 0; out.size() < count && tries < 50 * count; ++tries) {
    size_t sa = 0, sb = 0;
    const Vec3 a = point_on(sa);
    Vec3 b;
    if (light_total > 0 && tries % 2 == 0) {
      const size_t lp = std::min(static_cast<size_t>(std::lower_bound(light_cdf.begin(), light_cdf.end(), u(rng) * light_total) -
                                                     light_cdf.begin()),
                                 light_cdf.size() - 1);
      sb = mesh.patches[lp].surface;
      const Polygon& q = mesh.patches[lp].polygon;
      double t = u(rng) * 0.999;  // (drawn before s, as the probe has always drawn them)
      double s = u(rng) * 0.999;
      if (q.count == 3 && s + t > 1) s = 1 - s, t = 1 - t;  // a triangle: fold the square onto it
      b = q.v[0] + (q.v[1] - q.v[0]) * static_cast<float>(s) + (q.v[q.count - 1] - q.v[0]) * static_cast<float>(t);
    } else {
      b = point_on(sb);
    }
    if (sa == sb) continue;
    if (dot(mesh.surfaces[sa].polygon.normal(), b - a) <= 0 || dot(mesh.surfaces[sb].polygon.normal(), a - b) <= 0)
      continue;
    out.emplace_back(a, b);
    if (end_surface) end_surface->push_back(static_cast<uint32_t>(sb));
  }
  return out;
}

}  // namespace lf::radiosity
