#include "farm/pool_subset.hpp"

#include <algorithm>

namespace lf {

int64_t pool_subset(int64_t asked, int64_t replicas, int64_t clients, int64_t window) {
  if (asked == 0 || replicas <= 0) return replicas;
  if (asked > 0) return std::min(asked, replicas);
  const int64_t cover = (replicas + std::max<int64_t>(clients, 1) - 1) / std::max<int64_t>(clients, 1);
  return std::min(replicas, std::max(cover, 2 * std::max<int64_t>(window, 1)));
}

std::vector<int64_t> pool_order(int64_t replicas, int64_t subset, int64_t client) {
  std::vector<int64_t> order;
  order.reserve(static_cast<size_t>(std::max<int64_t>(replicas, 0)));
  if (subset <= 0 || subset >= replicas) {
    for (int64_t r = 0; r < replicas; ++r) order.push_back(r);
    return order;
  }
  const int64_t first = (client * subset) % replicas;
  for (int64_t i = 0; i < replicas; ++i) order.push_back((first + i) % replicas);
  return order;
}

int64_t add_near_replicas(std::vector<int64_t>& order, int64_t subset, const std::vector<bool>& near) {
  const auto size = static_cast<int64_t>(order.size());
  if (subset <= 0 || subset >= size) return subset;
  int64_t connected = subset;
  for (int64_t i = subset; i < size && connected < 2 * subset; ++i) {
    if (!near[static_cast<size_t>(order[static_cast<size_t>(i)])]) continue;
    std::rotate(order.begin() + connected, order.begin() + i, order.begin() + i + 1);
    ++connected;
  }
  return connected < size ? connected : 0;
}

}  // namespace lf
