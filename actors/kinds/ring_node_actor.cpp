// radiosity_node: one node of a radiosity ring (Stürzlinger, Schaufler & Volkert) as an actor. The protocol itself —
// states, packets, lending and borrowing — is radiosity::RingNodeProtocol (radiosity/ring_protocol.hpp); this file only
// carries its messages (bodies in actors/codecs/ring_codec.hpp).
//
// Accepts on the data socket (from other nodes), each answered at once with REPLY {}:
//   REQUEST ring.visit / ring.back / ring.return   a sample packet; ERROR bad_request for a malformed one or one
//                                                  more than one shooter ahead
//   REQUEST ring.poll {iteration, idle}            -> REPLY {packets: [...]} or {finished, idle}
//   anything else                                  -> ERROR unknown_op; before CONFIG: ERROR not_ready
// Sends to the director: ring.shooter (each iteration's report) and ring.result (its elements, when done).
// Ready: configure once the ring is planned; setup once the director took its elements; render at once.
// From the director: PEER_MOVED (another node was restarted; the runtime reconnects) and ROLLBACK (back to a
// checkpoint in a new epoch), which may come in any state, also after READY setup.
// Its inputs are every other node, in node order.
#include "actors/kinds/ring_node_actor.hpp"

#include <time.h>

#include <chrono>

#include "actors/codecs/ring_codec.hpp"
#include "core/log.hpp"
#include "radiosity/config.hpp"
#include "radiosity/ring_protocol.hpp"

namespace lf {
namespace {

using namespace radiosity;
using Clock = std::chrono::steady_clock;

std::optional<Hop> hop_of(wire::Op op) {
  switch (op) {
    case wire::Op::ring_visit: return Hop::visit;
    case wire::Op::ring_back: return Hop::back;
    case wire::Op::ring_return: return Hop::ret;
    default: return std::nullopt;
  }
}

wire::Op op_of(Hop hop) {
  switch (hop) {
    case Hop::visit: return wire::Op::ring_visit;
    case Hop::back: return wire::Op::ring_back;
    case Hop::ret: return wire::Op::ring_return;
  }
  return wire::Op::ring_visit;
}

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
    protocol_ = std::make_unique<RingNodeProtocol>(*node_, plan_->mesh, config_);
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override {
    if (phase == wire::Phase::setup && solving_started_) return rt.phase_done(wire::Phase::setup);  // a job's next frame
    if (phase == wire::Phase::setup) {
      solving_started_ = true;
      solve_cpu_start_ = cpu_seconds();
      carry_out(protocol_->start(), rt);
    }
    if (phase == wire::Phase::render) rt.phase_done(wire::Phase::render);  // the solution was handed over in setup
  }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (!protocol_)
      return rt.reply_error(peer, m.header.id, ErrorCode::not_ready, "'" + rt.name() + "' is not configured yet");
    if (op == wire::Op::ring_poll) {
      auto poll = ring::decode_poll(m.body);
      if (!poll) return rt.reply_error(peer, m.header.id, ErrorCode::bad_request, poll.error().message);
      return rt.reply(peer, m.header.id, ring::encode_poll_reply(protocol_->on_poll(*poll)));
    }
    const auto hop = hop_of(op);
    if (!hop) return rt.reply_unknown_op(peer, m, "a ring node serves ring.visit, ring.back, ring.return and ring.poll");
    auto decoded = ring::decode_packet(m.body, config_.layout.nodes());
    if (!decoded) return rt.reply_error(peer, m.header.id, ErrorCode::bad_request, decoded.error().message);
    if (auto st = protocol_->on_packet(*hop, std::move(decoded->packet), decoded->home); !st)
      return rt.reply_error(peer, m.header.id, ErrorCode::bad_request, st.error().message);
    rt.reply(peer, m.header.id, Value::Map{});
  }

  // Whatever was outstanding with the old process is redone after the ROLLBACK that follows.
  void on_peer_moved(const std::string& name, Runtime&) override { log_debug("ring node '" + name + "' was restarted"); }

  void on_rollback(const Value& body, Runtime& rt) override {
    if (!protocol_) return rt.fail("ring: a rollback before CONFIG");
    auto rollback = ring::decode_rollback(body, plan_->mesh.patches.size());
    if (!rollback) return rt.fail("ring: " + rollback.error().message);
    auto actions = protocol_->on_rollback(std::move(*rollback));
    if (!actions) return rt.fail("ring: " + actions.error().message);
    carry_out(std::move(*actions), rt);
    on_progress(rt);
  }

