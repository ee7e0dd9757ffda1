#include "radiosity/ring.hpp"

#include <algorithm>
#include <bit>

namespace lf::radiosity {

RingNode::RingNode(const Mesh& mesh, const GlobalBsp& bsp, RingLayout layout, int node, std::vector<uint32_t> patches,
                   SolverSettings solver, RingSettings ring)
    : mesh_(mesh),
      bsp_(bsp),
      layout_(layout),
      node_(node),
      solver_(solver),
      ring_(ring),
      part_(mesh, std::move(patches), solver),
      local_(mesh, bsp.surfaces_of(layout.position_of(node))) {
  if (ring_.max_visits <= 0) ring_.max_visits = layout_.length;
}

RingNode::~RingNode() = default;

void RingNode::begin_iteration(uint32_t iteration, const Shooter& shooter) {
  iteration_ = iteration;
  shooter_ = shooter;
  pending_.clear();
  pending_head_ = 0;
  out_.clear();
  part_.begin_shot(shooter_);
  shot_ = bsp_.plan_shot(mesh_, shooter_.polygon, shooter_.targets);
  at_home_.reset();
  if (!shot_.surfaces.empty()) at_home_ = std::make_unique<SceneVisibility>(mesh_, shot_.surfaces);
  make_packets();
}

Status RingNode::restore(int64_t iteration, std::vector<Element> leaves) {
  if (iteration < 0) {
    part_.reset();
  } else if (auto st = part_.restore(std::move(leaves)); !st) {
    return st;
  }
  iteration_ = iteration < 0 ? 0 : static_cast<uint32_t>(iteration);
  shooter_ = Shooter{};
  shot_ = ShotPlan{};
  at_home_.reset();
  pending_.clear();
  pending_head_ = 0;
  out_.clear();
  round_visible_.clear();
  return Ok{};
}

void RingNode::make_packets() {
  // A round's samples that need rays, packed in order: a packet closes at S samples or when one more sample would
  // make it visit more than V positions.
  round_visible_.assign(part_.sample_count(), 0);
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<long>(pending_head_));
  pending_head_ = 0;
  SamplePacket packet;
  std::vector<uint32_t> members;
  auto close = [&] {
    if (packet.points.empty()) return;
    packet.origin = static_cast<uint32_t>(node_);
    packet.serial = next_serial_++;
    packet.iteration = iteration_;
    out_[packet.serial] = std::move(members);
    pending_.push_back(std::move(packet));
    ++work_.packets_made;
    packet = SamplePacket{};
    members.clear();
  };
  for (size_t i = 0; i < part_.sample_count(); ++i) {
    const uint64_t mask = part_.sample_mask(i);
    if (!mask) continue;
    uint64_t route = 0;
    for (int m = 0; m < 64; ++m)
      if (mask >> m & 1) {
        const Segment s = visibility_segment(part_.sample_point(i), part_.sample_normal(i), shooter_, m, mesh_.epsilon);
        const Crossing c = bsp_.cross(s.from, s.to, shot_);
        route |= c.positions | (c.home ? uint64_t{1} << position() : 0);
      }
    if (!route) {
      round_visible_[i] = mask;  // nothing anywhere can block its segments
      continue;
    }
    ++work_.samples;
    if (!packet.points.empty() && (static_cast<int>(packet.points.size()) >= ring_.samples_per_packet ||
                                   std::popcount(packet.route | route) > ring_.max_visits))
      close();
    packet.route |= route;
    packet.points.push_back(part_.sample_point(i));
    packet.normals.push_back(part_.sample_normal(i));
    packet.visible.push_back(mask);
    members.push_back(static_cast<uint32_t>(i));
  }
  close();
  if (out_.empty() && part_.round_ready()) {
    // No sample of this round needs a ray: the round is done as it stands.
    part_.finish_round(round_visible_);
    if (part_.round_ready()) make_packets();
  }
}

size_t RingNode::surfaces_in_memory() const {
  const auto& held = bsp_.surfaces_of(position());
  size_t extra = 0;
  for (uint32_t s : shot_.surfaces) extra += !std::binary_search(held.begin(), held.end(), s);
  return held.size() + extra;
}

std::optional<SamplePacket> RingNode::take_pending() {
  if (pending_head_ >= pending_.size()) return std::nullopt;
  return std::move(pending_[pending_head_++]);
}

void RingNode::process(SamplePacket& packet) {
  const int p = position();
  const uint64_t bit = uint64_t{1} << p;
  if (!(packet.route & bit)) return;
  packet.route &= ~bit;
  ++work_.visits;
  const bool home = layout_.position_of(static_cast<int>(packet.origin)) == p;
  // Segments crossing this position's leaves are tested against its surfaces; at the packet's home, those crossing
  // the shot's home leaves also against theirs.
  std::vector<Segment> segments[2];
  std::vector<std::pair<uint32_t, uint32_t>> which[2];
  for (size_t i = 0; i < packet.points.size(); ++i) {
    const uint64_t mask = packet.visible[i];
    for (int m = 0; m < 64; ++m) {
      if (!(mask >> m & 1)) continue;
      const Segment s = visibility_segment(packet.points[i], packet.normals[i], shooter_, m, mesh_.epsilon);
      const Crossing c = bsp_.cross(s.from, s.to, shot_);
      for (int set = 0; set < 2; ++set) {
        if (set == 0 ? !(c.positions & bit) : !(c.home && home && at_home_)) continue;
        segments[set].push_back(s);
        which[set].emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(m));
      }
    }
  }
  for (int set = 0; set < 2; ++set) {
    work_.rays += segments[set].size();
    if (segments[set].empty()) continue;
    std::vector<uint8_t> occluded(segments[set].size(), 0);
    (set == 0 ? local_ : *at_home_)(segments[set], occluded);
    for (size_t k = 0; k < segments[set].size(); ++k)
      if (occluded[k]) packet.visible[which[set][k].first] &= ~(uint64_t{1} << which[set][k].second);
  }
}

int RingNode::next_position(const SamplePacket& packet, int from) const {
  const int home = layout_.position_of(static_cast<int>(packet.origin));
  for (int step = 1; step < layout_.length; ++step) {
    const int q = (from + step) % layout_.length;
    if (q == home) break;  // round the ring: home
    if (packet.route >> q & 1) return q;
  }
  return -1;
}

bool RingNode::complete(const SamplePacket& packet) {
  if (packet.origin != static_cast<uint32_t>(node_) || packet.iteration != iteration_) return false;
  auto it = out_.find(packet.serial);
  if (it == out_.end() || it->second.size() != packet.visible.size()) return false;
  for (size_t k = 0; k < it->second.size(); ++k) round_visible_[it->second[k]] = packet.visible[k];
  out_.erase(it);
  if (out_.empty() && pending_head_ >= pending_.size()) {
    part_.finish_round(round_visible_);
    if (part_.round_ready()) make_packets();
  }
  return true;
}

}  // namespace lf::radiosity
