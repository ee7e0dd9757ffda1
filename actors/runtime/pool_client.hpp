#pragma once
// PoolClient: a pool of identical LightOps (its replicas) used as one input. Each request goes whole to the
// replica the Scheduler picks, or, when it holds more than `split` points and several replicas live, in near-equal
// pieces to several; the answer reaches the caller once, as if one LightOp had given it. A lost replica's pieces go
// again to the live ones, and whatever it still answers is dropped, so each piece counts once.
//
// Two owners use it: the runtime of every built-in actor whose input is a pool (CONFIG gives it the replicas, and
// it talks to them directly: no hop through a multiplexer process), and the multiplexer actor, which serves a pool
// to clients that cannot dispatch themselves (plug-ins, a pool of pools).
//
// The connections (one RequestClient per replica, each with its own window) belong to the owner; the pool only
// sends on them and is told when a replica is gone.
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "actors/runtime/scheduler.hpp"
#include "core/value.hpp"
#include "render/math.hpp"
#include "transport/client.hpp"

namespace lf {

struct PoolOptions {
  Scheduler::Strategy strategy = Scheduler::Strategy::least_loaded;
  size_t split = 0;     // split shade requests larger than this across replicas (0: never)
  size_t window = 0;    // requests of this client in progress at once, the rest wait in order (0: no limit)
  size_t stall_cap = 16;  // round robin and random skip a replica holding this many unanswered pieces
  uint64_t seed = 0;    // for Strategy::random
};

// What a pool's parameters (multiplexer { strategy, split, window, seed }) mean for a dispatcher that keeps at most
// `client_window` of its requests going (0: no limit). The stall cap is four replica windows deep: a stall limit,
// not a balancing rule (at one window it would make round robin as load-aware as least_loaded).
PoolOptions pool_options(const std::string& strategy, int64_t split, int64_t replica_window, int64_t seed,
                         size_t client_window);

class PoolClient {
 public:
  struct Replica {
    std::string name;
    wire::RequestClient* connection = nullptr;
    bool remote = false;  // on another host than this client (least_loaded prefers the others on a tie)
    int64_t part = -1;    // the scene part it holds itself (partition { colocate = true }), or -1
  };
  PoolClient(std::string name, std::vector<Replica> replicas, const PoolOptions& options);

  const std::string& name() const { return name_; }
  // Same contract as RequestClient::request: the callback runs once, with the reply (body {L} for shade) or the
  // error of the replica that failed it. `part` >= 0: the points lie in that scene part, and the request goes whole
  // to a live replica that holds it (any live one if none does).
  void request(wire::Op op, Value body, wire::RequestClient::Callback callback, int64_t part = -1);
  // Replica `name` is gone. Returns false if it is not one of this pool's; otherwise its pieces are sent again to
  // the live replicas (none live: the waiting requests stay, and live() says 0).
  bool lost(const std::string& replica);
  // A replica joins the pool (a spare in place of a lost one): pieces left waiting when none was live go to it.
  void add(Replica replica);

  size_t live() const { return scheduler_.live(); }
  size_t in_progress() const { return requests_.size(); }
  // Per replica: packets and points sent, whether it was lost.
  Value stats() const;

 private:
  struct Request {
    wire::Op op;
    Value body;  // until started
    wire::RequestClient::Callback callback;
    size_t points = 0;
    int64_t part = -1;
    size_t pieces_left = 1;
    bool started = false;
    std::vector<RGB> radiance;  // split requests gather here (one value a point, or a pixel's run)
  };
  struct Piece {
    uint64_t request;
    size_t begin, end;          // its points in the request
    size_t out_begin, out_end;  // its values in the reply: the same, or its pixels' when the reply is folded
    size_t replica = 0;
    Value body;  // kept until answered, to send again if its replica is lost
  };

  void pump();
  void start(uint64_t rid);
  void dispatch(uint64_t pid);
  void on_answer(uint64_t pid, size_t replica, Result<wire::Message> reply);
  void finish(uint64_t rid, Result<wire::Message> result);

  std::string name_;
  std::vector<Replica> replicas_;
  PoolOptions options_;
  Scheduler scheduler_;
  std::map<uint64_t, Request> requests_;
  std::deque<uint64_t> waiting_;  // requests not started (over the window), in arrival order
  size_t started_ = 0;
  std::map<uint64_t, Piece> pieces_;
  uint64_t next_request_ = 1, next_piece_ = 1;
};

}  // namespace lf