  void on_progress(Runtime& rt) override {
    if (protocol_) carry_out(protocol_->step(Clock::now()), rt);  // the runtime counts this as busy time
  }

  bool has_local_work() const override { return protocol_ && protocol_->has_work(); }
  long next_due_ms() const override { return protocol_ ? protocol_->next_due_ms() : -1; }

  Value extra_stats() const override {
    if (!node_) return Value();
    const NodeWork& w = node_->work();
    return Value::Map{{"rays", static_cast<int64_t>(w.rays)},
                      {"visits", static_cast<int64_t>(w.visits)},
                      {"packets_made", static_cast<int64_t>(w.packets_made)},
                      {"packets_lent", static_cast<int64_t>(w.packets_lent)},
                      {"packets_borrowed", static_cast<int64_t>(w.packets_borrowed)},
                      {"samples", static_cast<int64_t>(w.samples)},
                      {"polls", static_cast<int64_t>(protocol_->polls())},
                      {"solve_cpu_seconds", solve_cpu_},
                      {"surfaces_held", static_cast<int64_t>(node_->surfaces_held())},
                      {"patches", static_cast<int64_t>(node_->part().patches().size())},
                      {"elements", static_cast<int64_t>(node_->part().leaf_count())},
                      {"ring", node_->ring()},
                      {"position", node_->position()}};
  }

 private:
  wire::RequestClient& client(Runtime& rt, int node) {
    const int self = node_->node();
    return rt.input(static_cast<size_t>(node < self ? node : node - 1));
  }

  void carry_out(std::vector<RingAction> actions, Runtime& rt) {
    for (auto& a : actions) {
      switch (a.kind) {
        case RingAction::Kind::send:
          client(rt, a.to).request(op_of(a.hop), ring::encode_packet(a.packet, a.home), [&rt](Result<wire::Message> r) {
            if (!r) rt.fail("ring: " + r.error().message);
          });
          break;
        case RingAction::Kind::ask_shooter:
          rt.ask_director(wire::Op::ring_shooter, ring::encode_shooter_report(a.report),
                          [this, &rt](Result<wire::Message> r) { on_shooter(std::move(r), rt); });
          break;
        case RingAction::Kind::send_result:
          solve_cpu_ = cpu_seconds() - solve_cpu_start_;
          rt.ask_director(wire::Op::ring_result, ring::encode_result(node_->part().elements(), protocol_->epoch()),
                          [this, &rt](Result<wire::Message> r) {
                            if (!r) return rt.fail("ring: " + r.error().message);
                            protocol_->on_result_taken();
                            rt.phase_done(wire::Phase::setup);
                          });
          break;
        case RingAction::Kind::poll:
          client(rt, a.to).request(wire::Op::ring_poll, ring::encode_poll(a.poll),
                                   [this, &rt, ring = a.poll_ring, poll = a.poll](Result<wire::Message> r) {
                                     if (!r) return rt.fail("ring: " + r.error().message);
                                     auto reply = ring::decode_poll_reply(r->body, config_.layout.nodes(),
                                                                          config_.layout.rings);
                                     if (!reply) return rt.fail("ring: " + reply.error().message);
                                     protocol_->on_poll_reply(ring, poll, std::move(*reply), Clock::now());
                                   });
          break;
      }
    }
  }

  void on_shooter(Result<wire::Message> r, Runtime& rt) {
    if (!r) return rt.fail("ring: " + r.error().message);
    auto choice = ring::decode_shooter_choice(r->body, plan_->mesh.patches.size());
    if (!choice) return rt.fail("ring: " + choice.error().message);
    auto actions = protocol_->on_shooter(*choice);
    if (!actions) return rt.fail("ring: " + actions.error().message);
    carry_out(std::move(*actions), rt);
    on_progress(rt);
  }

  // CPU time of this process: the work it did, whatever share of a core the OS gave it.
  static double cpu_seconds() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
  }

  double solve_cpu_start_ = 0, solve_cpu_ = 0;
  bool solving_started_ = false;  // PHASE setup again (a job's next frame): the solution is in, nothing to redo
  RingConfig config_;
  std::unique_ptr<RingPlan> plan_;
  std::unique_ptr<RingNode> node_;
  std::unique_ptr<RingNodeProtocol> protocol_;
};

}  // namespace

std::unique_ptr<Actor> make_ring_node_actor() { return std::make_unique<RingNodeActor>(); }

}  // namespace lf
