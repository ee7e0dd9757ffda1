#include "actors/kinds/slowdown.hpp"

#include <chrono>

namespace lf {
namespace {

using Clock = std::chrono::steady_clock;

class SlowedActor final : public Actor {
 public:
  explicit SlowedActor(std::unique_ptr<Actor> inner) : inner_(std::move(inner)) {}

  Status configure(const ActorConfig& config, Runtime& rt) override {
    if (auto it = config.debug.find("slowdown"); it != config.debug.end() && it->second.is_number())
      factor_ = std::max(1.0, it->second.as_double());
    return inner_->configure(config, rt);
  }
  void on_phase(wire::Phase phase, Runtime& rt) override { inner_->on_phase(phase, rt); }
  void on_frame(const FrameView& view, Runtime& rt) override { inner_->on_frame(view, rt); }
  void on_request(const std::string& peer, wire::Op op, wire::Message& request, Runtime& rt) override {
    inner_->on_request(peer, op, request, rt);
  }
  void on_progress(Runtime& rt) override {
    if (factor_ <= 1.0) return inner_->on_progress(rt);
    const auto started = Clock::now();
    if (started < resting_until_) return;
    inner_->on_progress(rt);
    const auto now = Clock::now();
    resting_until_ = now + std::chrono::duration_cast<Clock::duration>((now - started) * (factor_ - 1.0));
  }
  size_t queue_length() const override { return inner_->queue_length(); }
  bool has_local_work() const override { return Clock::now() >= resting_until_ && inner_->has_local_work(); }
  void on_peer_down(const std::string& name, Runtime& rt) override { inner_->on_peer_down(name, rt); }
  long next_due_ms() const override {
    const long inner = inner_->next_due_ms();
    const auto now = Clock::now();
    if (now >= resting_until_) return inner;
    const long rest = std::chrono::duration_cast<std::chrono::milliseconds>(resting_until_ - now).count() + 1;
    return inner < 0 ? rest : std::min(inner, rest);
  }
  Value extra_stats() const override { return inner_->extra_stats(); }

 private:
  std::unique_ptr<Actor> inner_;
  double factor_ = 1.0;
  Clock::time_point resting_until_{};
};

}  // namespace

std::unique_ptr<Actor> with_debug_slowdown(std::unique_ptr<Actor> actor) {
  return actor ? std::make_unique<SlowedActor>(std::move(actor)) : nullptr;
}

}  // namespace lf
