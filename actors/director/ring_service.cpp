#include "actors/director/ring_service.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include "core/log.hpp"
#include "radiosity/ply.hpp"

namespace lf {

using namespace radiosity;

static double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

RingService::RingService(const FarmSpec& spec, ExchangeService& exchange, bool quiet, bool live)
    : exchange_(exchange), quiet_(quiet), live_(live && !quiet) {
  std::map<int64_t, std::string> by_index;
  for (const auto& a : spec.actors) {
    if (!a.is_ring_node()) continue;
    by_index[a.params.at("node").as_int()] = a.name;
    if (by_index.size() == 1) {
      Value::Map params = a.params;
      params.erase("node");
      config_ = read_ring_config(ParamTable(params, "radiosity"));
      loc_ = a.loc;
    }
  }
  for (auto& [i, name] : by_index) nodes_.push_back(name);
  if (active()) exchange_.expect(kSolutionKey);
}

Status RingService::prepare(const Scene& scene) {
  auto plan = plan_ring(scene, config_);
  if (!plan) return make_error(loc_.str() + ": radiosity: " + plan.error().message);
  plan_ = std::make_unique<RingPlan>(std::move(*plan));
  if (!quiet_)
    log_info("radiosity: " + std::to_string(plan_->mesh.patches.size()) + " patches, " +
             std::to_string(plan_->mesh.element_count()) + " elements on " + std::to_string(config_.layout.rings) +
             " x " + std::to_string(config_.layout.length) + " nodes (balance " + config_.balance_name() +
             ", global BSP depth " + std::to_string(plan_->bsp.depth()) + ")");
  // The solution's PLY is written after the frame: a folder that cannot take it is said before anything starts.
  if (!config_.ply.empty()) {
    const auto dir = std::filesystem::path(config_.ply).parent_path();
    if (::access(dir.c_str(), W_OK) != 0)
      return make_error("radiosity: cannot write '" + config_.ply + "': folder '" + dir.string() +
                        "' does not exist or is not writable");
  }
  return Ok{};
}

int RingService::index_of(const std::string& node) const {
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i] == node) return static_cast<int>(i);
  return -1;
}

Status RingService::on_request(const std::string& actor, wire::Op op, uint64_t id, Value body, Outbox& out) {
  return op == wire::Op::ring_shooter ? on_shooter(actor, id, body, out) : on_result(actor, id, body, out);
}

Status RingService::on_shooter(const std::string& node, uint64_t id, const Value& body, Outbox& out) {
  const int at = index_of(node);
  if (at < 0) return make_error("'" + node + "' is not a ring node");
  auto report = ring::decode_shooter_report(body, plan_ ? plan_->mesh.patches.size() : 0);
  if (!report) return make_error("ring node '" + node + "' sent " + report.error().message);
  // Sent before a rollback (the node is being rolled back, or was restarted and waits for it): dropped unanswered.
  if (report->epoch != epoch_ || !restarting_.empty()) return Ok{};
  if (report->iteration != iteration_)
    return make_error("ring node '" + node + "' reported iteration " + std::to_string(report->iteration) +
                      " while the ring is on " + std::to_string(iteration_));
  asked_[at] = {id, *report};
  if (asked_.size() < nodes_.size()) return Ok{};
  // Every node's elements at the end of this iteration: the ring can come back here if a node is lost.
  size_t with_checkpoint = 0;
  for (auto& [i, a] : asked_) with_checkpoint += a.report.checkpoint ? 1 : 0;
  if (with_checkpoint == nodes_.size()) {
    checkpoint_ = Checkpoint{iteration_, {}, 0};
    for (auto& [i, a] : asked_) {
      checkpoint_.bytes += a.report.checkpoint->size() * ring::kElementWireBytes;
      checkpoint_.elements[i] = std::move(*a.report.checkpoint);
    }
    ++checkpoints_;
    checkpoint_bytes_ += checkpoint_.bytes;
  } else if (with_checkpoint > 0) {
    return make_error("ring nodes disagree about checkpointing iteration " + std::to_string(iteration_));
  }
  // Everyone is done with this shooter: choose the next one from the nodes' candidates (in node order, so ties
  // break the same way every time).
  Candidate best;
  double unshot = 0, emitted = 0;
  for (auto& [i, a] : asked_) {
    unshot += a.report.unshot_power;
    emitted = a.report.emitted_power;
    if (a.report.candidate && a.report.candidate->beats(best)) best = *a.report.candidate;
  }
  const double fraction = emitted > 0 ? unshot / emitted : 0;
  const double t = now_seconds();
  if (iteration_ < 0) {
    if (started_ == 0) started_ = t;  // a rollback to the start keeps the first start
  } else {
    iteration_seconds_.push_back(t - last_);
    unshot_fraction_.push_back(fraction);
  }
  last_ = t;
  const bool done = fraction < config_.solver.converge || best.patch == UINT32_MAX || !(best.power > 0) ||
                    iteration_ + 1 >= config_.solver.max_iterations;
  const int64_t next = iteration_ + 1;
  if (live_) {
    std::fprintf(stderr, "\rradiosity: iteration %lld, unshot energy %.3f %% of emitted   %s", static_cast<long long>(next),
                 100 * fraction, done ? "\n" : "");
  } else if (!quiet_ && (done || next < 4 || next % 50 == 0)) {
    char line[160];
    std::snprintf(line, sizeof line, "radiosity: iteration %lld, unshot energy %.3f %% of emitted%s",
                  static_cast<long long>(next), 100 * fraction, done ? (fraction < config_.solver.converge ? " (converged)" : " (stopped: max_iterations)") : "");
    log_info(line);
  }
  std::optional<ring::ShooterChoice> choice;
  if (!done) {
    shooters_.push_back(best.patch);
    choice = ring::ShooterChoice{next, best.patch, best.unshot};
    iteration_ = next;
  }
  const Value answer = ring::encode_shooter_choice(choice);
  for (auto& [i, a] : asked_) out.reply(nodes_[static_cast<size_t>(i)], a.id, answer);
  asked_.clear();
  if (done) iteration_ = INT64_MIN;  // nothing more to shoot
  return Ok{};
}

