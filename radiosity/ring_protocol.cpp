#include "radiosity/ring_protocol.hpp"

#include <algorithm>

namespace lf::radiosity {

using Clock = std::chrono::steady_clock;

const char* RingNodeProtocol::state_name(State s) {
  switch (s) {
    case State::configured: return "configured";
    case State::awaiting: return "awaiting";
    case State::shooting: return "shooting";
    case State::reported: return "reported";
    case State::gathering: return "gathering";
    case State::done: return "done";
  }
  return "?";
}

RingNodeProtocol::RingNodeProtocol(RingNode& node, const Mesh& mesh, const RingConfig& config)
    : node_(node), mesh_(mesh), config_(config) {
  rng_.seed(static_cast<unsigned>(node.node()) * 7919u + 1);
}

ShooterReport RingNodeProtocol::report(int64_t finished_iteration) const {
  ShooterReport r;
  r.epoch = epoch_;
  r.iteration = finished_iteration;
  r.unshot_power = node_.unshot_power();
  r.emitted_power = mesh_.emitted_power();
  r.power_arrived = finished_iteration >= 0 ? node_.part().shot().power_arrived : 0.0;
  if (const Candidate c = node_.candidate(); c.patch != UINT32_MAX) r.candidate = c;
  return r;
}

std::vector<RingAction> RingNodeProtocol::start() {
  if (state_ != State::configured) return {};
  state_ = State::awaiting;
  RingAction ask;
  ask.kind = RingAction::Kind::ask_shooter;
  ask.report = report(-1);
  return {std::move(ask)};
}

Result<std::vector<RingAction>> RingNodeProtocol::on_shooter(const std::optional<ShooterChoice>& choice) {
  if (state_ != State::awaiting && state_ != State::reported)
    return make_error(std::string("a shooter arrived while the node was ") + state_name(state_));
  polling_ = false;
  idle_rings_.clear();
  lent_to_me_.clear();  // cannot hold any: the lenders could not have finished
  if (!choice) {
    state_ = State::gathering;
    RingAction result;
    result.kind = RingAction::Kind::send_result;
    return std::vector<RingAction>{std::move(result)};
  }
  if (choice->patch >= mesh_.patches.size()) return make_error("the director chose a patch the mesh does not have");
  node_.begin_iteration(static_cast<uint32_t>(choice->iteration),
                        make_shooter(mesh_, choice->patch, choice->unshot, config_.solver.shooter_samples));
  state_ = State::shooting;
  return std::vector<RingAction>{};
}

Result<std::vector<RingAction>> RingNodeProtocol::on_rollback(Rollback rollback) {
  if (rollback.epoch <= epoch_) return std::vector<RingAction>{};
  if (auto st = node_.restore(rollback.iteration, std::move(rollback.elements)); !st) return st.error();
  epoch_ = rollback.epoch;
  inbox_.clear();
  lent_to_me_.clear();
  own_out_ = 0;
  borrowed_ = false;
  poll_out_ = false;  // its answer, if one comes, is of the old epoch
  polling_ = false;
  idle_rings_.clear();
  // Report the checkpoint's state again: the director's choice of the next shooter is then the one it made before.
  state_ = State::awaiting;
  RingAction ask;
  ask.kind = RingAction::Kind::ask_shooter;
  ask.report = report(rollback.iteration);
  ask.report.power_arrived = 0;  // that shot's figure is not part of a checkpoint
  return std::vector<RingAction>{std::move(ask)};
}

Status RingNodeProtocol::on_packet(Hop hop, SamplePacket packet, int home) {
  if (packet.epoch != epoch_) return Ok{};  // sent before a rollback: its work is being redone
  // Past the director's barrier a peer is at most one shooter ahead of this node; anything further would only
  // pile up here.
  if (packet.iteration > node_.iteration() + 1)
    return make_error("a packet of iteration " + std::to_string(packet.iteration) + " while this node is on " +
                      std::to_string(node_.iteration()));
  inbox_.push_back({hop, std::move(packet), home});
  return Ok{};
}

void RingNodeProtocol::send(std::vector<RingAction>& out, int to, Hop hop, SamplePacket p, int home) {
  RingAction a;
  a.kind = RingAction::Kind::send;
  a.to = to;
  a.hop = hop;
  p.epoch = epoch_;
  a.packet = std::move(p);
  a.home = home;
  out.push_back(std::move(a));
}

// Next position on the route, or home when the round is over.
void RingNodeProtocol::forward(std::vector<RingAction>& out, SamplePacket p, int home) {
  const int next = node_.next_position(p, node_.position());
  if (next >= 0) return send(out, config_.layout.node(node_.ring(), next), Hop::visit, std::move(p), home);
  if (home == node_.node()) return came_home(out, std::move(p));
  send(out, home, Hop::back, std::move(p), home);
}

void RingNodeProtocol::came_home(std::vector<RingAction>& out, SamplePacket p) {
  if (static_cast<int>(p.origin) == node_.node()) {
    if (node_.complete(p)) --own_out_;  // a duplicate or forged packet changes nothing
    return;
  }
  // Borrowed: back to the node whose samples these are.
  const int origin = static_cast<int>(p.origin);
  send(out, origin, Hop::ret, std::move(p), origin);
  borrowed_ = false;
}

std::vector<RingAction> RingNodeProtocol::step(Clock::time_point now) {
  std::vector<RingAction> out;
  // Packets of an iteration this node has not begun wait for its shooter.
  for (size_t handled = inbox_.size(); handled > 0 && !inbox_.empty(); --handled) {
    Inbound in = std::move(inbox_.front());
    inbox_.pop_front();
    if (!running() || in.packet.iteration != node_.iteration()) {
      if (running() && in.packet.iteration < node_.iteration()) continue;  // stale: cannot happen past the barrier
      inbox_.push_back(std::move(in));
      continue;
    }
    switch (in.hop) {
      case Hop::visit:
        node_.process(in.packet);
        forward(out, std::move(in.packet), in.home);
        break;
      case Hop::back: came_home(out, std::move(in.packet)); break;
      case Hop::ret: node_.complete(in.packet); break;  // our packet, run by another ring
    }
  }
  if (!running()) return out;
  // One own packet round the ring at a time (Stürzlinger et al.: never more packets in a ring than nodes).
  if (own_out_ == 0 && !borrowed_) {
    if (auto p = node_.take_pending()) {
      ++own_out_;
      node_.process(*p);  // a packet starts at its home node: this position's visibility first
      forward(out, std::move(*p), node_.node());
    }
  }
  if (node_.finished() && own_out_ == 0 && !borrowed_) {
    if (state_ == State::shooting) {
      state_ = State::reported;
      RingAction ask;
      ask.kind = RingAction::Kind::ask_shooter;
      ask.report = report(static_cast<int64_t>(node_.iteration()));
      if (config_.checkpoint_every > 0 && (node_.iteration() + 1) % static_cast<uint32_t>(config_.checkpoint_every) == 0) {
        std::vector<Element> leaves;
        for (const Element& e : node_.part().elements())
          if (e.leaf) leaves.push_back(e);
        ask.report.checkpoint = std::move(leaves);
      }
      out.push_back(std::move(ask));
    }
    if (!lent_to_me_.empty()) {
      // Borrowed packets go round this ring one at a time, like our own.
      SamplePacket p = std::move(lent_to_me_.front());
      lent_to_me_.pop_front();
      borrowed_ = true;
      node_.process(p);
      forward(out, std::move(p), node_.node());
    } else {
      poll(out, now);
    }
  }
  return out;
}

// Dynamic load balancing (Stürzlinger et al. §6.2): idle, ask a random node at this position in another ring for some
// of its packets; one that is idle too answers with the rings it knows to be idle.
void RingNodeProtocol::poll(std::vector<RingAction>& out, Clock::time_point now) {
  polling_ = false;
  if (!config_.dynamic_balance || config_.layout.rings < 2 || poll_out_) return;
  std::vector<int> candidates;
  for (int r = 0; r < config_.layout.rings; ++r)
    if (r != node_.ring() && !idle_rings_.count(r)) candidates.push_back(r);
  if (candidates.empty()) return;
  if (now < next_poll_) {
    polling_ = true;
    return;
  }
  const int ring = candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng_)];
  poll_out_ = true;
  ++polls_;
  RingAction a;
  a.kind = RingAction::Kind::poll;
  a.to = config_.layout.node(ring, node_.position());
  a.poll_ring = ring;
  a.poll = PollRequest{epoch_, static_cast<int64_t>(node_.iteration()),
                       std::vector<int>(idle_rings_.begin(), idle_rings_.end())};
  out.push_back(std::move(a));
}

