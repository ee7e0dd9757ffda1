#include "actors/runtime/pool_client.hpp"

#include <algorithm>
#include <limits>

#include "actors/codecs/shade_codec.hpp"
#include "core/log.hpp"

namespace lf {

PoolOptions pool_options(const std::string& strategy, int64_t split, int64_t replica_window, int64_t seed,
                         size_t client_window) {
  PoolOptions o;
  o.strategy = Scheduler::parse(strategy).value_or(Scheduler::Strategy::least_loaded);
  o.split = static_cast<size_t>(split);
  o.window = client_window;
  o.stall_cap = 4 * static_cast<size_t>(replica_window);
  o.seed = static_cast<uint64_t>(seed);
  return o;
}

PoolClient::PoolClient(std::string name, std::vector<Replica> replicas, const PoolOptions& options)
    : name_(std::move(name)),
      replicas_(std::move(replicas)),
      options_(options),
      scheduler_(options.strategy, replicas_.size(), options.stall_cap, options.seed) {
  for (size_t r = 0; r < replicas_.size(); ++r) {
    scheduler_.set_remote(r, replicas_[r].remote);
    scheduler_.set_group(r, replicas_[r].part);
  }
}

void PoolClient::request(wire::Op op, Value body, wire::RequestClient::Callback callback, int64_t part) {
  const uint64_t rid = next_request_++;
  Request& req = requests_[rid];
  req.op = op;
  req.part = part;
  req.callback = std::move(callback);
  if (const Value* n = body.find("n"); n && n->is_int() && n->as_int() >= 0) req.points = static_cast<size_t>(n->as_int());
  req.body = std::move(body);
  waiting_.push_back(rid);
  pump();
}

void PoolClient::pump() {
  while (!waiting_.empty() && (options_.window == 0 || started_ < options_.window) && scheduler_.live() > 0) {
    const uint64_t rid = waiting_.front();
    waiting_.pop_front();
    start(rid);
  }
}

void PoolClient::start(uint64_t rid) {
  Request& req = requests_.at(rid);
  req.started = true;
  ++started_;
  const size_t count = req.points;
  const size_t pieces = req.op == wire::Op::shade && req.part < 0 && options_.split > 0 && count > options_.split
                            ? std::min(scheduler_.live(), (count + options_.split - 1) / options_.split)
                            : 1;
  if (pieces <= 1) {
    pieces_.emplace(next_piece_, Piece{rid, 0, count, 0, count, 0, std::move(req.body)});
    dispatch(next_piece_++);
    return;
  }
  // A request whose reply is folded by pixel is cut between pixels only, and each piece's reply holds its runs.
  auto fold = decode_pixel_fold(req.body);
  if (!fold) return finish(rid, make_error(fold.error().message, ErrorCode::bad_request));
  const uint32_t spp = *fold ? static_cast<uint32_t>((*fold)->spp) : 1;
  auto pixel_at = [&](size_t j) { return (*fold)->samples[j] / spp; };
  std::vector<size_t> cuts{0};
  for (size_t i = 1; i < pieces; ++i) {
    size_t cut = std::max(count * i / pieces, cuts.back());
    while (*fold && cut > 0 && cut < count && pixel_at(cut) == pixel_at(cut - 1)) ++cut;
    if (cut > cuts.back() && cut < count) cuts.push_back(cut);
  }
  cuts.push_back(count);
  // The pieces are cut from the request's arrays as bytes; the replicas validate the points against the scene.
  std::vector<Piece> split;
  size_t out = 0;
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    auto body = slice_shade_request(req.body, cuts[i], cuts[i + 1]);
    if (!body) return finish(rid, make_error(body.error().message, ErrorCode::bad_request));
    const size_t values = *fold ? pixel_runs(std::span<const uint32_t>((*fold)->samples).subspan(cuts[i], cuts[i + 1] - cuts[i]),
                                             (*fold)->spp)
                                : cuts[i + 1] - cuts[i];
    split.push_back(Piece{rid, cuts[i], cuts[i + 1], out, out + values, 0, std::move(*body)});
    out += values;
  }
  req.body = Value();
  req.pieces_left = split.size();
  req.radiance.assign(out, RGB{});
  for (Piece& piece : split) {
    pieces_.emplace(next_piece_, std::move(piece));
    dispatch(next_piece_++);
  }
}

