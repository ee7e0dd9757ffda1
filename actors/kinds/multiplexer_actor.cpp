// multiplexer: a pool of identical LightOps (its inputs, the replicas) served as one LightOp by a process of its
// own, for clients that do not dispatch to the pool themselves: plug-ins, a pool of pools, or a pool declared with
// dispatch = "process". Built-in clients otherwise get the replicas in CONFIG and dispatch to them directly, with the
// same PoolClient this actor runs (actors/runtime/pool_client.hpp).
//
// Accepts on the data socket:
//   REQUEST op="shade" { n, p, nrm, wo, m, k }  ->  REPLY { n, L }  (header q = requests in progress here)
// Each request goes whole to the replica the strategy picks (actors/runtime/scheduler.hpp), or, when it holds more
// than `split` points and several replicas live, in near-equal pieces to several. An ERROR from a replica (a bad
// batch fails anywhere) is passed back to the client. At most `window` requests are in flight to each replica (the
// runtime's connection to it); the rest wait in arrival order.
// Control: ready for setup and render at once. PEER_DOWN {name} marks a replica lost: the pieces it held are sent
// again to live replicas, and anything it still answers is dropped, so each piece counts once. The director stops
// the farm when the last replica is gone.
// STATS detail: per replica, packets and points sent, and whether it was lost.
#include "actors/kinds/multiplexer_actor.hpp"

#include "actors/runtime/pool_client.hpp"
#include "core/log.hpp"
#include "core/params.hpp"
#include "farm/kind_params.hpp"

namespace lf {
namespace {

class MultiplexerActor final : public Actor {
 public:
  Status configure(const ActorConfig& config, Runtime& rt) override {
    MultiplexerParams params;
    try {
      ParamTable p(config.params, "multiplexer '" + rt.name() + "'");
      params = MultiplexerParams::read(p);  // window is applied by the runtime to each replica's connection
      p.report_unused();
    } catch (const ParamError& e) {
      return make_error(e.what());
    }
    if (rt.input_count() == 0) return make_error("a multiplexer needs at least one replica");
    std::vector<PoolClient::Replica> replicas;
    for (size_t r = 0; r < rt.input_count(); ++r) replicas.push_back({rt.input_name(r), &rt.input(r), false});
    // Clients' requests arrive already limited by their own windows: none wait here beyond the replicas' windows.
    pool_ = std::make_unique<PoolClient>(
        rt.name(), std::move(replicas), pool_options(params.strategy, params.split, params.window, params.seed, 0));
    return Ok{};
  }

  void on_phase(wire::Phase phase, Runtime& rt) override { rt.phase_done(phase); }

  void on_request(const std::string& peer, wire::Op op, wire::Message& m, Runtime& rt) override {
    if (op != wire::Op::shade) return rt.reply_unknown_op(peer, m, "this actor serves 'shade'");
    const Value* n = m.body.find("n");
    if (!n || !n->is_int() || n->as_int() < 0) {
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, "shade request: 'n' (point count) missing or negative");
      return;
    }
    const auto points = static_cast<uint64_t>(n->as_int());
    pool_->request(wire::Op::shade, std::move(m.body),
                   [&rt, peer, id = m.header.id, points](Result<wire::Message> reply) {
                     if (!reply) return rt.reply_error(peer, id, ErrorCode::shade_failed, reply.error().message);
                     ++rt.stats().requests;
                     rt.stats().points += points;
                     rt.reply(peer, id, std::move(reply->body));
                   });
  }

  void on_peer_down(const std::string& name, Runtime& rt) override {
    if (!pool_->lost(name)) return Actor::on_peer_down(name, rt);
    if (pool_->live() == 0) rt.fail("lost the last replica of '" + rt.name() + "'");
  }

  // Reported to clients as this pool's load; nothing here is computed locally, so the loop may sleep.
  size_t queue_length() const override { return pool_ ? pool_->in_progress() : 0; }
  bool has_local_work() const override { return false; }

  Value extra_stats() const override { return pool_ ? pool_->stats() : Value(); }

 private:
  std::unique_ptr<PoolClient> pool_;
};

}  // namespace

std::unique_ptr<Actor> make_multiplexer_actor() { return std::make_unique<MultiplexerActor>(); }

}  // namespace lf