void RingNodeProtocol::on_poll_reply(int ring, const PollRequest& poll, PollReply reply, Clock::time_point now) {
  if (poll.epoch != epoch_) return;  // a poll from before a rollback, which forgot it
  poll_out_ = false;
  if (!running() || static_cast<int64_t>(node_.iteration()) != poll.iteration) return;
  for (auto& p : reply.lent) {
    if (p.epoch != epoch_) continue;
    ++node_.work().packets_borrowed;
    lent_to_me_.push_back(std::move(p));
  }
  if (!lent_to_me_.empty()) return;
  idle_rings_.insert(reply.idle.begin(), reply.idle.end());
  if (reply.finished) idle_rings_.insert(ring);
  // Busy but nothing to lend right now: try again shortly.
  next_poll_ = now + std::chrono::milliseconds(2);
  polling_ = true;
}

PollReply RingNodeProtocol::on_poll(const PollRequest& poll) {
  PollReply reply;
  const bool current = running() && poll.epoch == epoch_ && static_cast<int64_t>(node_.iteration()) == poll.iteration;
  if (current && node_.pending() > 0) {
    // Half of what waits here, up to kMaxLend: one poll's round trip then buys several packets' work, which
    // matters when processes share cores and every message waits for the peer to be scheduled.
    const size_t count = std::min(kMaxLend, std::max<size_t>(1, node_.pending() / 2));
    for (size_t i = 0; i < count; ++i) {
      reply.lent.push_back(std::move(*node_.take_pending()));
      reply.lent.back().epoch = epoch_;
      ++node_.work().packets_lent;
    }
    return reply;
  }
  reply.finished = current && node_.finished() && own_out_ == 0;
  if (reply.finished) {
    reply.idle.push_back(node_.ring());
    reply.idle.insert(reply.idle.end(), idle_rings_.begin(), idle_rings_.end());
  }
  return reply;
}

bool RingNodeProtocol::has_work() const {
  if (!running()) return false;
  for (const auto& in : inbox_)
    if (in.packet.iteration == node_.iteration()) return true;
  return own_out_ == 0 && !borrowed_ && (node_.pending() > 0 || (node_.finished() && !lent_to_me_.empty()));
}

}  // namespace lf::radiosity
