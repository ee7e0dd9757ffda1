#include "actors/ring_node_actor.hpp"

#include <time.h>

#include <chrono>
#include <deque>
#include <random>
#include <set>

#include "core/log.hpp"
#include "radiosity/config.hpp"

namespace lf {
namespace {

using namespace radiosity;
using Clock = std::chrono::steady_clock;

// Packet bodies (docs/PROTOCOL.md, "radiosity ring"):
//   { o: origin node, s: serial, it: iteration, r: route bits, home: node, p: f32[3n], n: f32[3n], v: u64[n] }
Value encode_packet(const SamplePacket& p, int home) {
  std::vector<float> points, normals;
  for (size_t i = 0; i < p.points.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      points.push_back(p.points[i][c]);
      normals.push_back(p.normals[i][c]);
    }
  return Value::Map{{"o", static_cast<int64_t>(p.origin)}, {"s", static_cast<int64_t>(p.serial)},
                    {"it", static_cast<int64_t>(p.iteration)}, {"r", static_cast<int64_t>(p.route)},
                    {"home", static_cast<int64_t>(home)},     {"p", floats_to_bytes(points)},
                    {"n", floats_to_bytes(normals)},          {"v", u64_to_bytes(p.visible)}};
}

Result<std::pair<SamplePacket, int>> decode_packet(const Value& body, int nodes) {
  auto integer = [&](const char* key, int64_t lo, int64_t hi) -> std::optional<int64_t> {
    const Value* v = body.find(key);
    if (!v || !v->is_int() || v->as_int() < lo || v->as_int() > hi) return std::nullopt;
    return v->as_int();
  };
  auto origin = integer("o", 0, nodes - 1), serial = integer("s", 0, INT64_MAX), it = integer("it", 0, INT32_MAX),
       route = integer("r", INT64_MIN, INT64_MAX), home = integer("home", 0, nodes - 1);
  if (!origin || !serial || !it || !route || !home) return make_error("a sample packet needs o, s, it, r and home in range");
  const Value *p = body.find("p"), *n = body.find("n"), *v = body.find("v");
  std::vector<float> points, normals;
  SamplePacket packet;
  if (!p || !n || !v || !p->is_bytes() || !n->is_bytes() || !v->is_bytes() || !bytes_to_floats(p->as_bytes(), points) ||
      !bytes_to_floats(n->as_bytes(), normals) || !bytes_to_u64(v->as_bytes(), packet.visible) ||
      points.size() != 3 * packet.visible.size() || normals.size() != points.size())
    return make_error("a sample packet needs p, n (3 floats per sample) and v (one u64 per sample)");
  for (size_t i = 0; i < packet.visible.size(); ++i) {
    packet.points.push_back({points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    packet.normals.push_back({normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]});
  }
  packet.origin = static_cast<uint32_t>(*origin);
  packet.serial = static_cast<uint64_t>(*serial);
  packet.iteration = static_cast<uint32_t>(*it);
  packet.route = static_cast<uint64_t>(*route);
  return std::make_pair(std::move(packet), static_cast<int>(*home));
}

class RingNodeActor final : public Actor {
 public:
  Status configure(const Value& config, Runtime& rt) override {
    const Value* params = config.find("params");
    ParamTable table(params && params->is_map() ? params->as_map() : Value::Map{}, "radiosity");
    int node = 0;
    try {
      config_ = read_ring_config(table);
      node = static_cast<int>(table.get_int("node", 0, 0, config_.layout.nodes() - 1));
      table.report_unused();
    } catch (const ParamError& e) {
      return make_error(e.what());
    }
    const Value* scene = config.find("scene");
    auto loaded = Scene::load(SceneSpec::from_value(scene ? *scene : Value()));
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

  void on_phase(const std::string& phase, Runtime& rt) override {
    if (phase == "setup") {
      solve_cpu_start_ = cpu_seconds();
      ask_for_shooter(rt, -1);
    }
    if (phase == "render") rt.phase_done("render");  // the solution was handed over in setup
  }

  void on_request(const std::string& peer, wire::Message& m, Runtime& rt) override {
    const std::string& op = m.header.op;
    if (!node_) return rt.reply_error(peer, m.header.id, "not_ready", "'" + rt.name() + "' is not configured yet");
    if (op == "ring.poll") return on_poll(peer, m, rt);
    if (op != "ring.visit" && op != "ring.back" && op != "ring.return") {
      rt.reply_error(peer, m.header.id, "unknown_op", "unknown operation '" + op + "' (a ring node serves ring.visit, "
                                                      "ring.back, ring.return and ring.poll)");
      return;
    }
    auto decoded = decode_packet(m.body, config_.layout.nodes());
    if (!decoded) {
      rt.reply_error(peer, m.header.id, "bad_request", decoded.error().message);
      return;
    }
    // Past the director's barrier a peer is at most one shooter ahead of this node; anything further would only
    // pile up here.
    if (decoded->first.iteration > node_->iteration() + 1) {
      rt.reply_error(peer, m.header.id, "bad_request",
                     "a packet of iteration " + std::to_string(decoded->first.iteration) + " while this node is on " +
                         std::to_string(node_->iteration()));
      return;
    }
    rt.reply(peer, m.header.id, Value::Map{});
    inbox_.push_back({op, std::move(decoded->first), decoded->second});
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
      if (in.op == "ring.visit") {
        node_->process(in.packet);
        forward(rt, std::move(in.packet), in.home);
      } else if (in.op == "ring.back") {
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
    std::string op;
    SamplePacket packet;
    int home;
  };

  wire::RequestClient& client(int node) {
    const int self = node_->node();
    return rt_->input(static_cast<size_t>(node < self ? node : node - 1));
  }

  void send(Runtime& rt, int node, const std::string& op, const SamplePacket& p, int home) {
    client(node).request(op, encode_packet(p, home), [&rt](Result<wire::Message> r) {
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
    if (next >= 0) return send(rt, config_.layout.node(node_->ring(), next), "ring.visit", p, home);
    if (home == node_->node()) return came_home(rt, std::move(p));
    send(rt, home, "ring.back", p, home);
  }

  void came_home(Runtime& rt, SamplePacket p) {
    if (static_cast<int>(p.origin) == node_->node()) {
      if (node_->complete(p)) --own_out_;  // a duplicate or forged packet changes nothing
      return;
    }
    // Borrowed: back to the node whose samples these are.
    send(rt, static_cast<int>(p.origin), "ring.return", p, static_cast<int>(p.origin));
    borrowed_ = false;
  }

  void ask_for_shooter(Runtime& rt, int64_t finished_iteration) {
    asked_ = true;
    const Candidate c = node_->candidate();
    Value::Map body{{"iteration", finished_iteration},
                    {"unshot_power", node_->unshot_power()},
                    {"emitted_power", plan_->mesh.emitted_power()},
                    {"power_arrived", finished_iteration >= 0 ? node_->part().shot().power_arrived : 0.0}};
    if (c.patch != UINT32_MAX)
      body["candidate"] = Value::Map{{"patch", static_cast<int64_t>(c.patch)}, {"power", c.power},
                                     {"unshot", Value::Array{double(c.unshot.x), double(c.unshot.y), double(c.unshot.z)}}};
    rt.ask_director("ring.shooter", std::move(body), [this, &rt](Result<wire::Message> r) { on_shooter(rt, std::move(r)); });
  }

  void on_shooter(Runtime& rt, Result<wire::Message> r) {
    if (!r) return rt.fail("ring: " + r.error().message);
    polling_ = false;
    idle_rings_.clear();
    lent_to_me_.clear();  // cannot hold any: the lenders could not have finished
    const Value* shooter = r->body.find("shooter");
    if (!shooter) return send_result(rt);
    const Value* patch = shooter->find("patch");
    const Value* it = shooter->find("iteration");
    const Value* unshot = shooter->find("unshot");
    if (!patch || !patch->is_int() || patch->as_int() < 0 ||
        static_cast<size_t>(patch->as_int()) >= plan_->mesh.patches.size() || !it || !it->is_int() || !unshot ||
        !unshot->is_array() || unshot->as_array().size() != 3)
      return rt.fail("ring: the director sent a malformed shooter");
    const auto& u = unshot->as_array();
    const RGB rgb{static_cast<float>(u[0].as_double()), static_cast<float>(u[1].as_double()),
                  static_cast<float>(u[2].as_double())};
    const auto t = Clock::now();
    node_->begin_iteration(static_cast<uint32_t>(it->as_int()),
                           make_shooter(plan_->mesh, static_cast<uint32_t>(patch->as_int()), rgb,
                                        config_.solver.shooter_samples));
    rt.add_busy(t);
    running_ = true;
    asked_ = false;
    on_progress(rt);
  }

  void send_result(Runtime& rt) {
    running_ = false;
    solve_cpu_ = cpu_seconds() - solve_cpu_start_;
    // Leaf elements: patch, corner count, 4 corners, radiosity, unshot radiosity.
    std::vector<uint32_t> patch, corners;
    std::vector<float> points, radiosity, unshot;
    for (const auto& e : node_->part().elements()) {
      if (!e.leaf) continue;
      patch.push_back(e.patch);
      corners.push_back(static_cast<uint32_t>(e.polygon.count));
      for (const Vec3& v : e.polygon.v)
        for (int c = 0; c < 3; ++c) points.push_back(v[c]);
      for (int c = 0; c < 3; ++c) {
        radiosity.push_back(e.radiosity[c]);
        unshot.push_back(e.unshot[c]);
      }
    }
    rt.ask_director("ring.result",
                    Value::Map{{"patch", u32_to_bytes(patch)}, {"corners", u32_to_bytes(corners)},
                               {"points", floats_to_bytes(points)}, {"radiosity", floats_to_bytes(radiosity)},
                               {"unshot", floats_to_bytes(unshot)}},
                    [&rt](Result<wire::Message> r) {
                      if (!r) return rt.fail("ring: " + r.error().message);
                      rt.phase_done("setup");
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
    Value::Array known;
    for (int r : idle_rings_) known.push_back(r);
    client(target).request("ring.poll", Value::Map{{"iteration", static_cast<int64_t>(iteration)}, {"idle", known}},
                           [this, &rt, ring, iteration](Result<wire::Message> r) {
                             poll_out_ = false;
                             if (!r) return rt.fail("ring: " + r.error().message);
                             if (!running_ || node_->iteration() != iteration) return;
                             if (const Value* lent = r->body.find("packets"); lent && lent->is_array()) {
                               for (const auto& p : lent->as_array()) {
                                 auto decoded = decode_packet(p, config_.layout.nodes());
                                 if (!decoded) return rt.fail("ring: a lent packet: " + decoded.error().message);
                                 ++node_->work().packets_borrowed;
                                 lent_to_me_.push_back(std::move(decoded->first));
                               }
                               if (!lent_to_me_.empty()) return;
                             }
                             const Value* idle = r->body.find("idle");
                             if (idle && idle->is_array())
                               for (const auto& x : idle->as_array())
                                 if (x.is_int() && x.as_int() >= 0 && x.as_int() < config_.layout.rings)
                                   idle_rings_.insert(static_cast<int>(x.as_int()));
                             const Value* done = r->body.find("finished");
                             if (done && done->is_bool() && done->as_bool()) idle_rings_.insert(ring);
                             // Busy but nothing to lend right now: try again shortly.
                             next_poll_ = Clock::now() + std::chrono::milliseconds(2);
                             polling_ = true;
                           });
  }

  void on_poll(const std::string& peer, wire::Message& m, Runtime& rt) {
    const Value* it = m.body.find("iteration");
    if (!it || !it->is_int()) return rt.reply_error(peer, m.header.id, "bad_request", "ring.poll needs an iteration");
    const bool current = running_ && static_cast<int64_t>(node_->iteration()) == it->as_int();
    if (current && node_->pending() > 0) {
      // Half of what waits here, up to kMaxLend: one poll's round trip then buys several packets' work, which
      // matters when processes share cores and every message waits for the peer to be scheduled.
      const size_t count = std::min(kMaxLend, std::max<size_t>(1, node_->pending() / 2));
      Value::Array packets;
      for (size_t i = 0; i < count; ++i) {
        auto p = node_->take_pending();
        ++node_->work().packets_lent;
        packets.push_back(encode_packet(*p, static_cast<int>(p->origin)));
      }
      rt.reply(peer, m.header.id, Value::Map{{"packets", std::move(packets)}});
      return;
    }
    const bool finished = current && node_->finished() && own_out_ == 0;
    Value::Array idle;
    if (finished) {
      idle.push_back(node_->ring());
      for (int r : idle_rings_) idle.push_back(r);
    }
    rt.reply(peer, m.header.id, Value::Map{{"finished", finished}, {"idle", std::move(idle)}});
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
