#include "actors/ring_coordinator.hpp"

#include <chrono>
#include <cstdio>

#include "core/log.hpp"
#include "radiosity/ply.hpp"

namespace lf {

using namespace radiosity;

static double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

RingCoordinator::RingCoordinator(const FarmSpec& spec, bool quiet, bool live) : quiet_(quiet), live_(live && !quiet) {
  std::map<int64_t, std::string> by_index;
  for (const auto& a : spec.actors) {
    if (a.kind != "radiosity_node") continue;
    by_index[a.params.at("node").as_int()] = a.name;
    if (by_index.size() == 1) {
      Value::Map params = a.params;
      params.erase("node");
      config_ = read_ring_config(ParamTable(params, "radiosity"));
      loc_ = a.loc;
    }
  }
  for (auto& [i, name] : by_index) nodes_.push_back(name);
}

Status RingCoordinator::prepare(const Scene& scene) {
  auto plan = plan_ring(scene, config_);
  if (!plan) return make_error(loc_.str() + ": radiosity: " + plan.error().message);
  plan_ = std::make_unique<RingPlan>(std::move(*plan));
  if (!quiet_)
    log_info("radiosity: " + std::to_string(plan_->mesh.patches.size()) + " patches, " +
             std::to_string(plan_->mesh.element_count()) + " elements on " + std::to_string(config_.layout.rings) +
             " x " + std::to_string(config_.layout.length) + " nodes (balance " + config_.balance_name() +
             ", global BSP depth " + std::to_string(plan_->bsp.depth()) + ")");
  return Ok{};
}

int RingCoordinator::index_of(const std::string& node) const {
  for (size_t i = 0; i < nodes_.size(); ++i)
    if (nodes_[i] == node) return static_cast<int>(i);
  return -1;
}

Result<std::vector<RingCoordinator::Reply>> RingCoordinator::on_shooter(const std::string& node, uint64_t id,
                                                                         const Value& body) {
  const int at = index_of(node);
  const Value* it = body.find("iteration");
  if (at < 0) return make_error("'" + node + "' is not a ring node");
  if (!it || !it->is_int() || it->as_int() != iteration_)
    return make_error("ring node '" + node + "' reported iteration " + (it && it->is_int() ? std::to_string(it->as_int()) : "?") +
                      " while the ring is on " + std::to_string(iteration_));
  asked_[at] = {id, body};
  if (asked_.size() < nodes_.size()) return std::vector<Reply>{};
  // Everyone is done with this shooter: choose the next one from the nodes' candidates (in node order, so ties
  // break the same way every time).
  Candidate best;
  double unshot = 0, emitted = 0;
  for (auto& [i, a] : asked_) {
    const Value* u = a.body.find("unshot_power");
    const Value* e = a.body.find("emitted_power");
    unshot += u && u->is_number() ? u->as_double() : 0;
    emitted = e && e->is_number() ? e->as_double() : emitted;
    if (const Value* c = a.body.find("candidate"); c && c->is_map()) {
      const Value *patch = c->find("patch"), *power = c->find("power"), *rgb = c->find("unshot");
      if (!patch || !patch->is_int() || !power || !power->is_number() || !rgb || !rgb->is_array() || rgb->as_array().size() != 3)
        return make_error("ring node '" + nodes_[static_cast<size_t>(i)] + "' sent a malformed candidate");
      const auto& v = rgb->as_array();
      Candidate cand{static_cast<uint32_t>(patch->as_int()), power->as_double(),
                     RGB{static_cast<float>(v[0].as_double()), static_cast<float>(v[1].as_double()),
                         static_cast<float>(v[2].as_double())}};
      if (cand.beats(best)) best = cand;
    }
  }
  const double fraction = emitted > 0 ? unshot / emitted : 0;
  const double t = now_seconds();
  if (iteration_ < 0) {
    started_ = t;
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
  Value answer;
  if (done) {
    answer = Value::Map{{"done", true}};
  } else {
    shooters_.push_back(best.patch);
    answer = Value::Map{{"shooter", Value::Map{{"iteration", next},
                                               {"patch", static_cast<int64_t>(best.patch)},
                                               {"unshot", Value::Array{double(best.unshot.x), double(best.unshot.y),
                                                                       double(best.unshot.z)}}}}};
    iteration_ = next;
  }
  std::vector<Reply> replies;
  for (auto& [i, a] : asked_) replies.push_back({nodes_[static_cast<size_t>(i)], a.id, answer});
  asked_.clear();
  if (done) iteration_ = INT64_MIN;  // nothing more to shoot
  return replies;
}

Result<std::vector<RingCoordinator::Reply>> RingCoordinator::on_result(const std::string& node, uint64_t id,
                                                                        const Value& body) {
  const int at = index_of(node);
  if (at < 0) return make_error("'" + node + "' is not a ring node");
  std::vector<uint32_t> patch, corners;
  std::vector<float> points, radiosity, unshot;
  const Value *p = body.find("patch"), *c = body.find("corners"), *x = body.find("points"), *b = body.find("radiosity"),
              *u = body.find("unshot");
  if (!p || !c || !x || !b || !u || !p->is_bytes() || !c->is_bytes() || !x->is_bytes() || !b->is_bytes() ||
      !u->is_bytes() || !bytes_to_u32(p->as_bytes(), patch) || !bytes_to_u32(c->as_bytes(), corners) ||
      !bytes_to_floats(x->as_bytes(), points) || !bytes_to_floats(b->as_bytes(), radiosity) ||
      !bytes_to_floats(u->as_bytes(), unshot) || corners.size() != patch.size() ||
      points.size() != 12 * patch.size() || radiosity.size() != 3 * patch.size() || unshot.size() != radiosity.size())
    return make_error("ring node '" + node + "' sent a malformed result");
  auto& elements = results_[at];
  for (size_t i = 0; i < patch.size(); ++i) {
    if (patch[i] >= plan_->mesh.patches.size() || (corners[i] != 3 && corners[i] != 4))
      return make_error("ring node '" + node + "' sent an element of an unknown patch");
    Element e;
    e.patch = patch[i];
    e.polygon.count = static_cast<int>(corners[i]);
    for (size_t k = 0; k < 4; ++k) e.polygon.v[k] = {points[12 * i + 3 * k], points[12 * i + 3 * k + 1], points[12 * i + 3 * k + 2]};
    e.radiosity = {radiosity[3 * i], radiosity[3 * i + 1], radiosity[3 * i + 2]};
    e.unshot = {unshot[3 * i], unshot[3 * i + 1], unshot[3 * i + 2]};
    elements.push_back(e);
  }
  std::vector<Reply> replies{{node, id, Value::Map{}}};
  if (results_.size() < nodes_.size()) return replies;
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
  return replies;
}

Value RingCoordinator::report() const {
  Value::Array seconds(iteration_seconds_.begin(), iteration_seconds_.end());
  Value::Array fractions(unshot_fraction_.begin(), unshot_fraction_.end());
  Value::Array shooters;
  for (uint32_t s : shooters_) shooters.push_back(static_cast<int64_t>(s));
  return Value::Map{{"rings", config_.layout.rings},
                    {"ring_length", config_.layout.length},
                    {"balance", config_.balance_name()},
                    {"iterations", static_cast<int64_t>(iteration_seconds_.size())},
                    {"solve_seconds", last_ - started_},
                    {"iteration_seconds", std::move(seconds)},
                    {"unshot_fraction", std::move(fractions)},
                    {"shooters", std::move(shooters)},
                    {"patches", static_cast<int64_t>(plan_ ? plan_->mesh.patches.size() : 0)},
                    {"ambient", Value::Array{double(ambient_.x), double(ambient_.y), double(ambient_.z)}}};
}

}  // namespace lf
