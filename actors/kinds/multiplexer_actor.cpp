// multiplexer: a pool of identical LightOps (its inputs, the replicas) that looks like one LightOp.
//
// Accepts on the data socket:
//   REQUEST op="shade" { n, p, nrm, wo, m, k }  ->  REPLY { n, L }  (header q = requests in progress here)
// Each request goes whole to the replica the strategy picks (actors/kinds/scheduler.hpp), or, when it holds more than
// `split` points and several replicas live, in near-equal pieces to several. An ERROR from a replica (a bad batch
// fails anywhere) is passed back to the client. At most `window` requests are in flight to each replica (the
// runtime's connection to it); the rest wait here in arrival order.
// Control: ready for setup and render at once. PEER_DOWN {name} marks a replica lost: the pieces it held are sent
// again to live replicas, and anything it still answers is dropped, so each piece counts once. The director stops
// the farm when the last replica is gone.
// STATS detail: per replica, packets and points sent, and whether it was lost.
#include "actors/kinds/multiplexer_actor.hpp"

#include <limits>
#include <map>

#include "actors/kinds/scheduler.hpp"
#include "actors/codecs/shade_codec.hpp"
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
    split_ = static_cast<size_t>(params.split);
    // The cap is a stall limit (a replica holding that many unanswered packets gets no more), not a balancing
    // rule: at one window it would make round robin as load-aware as least_loaded.
    scheduler_ = std::make_unique<Scheduler>(*Scheduler::parse(params.strategy), rt.input_count(),
                                             4 * static_cast<size_t>(params.window), static_cast<uint64_t>(params.seed));
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
    const uint64_t rid = next_request_++;
    Request& req = requests_[rid];
    req.peer = peer;
    req.id = m.header.id;
    req.radiance.assign(static_cast<size_t>(n->as_int()), RGB{});
    const size_t count = req.radiance.size();
    const size_t pieces = split_ > 0 && count > split_ ? std::min(scheduler_->live(), (count + split_ - 1) / split_) : 1;
    if (pieces <= 1) {
      add_piece(rid, 0, count, std::move(m.body), rt);
      return;
    }
    // Splitting needs the points themselves; the replicas validate them against the scene.
    auto points = decode_shade_request(m.body, std::numeric_limits<size_t>::max());
    if (!points) {
      requests_.erase(rid);
      rt.reply_error(peer, m.header.id, ErrorCode::bad_request, points.error().message);
      return;
    }
    req.pieces_left = pieces;
    for (size_t i = 0; i < pieces; ++i) {
      const size_t begin = count * i / pieces, end = count * (i + 1) / pieces;
      pieces_.emplace(next_piece_, Piece{rid, begin, end, 0, encode_shade_request(*points, begin, end)});
      dispatch(next_piece_++, rt);
    }
  }

  void on_peer_down(const std::string& name, Runtime& rt) override {
    for (size_t r = 0; r < rt.input_count(); ++r) {
      if (rt.input_name(r) != name || !scheduler_->is_live(r)) continue;
      scheduler_->lost(r);
      rt.input(r).abandon_all();
      std::vector<uint64_t> again;
      for (auto& [pid, piece] : pieces_)
        if (piece.replica == r) again.push_back(pid);
      log_warn("replica '" + name + "' is gone; sending its " + std::to_string(again.size()) + " packets elsewhere");
      if (scheduler_->live() == 0) return rt.fail("lost the last replica of '" + rt.name() + "'");
      for (uint64_t pid : again) dispatch(pid, rt);
    }
  }

  // Reported to clients as this pool's load; nothing here is computed locally, so the loop may sleep.
  size_t queue_length() const override { return requests_.size(); }
  bool has_local_work() const override { return false; }

  Value extra_stats() const override {
    Value::Array replicas;
    for (size_t r = 0; r < scheduler_->size(); ++r)
      replicas.push_back(Value::Map{{"name", names_.size() > r ? names_[r] : std::string()},
                                    {"packets", scheduler_->packets_sent(r)},
                                    {"points", scheduler_->points_sent(r)},
                                    {"lost", !scheduler_->is_live(r)}});
    return Value::Map{{"replicas", std::move(replicas)}};
  }

 private:
  struct Request {
    std::string peer;
    uint64_t id = 0;
    std::vector<RGB> radiance;
    size_t pieces_left = 1;
  };
  struct Piece {
    uint64_t request;
    size_t begin, end;
    size_t replica;
    Value body;  // kept until answered, to send again if its replica is lost
  };

  void add_piece(uint64_t rid, size_t begin, size_t end, Value body, Runtime& rt) {
    pieces_.emplace(next_piece_, Piece{rid, begin, end, 0, std::move(body)});
    dispatch(next_piece_++, rt);
  }

  void dispatch(uint64_t pid, Runtime& rt) {
    if (names_.empty())
      for (size_t r = 0; r < rt.input_count(); ++r) names_.push_back(rt.input_name(r));
    Piece& piece = pieces_.at(pid);
    auto r = scheduler_->pick();
    if (!r) return rt.fail("no replica of '" + rt.name() + "' is left");
    piece.replica = *r;
    scheduler_->sent(*r, piece.end - piece.begin);
    rt.input(*r).request(wire::Op::shade, piece.body, [this, pid, replica = *r, &rt](Result<wire::Message> reply) {
      on_answer(pid, replica, std::move(reply), rt);
    });
  }

  void on_answer(uint64_t pid, size_t replica, Result<wire::Message> reply, Runtime& rt) {
    auto it = pieces_.find(pid);
    if (it == pieces_.end() || it->second.replica != replica) return;  // answered already, or moved on
    Piece piece = std::move(it->second);
    pieces_.erase(it);
    if (reply) scheduler_->answered(replica, reply->header.queue);
    auto rq = requests_.find(piece.request);
    if (rq == requests_.end()) return;  // the request already failed
    Request& req = rq->second;
    if (!reply) {
      rt.reply_error(req.peer, req.id, ErrorCode::shade_failed, reply.error().message);
      drop_request(piece.request);
      return;
    }
    auto radiance = decode_radiance(reply->body, piece.end - piece.begin);
    if (!radiance) {
      rt.reply_error(req.peer, req.id, ErrorCode::shade_failed, rt.input_name(replica) + ": " + radiance.error().message);
      drop_request(piece.request);
      return;
    }
    std::copy(radiance->begin(), radiance->end(), req.radiance.begin() + static_cast<ptrdiff_t>(piece.begin));
    if (--req.pieces_left > 0) return;
    ++rt.stats().requests;
    rt.stats().points += req.radiance.size();
    rt.reply(req.peer, req.id, encode_radiance(req.radiance));
    requests_.erase(rq);
  }

  void drop_request(uint64_t rid) {
    requests_.erase(rid);
    for (auto it = pieces_.begin(); it != pieces_.end();) it = it->second.request == rid ? pieces_.erase(it) : std::next(it);
  }

  std::unique_ptr<Scheduler> scheduler_;
  size_t split_ = 0;
  std::map<uint64_t, Request> requests_;
  std::map<uint64_t, Piece> pieces_;
  uint64_t next_request_ = 1, next_piece_ = 1;
  std::vector<std::string> names_;
};

}  // namespace

std::unique_ptr<Actor> make_multiplexer_actor() { return std::make_unique<MultiplexerActor>(); }

}  // namespace lf
