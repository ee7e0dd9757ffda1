#pragma once
// A ring node's protocol (Stürzlinger et al. §4-§6) as a state machine with no sockets: the actor
// (actors/kinds/ring_node_actor.cpp) feeds it what arrives and carries out the actions it returns; tests do the
// same in-process (ring_protocol.test.cpp), and the director's ring service reads the same report and choice.
//
// States:
//   configured      before the setup phase
//   awaiting        asked the director for the first shooter
//   shooting        this iteration's own packets go round the ring, one at a time; visits are processed
//   reported        every own packet is home (lent ones included): the node reported to the director and, until
//                   the next shooter arrives, lends its packets to pollers and borrows from busy rings
//   gathering       the director said done: the node sent its elements
//   done            the director took them
// Packets of an iteration the node has not begun wait in its inbox; older ones are dropped.
//
// Recovery (Stürzlinger et al. have none; docs/decisions.md): a node's elements exist nowhere else, so when one is lost
// the director restarts it and rolls the whole ring back to its last checkpoint: every `checkpoint_every` iterations
// each node's report carries its leaf elements, and a rollback hands each node its own back (or starts them all afresh
// when there is none). The rollback opens a new epoch; packets, polls, reports and results of an older epoch are
// dropped. Iterations are deterministic (visibility does not depend on which node or ring traced it, and a round's sums
// run in element order), so the ring then repeats the lost iterations exactly and the solution equals the fault-free
// one.
#include <chrono>
#include <deque>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "radiosity/config.hpp"
#include "radiosity/ring.hpp"

namespace lf::radiosity {

// What a node tells the director when its iteration is done (-1: before the first).
struct ShooterReport {
  uint32_t epoch = 0;
  int64_t iteration = -1;
  double unshot_power = 0;
  double emitted_power = 0;
  double power_arrived = 0;
  std::optional<Candidate> candidate;
  std::optional<std::vector<Element>> checkpoint;  // this node's leaf elements, every checkpoint_every iterations
};

// The director's rollback: back to the end of `iteration` (-1: the start) with this node's checkpointed elements.
struct Rollback {
  uint32_t epoch = 0;
  int64_t iteration = -1;
  std::vector<Element> elements;
};

// The director's answer: the next shooter, or none (converged or stopped).
struct ShooterChoice {
  int64_t iteration = 0;
  uint32_t patch = 0;
  RGB unshot;
};

struct PollRequest {
  uint32_t epoch = 0;
  int64_t iteration = 0;
  std::vector<int> idle;  // rings the poller knows are idle
};

struct PollReply {
  std::vector<SamplePacket> lent;  // non-empty: work to run round the poller's ring
  bool finished = false;           // otherwise: whether the answerer's ring is idle
  std::vector<int> idle;           // and the idle rings it knows
};

// How a packet travels between nodes.
enum class Hop {
  visit,   // process it and pass it on along its route
  back,    // it is round its ring: to the node it circulates for
  ret,     // a lent packet, back to its origin
};

struct RingAction {
  enum class Kind { send, ask_shooter, send_result, poll } kind = Kind::send;
  int to = -1;            // send, poll: the node
  Hop hop = Hop::visit;   // send
  SamplePacket packet;    // send
  int home = 0;           // send: the node the packet circulates for
  ShooterReport report;   // ask_shooter
  PollRequest poll;       // poll
  int poll_ring = -1;     // poll: the ring polled
};

class RingNodeProtocol {
 public:
  enum class State { configured, awaiting, shooting, reported, gathering, done };
  static const char* state_name(State s);

  // `node` holds this node's part; `emitted_power` is the whole scene's (the director's convergence test).
  RingNodeProtocol(RingNode& node, const Mesh& mesh, const RingConfig& config);

  State state() const { return state_; }
  // Setup began: ask for the first shooter.
  std::vector<RingAction> start();
  // The director's answer to the last report. An error for a choice out of order.
  Result<std::vector<RingAction>> on_shooter(const std::optional<ShooterChoice>& choice);
  // The director took the elements.
  void on_result_taken() { state_ = State::done; }
  // The director rolled the ring back (a node was lost). From any state; a repeat of an epoch already begun changes
  // nothing. An error for elements this node does not hold.
  Result<std::vector<RingAction>> on_rollback(Rollback rollback);
  uint32_t epoch() const { return epoch_; }
  // A packet from another node. An error (to refuse it with) for one more than one shooter ahead, which no
  // conforming peer sends past the director's barrier.
  Status on_packet(Hop hop, SamplePacket packet, int home);
  // Another ring's idle node asks for work.
  PollReply on_poll(const PollRequest& poll);
  // The answer to our poll of `ring` (as it was sent: `poll` says for which epoch and iteration).
  void on_poll_reply(int ring, const PollRequest& poll, PollReply reply, std::chrono::steady_clock::time_point now);
  // Makes what progress it can: processes the inbox, sends own packets, reports, borrows, polls.
  std::vector<RingAction> step(std::chrono::steady_clock::time_point now);

  // Work that can be done now (the transport then polls without sleeping).
  bool has_work() const;
  // Milliseconds until a poll is due; -1: none.
  long next_due_ms() const { return polling_ ? 2 : -1; }
  uint64_t polls() const { return polls_; }

 private:
  struct Inbound {
    Hop hop;
    SamplePacket packet;
    int home;
  };
  bool running() const { return state_ == State::shooting || state_ == State::reported; }
  void forward(std::vector<RingAction>& out, SamplePacket p, int home);
  void came_home(std::vector<RingAction>& out, SamplePacket p);
  void send(std::vector<RingAction>& out, int to, Hop hop, SamplePacket p, int home);
  ShooterReport report(int64_t finished_iteration) const;
  void poll(std::vector<RingAction>& out, std::chrono::steady_clock::time_point now);

  static constexpr size_t kMaxLend = 4;
  RingNode& node_;
  const Mesh& mesh_;
  RingConfig config_;
  State state_ = State::configured;
  uint32_t epoch_ = 0;
  std::deque<Inbound> inbox_;
  std::deque<SamplePacket> lent_to_me_;  // borrowed, waiting for their turn round this ring
  int own_out_ = 0;                      // own packets round the ring (at most one)
  bool borrowed_ = false;                // a borrowed packet is round the ring
  bool poll_out_ = false;
  bool polling_ = false;                 // a poll is due shortly
  uint64_t polls_ = 0;
  std::chrono::steady_clock::time_point next_poll_{};
  std::set<int> idle_rings_;
  std::mt19937 rng_;
};

}  // namespace lf::radiosity
