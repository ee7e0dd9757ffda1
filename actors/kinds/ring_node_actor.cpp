#include "actors/kinds/ring_node_actor.hpp"

#include <time.h>

#include <chrono>
#include <deque>
#include <random>
#include <set>

#include "core/log.hpp"
#include "actors/codecs/ring_codec.hpp"
#include "radiosity/config.hpp"

namespace lf {
namespace {

using namespace radiosity;
using Clock = std::chrono::steady_clock;

class RingNodeActor final : public Actor {
 public:
  Status configure(const ActorConfig& config, Runtime& rt) override {
    ParamTable table(config.params, "radiosity");
    int node = 0;
    try {
      config_ = read_ring_config(table);
      node = static_cast<int>(table.get_int("node", 0, 0, config_.layout.nodes() - 1));
      table.report_unused();
    } catch (const ParamError& e) {
      return make_error(e.what());
    }
    auto loaded = Scene::load(config.scene);
    if (!loaded) return loaded.error();
    auto plan = plan_ring(*loaded, config_);
    if (!plan) return plan.error();
    plan_ = std::make_unique<RingPlan>(std::move(*plan));
    node_ = std::make_unique<RingNode>(plan_->mesh, plan_->bsp, config_.layout, node, plan_->patches_of(node),
                                       config_.solver, config_.ring);
    if (static_cast<int>(rt.input_count()) != config_.layout.nodes() - 1)
      return make_error("a ring node needs every other node as an input");
    rng_.seed(static_cast<unsigned>(node) * 7919u + 1);
    rt_ = &rt;
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup) {
      solve_cpu_start_ = cpu_seconds();
      ask_for_shooter(rt, -1);
    }
    if (phase == wire::Phase::render) rt.phase_done(wire::Phase::render);  // the solution was handed over in setup
  }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (!node_) return rt.reply_error(peer, m.header.id, ErrorCode::not_ready, "'" + rt.name() + "' is not configured yet");
    if (op == wire::Op::ring_poll) return on_poll(peer, m, rt);
    if (op != wire::Op::ring_visit && op != wire::Op::ring_back && op != wire::Op::ring_return)
      return rt.reply_unknown_op(peer, m, "a ring node serves ring.visit, ring.back, ring.return and ring.poll");
    auto decoded = ring::decode_packet(m.body, config_.layout.nodes());
    if (!decoded) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, decoded.error().message);
      return;
    }
    // Past the director's barrier a peer is at most one shooter ahead of this node; anything further would only
    // pile up here.
    if (decoded->packet.iteration > node_->iteration() + 1) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request,
                     "a packet of iteration " + std::to_string(decoded->packet.iteration) + " while this node is on " +
                         std::to_string(node_->iteration()));
      return;
    }
    rt.reply(peer, m.header.id, Value::Map{});
    inbox_.push_back({op, std::move(decoded->packet), decoded->home});
  }

  void on_progress(Runtime& rt) override {
    // Packets of an iteration this node has not begun wait for its shooter.
    for (size_t handled = inbox_.size(); handled > 0 && !inbox_.empty(); --handled) {
      Incoming in = std::move(inbox_.front());
      inbox_.pop_front();
      if (!running_ || in.packet.iteration != node_->iteration()) {
        if (running_ && in.packet.iteration < node_->iteration()) continue;  // stale: cannot happen past the barrier
        inbox_.push_back(std::move(in));
        continue;
      }
      const auto t = Clock::now();
      if (in.op == wire::Op::ring_visit) {
        node_->process(in.packet);
        forward(rt, std::move(in.packet), in.home);
      } else if (in.op == wire::Op::ring_back) {
        came_home(rt, std::move(in.packet));
      } else {  // ring.return: our packet, run by another ring
        node_->complete(in.packet);
      }
      rt.add_busy(t);
    }
    if (!running_) return;
    // One own packet round the ring at a time (seed 003: never more packets in a ring than nodes).
    if (own_out_ == 0 && !borrowed_) {
      if (auto p = node_->take_pending()) {
        const auto t = Clock::now();
        ++own_out_;
        start(rt, std::move(*p));
        rt.add_busy(t);
      }
    }
    if (node_->finished() && own_out_ == 0 && !borrowed_) {
      if (!asked_) ask_for_shooter(rt, static_cast<int64_t>(node_->iteration()));
      if (!lent_to_me_.empty()) {
        // Borrowed packets go round this ring one at a time, like our own.
        SamplePacket p = std::move(lent_to_me_.front());
        lent_to_me_.pop_front();
        borrowed_ = true;
        const auto t = Clock::now();
        node_->process(p);
        forward(rt, std::move(p), node_->node());
        rt.add_busy(t);
      } else {
        poll(rt);
      }
    }
  }

  bool has_local_work() const override {
    if (!running_) return false;
    for (const auto& in : inbox_)
      if (in.packet.iteration == node_->iteration()) return true;
    return own_out_ == 0 && !borrowed_ && (node_->pending() > 0 || (node_->finished() && !lent_to_me_.empty()));
  }

  long next_due_ms() const override { return polling_ ? 2 : -1; }

  Value extra_stats() const override {
    if (!node_) return Value();
    const NodeWork& w = node_->work();
    return Value::Map{{"rays", static_cast<int64_t>(w.rays)},
                      {"visits", static_cast<int64_t>(w.visits)},
                      {"packets_made", static_cast<int64_t>(w.packets_made)},
                      {"packets_lent", static_cast<int64_t>(w.packets_lent)},
                      {"packets_borrowed", static_cast<int64_t>(w.packets_borrowed)},
                      {"samples", static_cast<int64_t>(w.samples)},
                      {"polls", static_cast<int64_t>(polls_)},
                      {"solve_cpu_seconds", solve_cpu_},
                      {"surfaces_held", static_cast<int64_t>(node_->surfaces_held())},
                      {"patches", static_cast<int64_t>(node_->part().patches().size())},
                      {"elements", static_cast<int64_t>(node_->part().leaf_count())},
                      {"ring", node_->ring()},
                      {"position", node_->position()}};
  }

 private:
  struct Incoming {
    wire::Op op;
    SamplePacket packet;
    int home;
  };

  wire::RequestClient& client(int node) {
    const int self = node_->node();
    return rt_->input(static_cast<size_t>(node < self ? node : node - 1));
  }

  void send(Runtime& rt, int node, wire::Op op, const SamplePacket& p, int home) {
    client(node).request(op, ring::encode_packet(p, home), [&rt](Result<wire::Message> r) {
      if (!r) rt.fail("ring: " + r.error().message);
    });
  }

  // A packet starts at its home node (here): this position's visibility first, then round the ring.
  void start(Runtime& rt, SamplePacket p) {
    node_->process(p);
    forward(rt, std::move(p), node_->node());
  }

  void forward(Runtime& rt, SamplePacket p, int home) {
    const int next = node_->next_position(p, node_->position());
    if (next >= 0) return send(rt, config_.layout.node(node_->ring(), next), wire::Op::ring_visit, p, home);
    if (home == node_->node()) return came_home(rt, std::move(p));
    send(rt, home, wire::Op::ring_back, p, home);
  }

  void came_home(Runtime& rt, SamplePacket p) {
    if (static_cast<int>(p.origin) == node_->node()) {
      if (node_->complete(p)) --own_out_;  // a duplicate or forged packet changes nothing
      return;
    }
    // Borrowed: back to the node whose samples these are.
    send(rt, static_cast<int>(p.origin), wire::Op::ring_return, p, static_cast<int>(p.origin));
    borrowed_ = false;
  }

  void ask_for_shooter(Runtime& rt, int64_t finished_iteration) {
    asked_ = true;
    ring::ShooterReport report;
    report.iteration = finished_iteration;
    report.unshot_power = node_->unshot_power();
    report.emitted_power = plan_->mesh.emitted_power();
    report.power_arrived = finished_iteration >= 0 ? node_->part().shot().power_arrived : 0.0;
    if (const Candidate c = node_->candidate(); c.patch != UINT32_MAX) report.candidate = c;
    rt.ask_director(wire::Op::ring_shooter, ring::encode_shooter_report(report),
                    [this, &rt](Result<wire::Message> r) { on_shooter(rt, std::move(r)); });
  }

  void on_shooter(Runtime& rt, Result<wire::Message> r) {
    if (!r) return rt.fail("ring: " + r.error().message);
    polling_ = false;
    idle_rings_.clear();
    lent_to_me_.clear();  // cannot hold any: the lenders could not have finished
    auto choice = ring::decode_shooter_choice(r->body, plan_->mesh.patches.size());
    if (!choice) return rt.fail("ring: " + choice.error().message);
    if (!*choice) return send_result(rt);
    const auto t = Clock::now();
    node_->begin_iteration(static_cast<uint32_t>((*choice)->iteration),
                           make_shooter(plan_->mesh, (*choice)->patch, (*choice)->unshot, config_.solver.shooter_samples));
    rt.add_busy(t);
    running_ = true;
    asked_ = false;
    on_progress(rt);
  }

  void send_result(Runtime& rt) {
    running_ = false;
    solve_cpu_ = cpu_seconds() - solve_cpu_start_;
    rt.ask_director(wire::Op::ring_result, ring::encode_result(node_->part().elements()), [&rt](Result<wire::Message> r) {
      if (!r) return rt.fail("ring: " + r.error().message);
      rt.phase_done(wire::Phase::setup);
    });
  }

  // Dynamic load balancing (seed 003 §6.2): idle, ask a random node at this position in another ring for one of
  // its packets; one that is idle too answers with the rings it knows to be idle.
  void poll(Runtime& rt) {
    polling_ = false;
    if (!config_.dynamic_balance || config_.layout.rings < 2 || poll_out_) return;
    std::vector<int> candidates;
    for (int r = 0; r < config_.layout.rings; ++r)
      if (r != node_->ring() && !idle_rings_.count(r)) candidates.push_back(r);
    if (candidates.empty()) return;
    if (Clock::now() < next_poll_) {
      polling_ = true;
      return;
    }
    const int ring = candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng_)];
    const int target = config_.layout.node(ring, node_->position());
    poll_out_ = true;
    ++polls_;
    const uint32_t iteration = node_->iteration();
    ring::PollRequest request{static_cast<int64_t>(iteration), std::vector<int>(idle_rings_.begin(), idle_rings_.end())};
    client(target).request(wire::Op::ring_poll, ring::encode_poll(request),
                           [this, &rt, ring, iteration](Result<wire::Message> r) {
                             poll_out_ = false;
                             if (!r) return rt.fail("ring: " + r.error().message);
                             if (!running_ || node_->iteration() != iteration) return;
                             auto reply = ring::decode_poll_reply(r->body, config_.layout.nodes(), config_.layout.rings);
                             if (!reply) return rt.fail("ring: " + reply.error().message);
                             for (auto& p : reply->lent) {
                               ++node_->work().packets_borrowed;
                               lent_to_me_.push_back(std::move(p));
                             }
                             if (!lent_to_me_.empty()) return;
                             idle_rings_.insert(reply->idle.begin(), reply->idle.end());
                             if (reply->finished) idle_rings_.insert(ring);
                             // Busy but nothing to lend right now: try again shortly.
                             next_poll_ = Clock::now() + std::chrono::milliseconds(2);
                             polling_ = true;
                           });
  }

  void on_poll(const std::string& peer, wire::Message& m, Runtime& rt) {
    auto poll = ring::decode_poll(m.body);
    if (!poll) return rt.reply_error(peer, m.header.id, ErrorCode::bad_request, poll.error().message);
    const bool current = running_ && static_cast<int64_t>(node_->iteration()) == poll->iteration;
    if (current && node_->pending() > 0) {
      // Half of what waits here, up to kMaxLend: one poll's round trip then buys several packets' work, which
      // matters when processes share cores and every message waits for the peer to be scheduled.
      const size_t count = std::min(kMaxLend, std::max<size_t>(1, node_->pending() / 2));
      std::vector<Value> packets;
      for (size_t i = 0; i < count; ++i) {
        auto p = node_->take_pending();
        ++node_->work().packets_lent;
        packets.push_back(ring::encode_packet(*p, static_cast<int>(p->origin)));
      }
      rt.reply(peer, m.header.id, ring::encode_poll_reply(packets));
      return;
    }
    const bool finished = current && node_->finished() && own_out_ == 0;
    std::vector<int> idle;
    if (finished) {
      idle.push_back(node_->ring());
      idle.insert(idle.end(), idle_rings_.begin(), idle_rings_.end());
    }
    rt.reply(peer, m.header.id, ring::encode_poll_reply(finished, idle));
  }

  // CPU time of this process: the work it did, whatever share of a core the OS gave it.
  static double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
  }

  static constexpr size_t kMaxLend = 4;
  double solve_cpu_start_ = 0, solve_cpu_ = 0;
  std::deque<SamplePacket> lent_to_me_;  // borrowed, waiting for their turn round this ring
  RingConfig config_;
  std::unique_ptr<RingPlan> plan_;
  std::unique_ptr<RingNode> node_;
  Runtime* rt_ = nullptr;
  std::deque<Incoming> inbox_;
  bool running_ = false;
  bool asked_ = false;
  int own_out_ = 0;
  bool borrowed_ = false;
  bool poll_out_ = false;
  bool polling_ = false;
  uint64_t polls_ = 0;
  Clock::time_point next_poll_;
  std::set<int> idle_rings_;
  std::mt19937 rng_;
};

}  // namespace

std::unique_ptr<Actor> make_ring_node_actor() { return std::make_unique<RingNodeActor>(); }

}  // namespace lf