Status RingService::on_result(const std::string& node, uint64_t id, const Value& body, Outbox& out) {
  const int at = index_of(node);
  if (at < 0) return make_error("'" + node + "' is not a ring node");
  if (!plan_) return make_error("ring node '" + node + "' sent a result before the ring was planned");
  auto decoded = ring::decode_result(body, plan_->mesh.patches.size());
  if (!decoded) return make_error("ring node '" + node + "' sent " + decoded.error().message);
  if (decoded->epoch != epoch_ || !restarting_.empty() || solved()) return Ok{};  // from before a rollback
  auto& elements = results_[at];
  elements.insert(elements.end(), decoded->elements.begin(), decoded->elements.end());
  out.reply(node, id, Value::Map{});
  if (results_.size() < nodes_.size()) return Ok{};
  std::vector<Element> all;
  for (auto& [i, list] : results_) all.insert(all.end(), list.begin(), list.end());
  // Shown with the ambient term (what is still unshot, spread evenly), like any progressive radiosity display.
  ambient_ = add_ambient(plan_->mesh, all);
  const RadiosityField field = vertex_field(plan_->mesh, all);
  if (!config_.ply.empty()) {
    if (auto st = write_ply(field, config_.ply); !st) return make_error("radiosity: " + st.error().message);
    if (!quiet_) log_info("radiosity: wrote " + config_.ply + " (" + std::to_string(field.position.size()) + " vertices, " +
                          std::to_string(field.triangles.size()) + " triangles)");
  }
  solution_ = field.to_bytes();
  exchange_.publish(kSolutionKey, solution_, out);
  return Ok{};
}

Status RingService::on_lost(const std::string& node, const std::string& why, Outbox&) {
  const int at = index_of(node);
  if (at < 0 || solved()) return Ok{};
  if (!plan_) return make_error("ring node '" + node + "' was lost before the ring was planned");
  // Everything since the checkpoint is redone: forget it, and drop whatever the nodes still send about it.
  ++epoch_;
  restarting_.insert(at);
  recoveries_.push_back({node, why, iteration_ == INT64_MIN ? static_cast<int64_t>(shooters_.size()) : iteration_,
                         checkpoint_.iteration});
  asked_.clear();
  results_.clear();
  const int64_t c = checkpoint_.iteration;
  iteration_ = c;
  shooters_.resize(static_cast<size_t>(c + 1));
  iteration_seconds_.resize(static_cast<size_t>(std::max<int64_t>(c, 0)));
  unshot_fraction_.resize(static_cast<size_t>(std::max<int64_t>(c, 0)));
  if (!quiet_)
    log_info(c < 0 ? std::string("radiosity: the ring starts the solve again (no checkpoint yet)")
                   : "radiosity: the ring goes back to its checkpoint after iteration " + std::to_string(c),
             LogKind::recovery);
  return Ok{};
}

Status RingService::on_rejoined(const std::string& node, Outbox& out) {
  const int at = index_of(node);
  if (at < 0 || !restarting_.erase(at) || !restarting_.empty()) return Ok{};
  for (size_t i = 0; i < nodes_.size(); ++i) {
    ring::Rollback rollback{epoch_, checkpoint_.iteration, {}};
    if (auto it = checkpoint_.elements.find(static_cast<int>(i)); it != checkpoint_.elements.end())
      rollback.elements = it->second;
    out.tell(nodes_[i], wire::MsgType::rollback, ring::encode_rollback(rollback));
  }
  return Ok{};
}

Value RingService::report() const {
  Value::Array seconds(iteration_seconds_.begin(), iteration_seconds_.end());
  Value::Array fractions(unshot_fraction_.begin(), unshot_fraction_.end());
  Value::Array shooters;
  for (uint32_t s : shooters_) shooters.push_back(static_cast<int64_t>(s));
  Value::Array recoveries;
  for (const auto& r : recoveries_)
    recoveries.push_back(Value::Map{{"node", r.node}, {"why", r.why}, {"lost_at_iteration", r.lost_at},
                                    {"resumed_from_iteration", r.resumed_from}});
  return Value::Map{{"rings", config_.layout.rings},
                    {"ring_length", config_.layout.length},
                    {"balance", config_.balance_name()},
                    {"iterations", static_cast<int64_t>(iteration_seconds_.size())},
                    {"solve_seconds", last_ - started_},
                    {"iteration_seconds", std::move(seconds)},
                    {"unshot_fraction", std::move(fractions)},
                    {"shooters", std::move(shooters)},
                    {"patches", static_cast<int64_t>(plan_ ? plan_->mesh.patches.size() : 0)},
                    {"checkpoint_every", config_.checkpoint_every},
                    {"checkpoints", static_cast<int64_t>(checkpoints_)},
                    {"checkpoint_bytes", static_cast<int64_t>(checkpoint_bytes_)},
                    {"recoveries", std::move(recoveries)},
                    {"ambient", Value::Array{double(ambient_.x), double(ambient_.y), double(ambient_.z)}}};
}

}  // namespace lf