void PoolClient::dispatch(uint64_t pid) {
  Piece& piece = pieces_.at(pid);
  const int64_t part = requests_.at(piece.request).part;
  const auto r = part >= 0 ? scheduler_.pick(part) : scheduler_.pick();
  if (!r) return;  // nobody left: the owner stops (lost() said so)
  piece.replica = *r;
  scheduler_.sent(*r, piece.end - piece.begin);
  const wire::Op op = requests_.at(piece.request).op;
  replicas_[*r].connection->request(op, piece.body, [this, pid, replica = *r](Result<wire::Message> reply) {
    on_answer(pid, replica, std::move(reply));
  });
}

void PoolClient::on_answer(uint64_t pid, size_t replica, Result<wire::Message> reply) {
  auto it = pieces_.find(pid);
  if (it == pieces_.end() || it->second.replica != replica) return;  // answered already, or moved on
  Piece piece = std::move(it->second);
  pieces_.erase(it);
  scheduler_.answered(replica, reply ? reply->header.queue : 0);
  auto rq = requests_.find(piece.request);
  if (rq == requests_.end()) return;  // the request already failed
  Request& req = rq->second;
  if (!reply || req.radiance.empty()) return finish(piece.request, std::move(reply));  // whole: passed on as it came
  auto radiance = decode_radiance(reply->body, piece.out_end - piece.out_begin);
  if (!radiance) return finish(piece.request, make_error(replicas_[replica].name + ": " + radiance.error().message, ErrorCode::shade_failed));
  std::copy(radiance->begin(), radiance->end(), req.radiance.begin() + static_cast<ptrdiff_t>(piece.out_begin));
  if (--req.pieces_left > 0) return;
  wire::Message whole = std::move(*reply);
  whole.body = encode_radiance(req.radiance);
  finish(piece.request, std::move(whole));
}

void PoolClient::finish(uint64_t rid, Result<wire::Message> result) {
  auto rq = requests_.find(rid);
  auto callback = std::move(rq->second.callback);
  if (rq->second.started) --started_;
  requests_.erase(rq);
  // A failed request's other pieces are dropped; their answers then find nothing.
  for (auto it = pieces_.begin(); it != pieces_.end();) it = it->second.request == rid ? pieces_.erase(it) : std::next(it);
  callback(std::move(result));
  pump();
}

bool PoolClient::lost(const std::string& name) {
  for (size_t r = 0; r < replicas_.size(); ++r) {
    if (replicas_[r].name != name) continue;
    if (!scheduler_.is_live(r)) return true;
    scheduler_.lost(r);
    replicas_[r].connection->abandon_all();
    std::vector<uint64_t> again;
    for (const auto& [pid, piece] : pieces_)
      if (piece.replica == r) again.push_back(pid);
    log_warn("replica '" + name + "' of '" + name_ + "' is gone; sending its " + std::to_string(again.size()) +
             " packets to the others");
    if (scheduler_.live() == 0) return true;
    for (uint64_t pid : again) dispatch(pid);
    return true;
  }
  return false;
}

void PoolClient::add(Replica replica) {
  scheduler_.add(replica.remote, replica.part);
  replicas_.push_back(std::move(replica));
  std::vector<uint64_t> stranded;
  for (const auto& [pid, piece] : pieces_)
    if (!scheduler_.is_live(piece.replica)) stranded.push_back(pid);
  for (uint64_t pid : stranded) dispatch(pid);
  pump();
}

Value PoolClient::stats() const {
  Value::Array replicas;
  for (size_t r = 0; r < replicas_.size(); ++r)
    replicas.push_back(Value::Map{{"replica", replicas_[r].name},
                                  {"packets", scheduler_.packets_sent(r)},
                                  {"points", scheduler_.points_sent(r)},
                                  {"lost", !scheduler_.is_live(r)}});
  return Value::Map{{"pool", name_}, {"replicas", std::move(replicas)}};
}

}  // namespace lf
