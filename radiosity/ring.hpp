#pragma once
// A ring node's algorithm (Stürzlinger et al. §3-§6), with no transport: the actor (actors/kinds/ring_node_actor.cpp)
// moves its packets between processes, and tests move them in-process.
//
// N = rings x length nodes. Node (r, p) computes radiosity for its share of the patches (a Part) and holds, for
// visibility, the surfaces of the global BSP leaves of position p; every ring holds the whole geometry once. Its
// samples travel in packets (at most S samples, at most V positions to visit) whose processor vector (`route`)
// names the positions whose space their rays cross. A packet starts at its home node, which ANDs its own
// visibility, then visits the remaining positions in ring order and comes home; home is the origin, or the node
// at the same position of another ring that borrowed it (dynamic load balancing), which then returns it.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "radiosity/bsp.hpp"
#include "radiosity/solver.hpp"

namespace lf::radiosity {

struct RingLayout {
  int rings = 1;
  int length = 1;
  int nodes() const { return rings * length; }
  int ring_of(int node) const { return node / length; }
  int position_of(int node) const { return node % length; }
  int node(int ring, int position) const { return ring * length + position; }
};

struct RingSettings {
  int samples_per_packet = 50;  // S
  int max_visits = 0;           // V: positions a packet may have to visit; 0: the ring's length
};

struct SamplePacket {
  uint32_t origin = 0;     // node whose samples these are
  uint64_t serial = 0;     // the origin's number for it
  uint32_t iteration = 0;
  uint32_t epoch = 0;      // the ring's run since its last rollback (ring_protocol.hpp): older ones are dropped
  uint64_t route = 0;      // positions still to visit
  std::vector<Vec3> points, normals;
  std::vector<uint64_t> visible;  // per sample: sub-areas not yet found blocked
};

struct NodeWork {
  uint64_t rays = 0;            // visibility rays cast here
  uint64_t visits = 0;          // packets processed here (own, forwarded, borrowed)
  uint64_t packets_made = 0;    // packets this node's samples filled
  uint64_t packets_lent = 0;    // own packets another ring ran
  uint64_t packets_borrowed = 0;
  uint64_t samples = 0;         // own samples that needed rays
};

class RingNode {
 public:
  RingNode(const Mesh& mesh, const GlobalBsp& bsp, RingLayout layout, int node, std::vector<uint32_t> patches,
           SolverSettings solver, RingSettings ring);
  ~RingNode();

  int node() const { return node_; }
  int position() const { return layout_.position_of(node_); }
  int ring() const { return layout_.ring_of(node_); }
  Candidate candidate() const { return part_.best(); }
  double unshot_power() const { return part_.unshot_power(); }

  void begin_iteration(uint32_t iteration, const Shooter& shooter);
  // Back to the end of `iteration` (-1: before the first), with `leaves` this node's elements then (ignored for
  // -1): whatever was under way is dropped. The ring's recovery from a lost node (ring_protocol.hpp).
  Status restore(int64_t iteration, std::vector<Element> leaves);
  uint32_t iteration() const { return iteration_; }
  const Shooter& shooter() const { return shooter_; }
  // Own packets not yet sent out, first come first served (also what a polling idle node may take).
  std::optional<SamplePacket> take_pending();
  size_t pending() const { return pending_.size() - pending_head_; }
  size_t out() const { return out_.size(); }
  // ANDs this position's visibility into the packet and clears this position from its route.
  void process(SamplePacket& packet);
  // The next position after `from` still on the route, in ring order; -1: none, the packet goes home.
  int next_position(const SamplePacket& packet, int from) const;
  // An own packet is home for good (from this ring or back from a borrower). false: not one we wait for.
  bool complete(const SamplePacket& packet);
  // Nothing pending, nothing out, no further round: this iteration's work is done here.
  bool finished() const { return pending_head_ >= pending_.size() && out_.empty() && !part_.round_ready(); }

  const Part& part() const { return part_; }
  const NodeWork& work() const { return work_; }
  NodeWork& work() { return work_; }
  size_t surfaces_held() const { return bsp_.surfaces_of(position()).size(); }
  // Those and this shot's home leaves' surfaces: what its visibility structures hold now.
  size_t surfaces_in_memory() const;

 private:
  void make_packets();

  const Mesh& mesh_;
  const GlobalBsp& bsp_;
  RingLayout layout_;
  int node_;
  SolverSettings solver_;
  RingSettings ring_;
  Part part_;
  SceneVisibility local_;
  Shooter shooter_;
  ShotPlan shot_;                            // this shot's home leaves (GlobalBsp::plan_shot)
  std::unique_ptr<SceneVisibility> at_home_;  // their surfaces; null: none
  uint32_t iteration_ = 0;
  uint64_t next_serial_ = 0;
  std::vector<SamplePacket> pending_;  // front first
  size_t pending_head_ = 0;
  std::map<uint64_t, std::vector<uint32_t>> out_;  // serial -> sample indices of the round
  std::vector<uint64_t> round_visible_;
  NodeWork work_;
};

}  // namespace lf::radiosity
