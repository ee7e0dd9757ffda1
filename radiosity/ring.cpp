#include "radiosity/ring.hpp"

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
    ++work_.samples;
    uint64_t route = 0;
    for (int m = 0; m < 64; ++m)
      if (mask >> m & 1) {
        const Segment s = visibility_segment(part_.sample_point(i), part_.sample_normal(i), shooter_, m, mesh_.epsilon);
        route |= bsp_.route(s.from, s.to);
      }
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
  std::vector<Segment> segments;
  std::vector<std::pair<uint32_t, uint32_t>> which;
  for (size_t i = 0; i < packet.points.size(); ++i) {
    const uint64_t mask = packet.visible[i];
    for (int m = 0; m < 64; ++m) {
      if (!(mask >> m & 1)) continue;
      const Segment s = visibility_segment(packet.points[i], packet.normals[i], shooter_, m, mesh_.epsilon);
      if (!(bsp_.route(s.from, s.to) & bit)) continue;  // does not cross this position's space
      segments.push_back(s);
      which.emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(m));
    }
  }
  work_.rays += segments.size();
  if (segments.empty()) return;
  std::vector<uint8_t> occluded(segments.size(), 0);
  local_(segments, occluded);
  for (size_t k = 0; k < segments.size(); ++k)
    if (occluded[k]) packet.visible[which[k].first] &= ~(uint64_t{1} << which[k].second);
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
