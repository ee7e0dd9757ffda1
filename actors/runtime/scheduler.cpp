#include "actors/runtime/scheduler.hpp"

#include "render/shading/sampler.hpp"

namespace lf {

std::optional<Scheduler::Strategy> Scheduler::parse(const std::string& name) {
  if (name == "round_robin") return Strategy::round_robin;
  if (name == "least_loaded") return Strategy::least_loaded;
  if (name == "random") return Strategy::random;
  return std::nullopt;
}

Scheduler::Scheduler(Strategy strategy, size_t replicas, size_t cap, uint64_t seed)
    : strategy_(strategy), cap_(cap ? cap : 1), rng_(splitmix64(seed + 0x5eed)), replicas_(replicas) {}

size_t Scheduler::live() const {
  size_t n = 0;
  for (const auto& r : replicas_) n += r.live;
  return n;
}

std::optional<size_t> Scheduler::pick() {
  const size_t n = replicas_.size();
  if (live() == 0) return std::nullopt;
  switch (strategy_) {
    case Strategy::round_robin: {
      // First live replica below the cap in cycle order; if all are full, the next live one anyway.
      std::optional<size_t> fallback;
      for (size_t k = 0; k < n; ++k) {
        size_t r = (next_ + k) % n;
        if (!replicas_[r].live) continue;
        if (!fallback) fallback = r;
        if (replicas_[r].out < cap_) {
          next_ = (r + 1) % n;
          return r;
        }
      }
      next_ = (*fallback + 1) % n;
      return fallback;
    }
    case Strategy::least_loaded: {
      std::optional<size_t> best;
      size_t best_load = 0;
      for (size_t k = 0; k < n; ++k) {
        size_t r = (next_ + k) % n;
        if (!replicas_[r].live) continue;
        size_t load = replicas_[r].out + replicas_[r].queue + (replicas_[r].remote ? 1 : 0);
        // Ties go by rotation, except that this host's replica beats another host's.
        if (!best || load < best_load || (load == best_load && !replicas_[r].remote && replicas_[*best].remote)) {
          best = r;
          best_load = load;
        }
      }
      next_ = (*best + 1) % n;
      return best;
    }
    case Strategy::random: {
      std::vector<size_t> candidates, any;
      for (size_t r = 0; r < n; ++r) {
        if (!replicas_[r].live) continue;
        any.push_back(r);
        if (replicas_[r].out < cap_) candidates.push_back(r);
      }
      const auto& from = candidates.empty() ? any : candidates;
      rng_ = splitmix64(rng_);
      return from[rng_ % from.size()];
    }
  }
  return std::nullopt;
}

std::optional<size_t> Scheduler::pick(int64_t group) {
  const size_t n = replicas_.size();
  std::optional<size_t> best;
  size_t best_load = 0;
  for (size_t k = 0; k < n; ++k) {
    const size_t r = (next_ + k) % n;
    if (!replicas_[r].live || replicas_[r].group != group) continue;
    const size_t load = replicas_[r].out + replicas_[r].queue;
    if (!best || load < best_load) {
      best = r;
      best_load = load;
    }
  }
  return best ? best : pick();
}

void Scheduler::sent(size_t r, size_t points) {
  ++replicas_[r].out;
  ++replicas_[r].packets;
  replicas_[r].points += points;
}

void Scheduler::answered(size_t r, uint32_t reported_queue) {
  if (replicas_[r].out > 0) --replicas_[r].out;
  replicas_[r].queue = reported_queue;
}

void Scheduler::lost(size_t r) {
  replicas_[r].live = false;
  replicas_[r].out = 0;
}

}  // namespace lf
