#pragma once
// Scheduler: which replica of a pool gets the next packet (the multiplexer's strategy). Pure logic, fed with what
// the multiplexer observes; tests drive it with scripted fake replicas.
//
//   round_robin   cycles through live replicas, skipping one that already holds `cap` packets
//   least_loaded  the live replica with the smallest (packets out + queue length it last reported), as Kipfer &
//                 Slusallek's wrappers do with the FIFO fill level piggybacked on replies; a replica on another
//                 host counts one packet more, so that on a tie the one on this host wins (no network, no
//                 encryption) while a busier local replica still loses
//   random        uniform over live replicas below the cap, from a seeded generator
// A replica that stops answering accumulates packets out, so it stops getting work before it is declared dead.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lf {

class Scheduler {
 public:
  enum class Strategy { round_robin, least_loaded, random };
  static std::optional<Strategy> parse(const std::string& name);

  Scheduler(Strategy strategy, size_t replicas, size_t cap, uint64_t seed = 0);

  // The replica for the next packet, or nullopt when every replica is lost.
  std::optional<size_t> pick();
  // The least loaded live replica of `group` (set_group), or pick() when none of them lives: a partitioned farm's
  // points go to a replica that holds their part (partition { colocate = true }), whatever the pool's strategy.
  std::optional<size_t> pick(int64_t group);
  void set_group(size_t replica, int64_t group) { replicas_[replica].group = group; }
  void sent(size_t replica, size_t points);
  void answered(size_t replica, uint32_t reported_queue);
  void lost(size_t replica);  // never picked again
  // A replica joins (a spare connected in place of a lost one); its index is size() - 1.
  void add(bool remote, int64_t group) { replicas_.push_back(Replica{true, remote, group}); }
  // Replica r runs on another host than the one dispatching (least_loaded prefers the others on a tie).
  void set_remote(size_t replica, bool remote) { replicas_[replica].remote = remote; }

  size_t live() const;
  bool is_live(size_t r) const { return replicas_[r].live; }
  size_t out(size_t r) const { return replicas_[r].out; }
  uint64_t packets_sent(size_t r) const { return replicas_[r].packets; }
  uint64_t points_sent(size_t r) const { return replicas_[r].points; }
  size_t size() const { return replicas_.size(); }

 private:
  struct Replica {
    bool live = true;
    bool remote = false;      // on another host than the dispatcher
    int64_t group = -1;       // the scene part it holds (-1: none)
    size_t out = 0;           // packets sent and not answered
    uint32_t queue = 0;       // last reported queue length
    uint64_t packets = 0, points = 0;
  };
  Strategy strategy_;
  size_t cap_;
  size_t next_ = 0;   // round-robin position; also breaks least_loaded ties in rotation
  uint64_t rng_;
  std::vector<Replica> replicas_;
};

}  // namespace lf
