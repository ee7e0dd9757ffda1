#include "actors/director/frame_loop.hpp"

#include <chrono>
#include <cstdio>

#include "actors/codecs/control_codec.hpp"
#include "actors/director/farm_failure.hpp"
#include "actors/director/film_checkpoint.hpp"
#include "core/log.hpp"
#include "render/lightops/lightop_registry.hpp"

namespace lf {

namespace {

// Whether actor `a` is a LightOp that carries its setup over a job's views (a plug-in's own process cannot say: no).
bool carries_views(const ActorSpec& a) {
  const LightOpKind* kind = a.runtime.count("cmd") ? nullptr : find_lightop_kind(a.kind);
  if (!kind) return false;
  try {
    const auto op = create_lightop(*kind, ParamTable(a.params, a.name));
    return op->setup_sees_camera() && op->carries_views();
  } catch (const std::exception&) {
    return false;  // its own process will say what is wrong with its parameters
  }
}

// Whether actor i is a pool's second or later replica that shares its setup with the others: the pool's first
// keeps the carried setup for all of them (they hold the same), and all restore the first's.
bool kept_by_first_replica(const FarmSpec& spec, size_t i) {
  const int pool = spec.pool_of(static_cast<int>(i));
  if (pool < 0) return false;
  const auto& replicas = spec.actors[static_cast<size_t>(pool)].inputs;
  const LightOpKind* kind = find_lightop_kind(spec.actors[i].kind);
  return replicas.size() > 1 && replicas.front() != static_cast<int>(i) && kind && kind->shares_setup_for(spec.actors[i].params);
}

// The actors a carried setup may ask while it extends to a view: every input of a carrying op, and theirs, on to the
// end of the network. During a replay only these set themselves up for the view.
std::vector<std::string> asked_by_carried_setups(const FarmSpec& spec) {
  std::vector<bool> asked(spec.actors.size(), false);
  std::vector<int> todo;
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (carries_views(spec.actors[i])) todo.insert(todo.end(), spec.actors[i].inputs.begin(), spec.actors[i].inputs.end());
  while (!todo.empty()) {
    const int i = todo.back();
    todo.pop_back();
    if (asked[static_cast<size_t>(i)]) continue;
    asked[static_cast<size_t>(i)] = true;
    const auto& inputs = spec.actors[static_cast<size_t>(i)].inputs;
    todo.insert(todo.end(), inputs.begin(), inputs.end());
  }
  std::vector<std::string> names;
  for (size_t i = 0; i < spec.actors.size(); ++i)
    if (asked[i]) names.push_back(spec.actors[i].name);
  return names;
}

// Whether actor `a` answers two frames' views at once (frames in flight). The farm's own kinds do, but geometry
// actors' rays resume ops without their view; a built-in op does unless it carries its setup over the views and
// cannot be copied (LightOp::fork_view); a plug-in's own process cannot say: no.
bool answers_two_views(const ActorSpec& a) {
  if (a.runtime.count("cmd") || a.is_geometry()) return false;
  const LightOpKind* kind = find_lightop_kind(a.kind);
  if (!kind || a.is_renderer() || a.is_multiplexer() || a.is_ring_node()) return true;
  try {
    const auto op = create_lightop(*kind, ParamTable(a.params, a.name));
    return !(op->setup_sees_camera() && op->carries_views()) || op->fork_view() != nullptr;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

FrameLoop::FrameLoop(FarmSpec& spec, TileService& tiles, ExchangeService& exchange, Outbox& out, const RunOptions& options)
    : spec_(spec), tiles_(tiles), exchange_(exchange), out_(out), options_(options) {}

void FrameLoop::prepare(const std::string& scene_hash) {
  if (!spec_.job.declared) {
    FrameSpec one{1, spec_.camera, spec_.image.output};
    left_.push_back({one, 0, frame_key(spec_, scene_hash, one.camera)});
  } else {
    record_.emplace(spec_.image.output);
    std::string note;
    if (options_.restart) record_->clear(), CarriedSetups::clear(record_->folder());
    else record_->load(note);
    if (!note.empty()) log_warn(note);
    for (size_t i = 0; i < spec_.actors.size(); ++i)
      if (spec_.actors[i].has_process() && carries_views(spec_.actors[i]) && !kept_by_first_replica(spec_, i))
        carrying_.push_back(spec_.actors[i].name);
    // Each frame's key; a carried setup's key chains those of every frame up to its own, chosen or not.
    std::map<int, std::string> setup_keys;
    std::string chain;
    for (size_t i = 0; i < spec_.frames.size(); ++i) {
      const FrameSpec& f = spec_.frames[i];
      if (!f.selected && !any_carried()) continue;
      std::string key = frame_key(spec_, scene_hash, f.camera, f.materials);
      if (any_carried()) setup_keys[f.number] = chain = setup_key(chain, key);
      if (!f.selected) continue;
      if (record_->done(f.number, key, f.output)) ++skipped_;
      else left_.push_back({f, i, std::move(key)});
    }
    flyable_ = spec_.job.in_flight && options_.preview_every <= 0 && spec_.image.time_limit <= 0 &&
               std::all_of(spec_.actors.begin(), spec_.actors.end(), [](const ActorSpec& a) { return answers_two_views(a); });
    if (any_carried()) {
      asked_by_carried_ = asked_by_carried_setups(spec_);
      carried_.begin(record_->folder(), std::move(setup_keys));
    }
    if (skipped_ > 0)
      log_info(std::to_string(skipped_) + " of the job's " + std::to_string(left_.size() + skipped_) + " frames are done (" +
                   record_->folder() + ", their images unchanged); " +
                   (left_.empty() ? std::string("nothing to render") : std::to_string(left_.size()) + " to render"),
               LogKind::recovery);
  }
  if (left_.empty()) return;
  tiles_.begin_frame(left_[0].frame.output, left_[0].key, options_.checkpoint_every, options_.restart, options_.preview_every,
                     frame_number(left_[0]));
  // Set up seen from the job's first frame, whichever frame renders first: a setup kept over the frames (one
  // that does not see the camera, but may have asked ops that do) is then the same in every run of the job.
  spec_.camera = spec_.job.declared ? spec_.frames.front().camera : left_[0].frame.camera;
}

size_t FrameLoop::materials_change(size_t index) const {
  while (index > 0 && spec_.frames[index].materials == spec_.frames[index - 1].materials) --index;
  return index;
}

void FrameLoop::switch_view(const FrameSpec& f, bool replay, const std::function<void(wire::Phase, Value::Map)>& run_phase,
                            bool new_materials, std::optional<int> in_flight) {
  // Every actor takes the view first; then what depends on it is set up again (an op's new setup may ask others).
  // A replayed view, which nothing renders, needs only what carried setups extend to it and what they ask.
  control::FrameView view{f.number, f.camera, replay ? std::optional(asked_by_carried_) : std::nullopt};
  view.keep = any_carried();  // for a later run of the job, which then need not replay
  view.materials = f.materials;
  view.new_materials = new_materials;
  view.in_flight = in_flight;
  if (new_materials && !replay && !options_.quiet)
    log_info("frame " + std::to_string(f.number) + ": the materials change, and every setup starts anew");
  const auto start = std::chrono::steady_clock::now();
  run_phase(wire::Phase::frame, control::encode_frame(view));
  const auto taken = std::chrono::steady_clock::now();
  run_phase(wire::Phase::setup, {});
  char line[96];
  std::snprintf(line, sizeof line, ": view taken in %.3f s, set up in %.3f s",
                std::chrono::duration<double>(taken - start).count(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - taken).count());
  log_debug("frame " + std::to_string(f.number) + (replay ? " (replayed)" : "") + line);
}

bool FrameLoop::catch_up(size_t holds, size_t before, const std::function<void(wire::Phase, Value::Map)>& run_phase) {
  using Clock = std::chrono::steady_clock;
  size_t from = holds + 1;
  for (size_t j = before; j > holds; --j) {
    std::vector<std::string> states;
    for (const std::string& actor : carrying_) {
      auto state = carried_.find(actor, spec_.frames[j].number);
      if (!state) break;
      states.push_back(std::move(*state));
    }
    if (states.size() != carrying_.size()) continue;
    const auto start = Clock::now();
    size_t bytes = 0;
    for (size_t a = 0; a < carrying_.size(); ++a) {
      bytes += states[a].size();
      carried_.restored(carrying_[a], spec_.frames[j].number, states[a]);
      exchange_.publish("setup/" + carrying_[a], std::move(states[a]), out_);
    }
    // The frame about to render restored: every other op sets up for its view as usual. An earlier one: nothing
    // else need set up for a view nothing renders.
    control::FrameView view{spec_.frames[j].number, spec_.frames[j].camera,
                            j == before ? std::nullopt : std::optional(std::vector<std::string>{})};
    view.restore = true;
    view.materials = spec_.frames[j].materials;  // those the farm holds (no change lies between holds and j)
    run_phase(wire::Phase::frame, control::encode_frame(view));
    run_phase(wire::Phase::setup, {});
    restore_seconds_ += std::chrono::duration<double>(Clock::now() - start).count();
    if (!options_.quiet) {
      char size[32];
      std::snprintf(size, sizeof size, "%.1f MB", static_cast<double>(bytes) / 1e6);
      log_info("restored the setups carried over the views to frame " + std::to_string(spec_.frames[j].number) + " (" +
                   size + ", " + record_->folder() + "/setups)",
               LogKind::recovery);
    }
    if (j == before) return true;
    from = j + 1;
    break;
  }
  if (from >= before) return false;
  if (!options_.quiet)
    log_info("replaying the views of the " + std::to_string(before - from) + " frames before frame " +
             std::to_string(spec_.frames[before].number) + ", which this run does not render: a setup carried over the "
             "frames then holds what the whole job's would");
  const auto replay_start = Clock::now();
  for (size_t j = from; j < before; ++j) switch_view(spec_.frames[j], true, run_phase);
  replay_seconds_ += std::chrono::duration<double>(Clock::now() - replay_start).count();
  return false;
}

bool FrameLoop::flies(size_t i) const {
  return flyable_ && i + 1 < left_.size() && left_[i + 1].index == left_[i].index + 1 &&
         spec_.frames[left_[i + 1].index].materials == spec_.frames[left_[i].index].materials;
}

void FrameLoop::run(const FrameStages& stages) {
  using Clock = std::chrono::steady_clock;
  size_t holds = 0;        // the frame (in spec.frames) whose view the farm holds: set up from the first
  bool began = false;      // left_[i] began in flight, beside the frame before
  bool rendering = false;  // PHASE render is out, and the renderers have not all answered READY render
  const auto start = Clock::now();
  auto tiles_began = start;  // when the frame under way began to hand out its tiles
  for (size_t i = 0; i < left_.size(); ++i) {
    const Left& f = left_[i];
    if (!began) {
      if (i > 0)
        tiles_.begin_frame(f.frame.output, f.key, options_.checkpoint_every, options_.restart, options_.preview_every,
                           frame_number(f));
      // Where the materials change, every setup starts anew, seen from that frame: a run that skips to a later frame
      // takes the change's frame first (no render), so its setups are those of the job run in one go.
      const size_t change = materials_change(f.index);
      if (change > holds && change < f.index) {
        if (!options_.quiet)
          log_info("taking frame " + std::to_string(spec_.frames[change].number) + " first, where the materials change "
                   "(every setup starts anew there), for frame " + std::to_string(f.frame.number),
                   LogKind::recovery);
        switch_view(spec_.frames[change], true, stages.run_phase, /*new_materials=*/true);
        holds = change;
      }
      const bool restored = any_carried() && change <= holds && f.index > holds + 1 && catch_up(holds, f.index, stages.run_phase);
      if (f.index != holds && !restored) switch_view(f.frame, false, stages.run_phase, change == f.index && change > 0);
      holds = f.index;
    }
    if (!rendering) stages.run_phase(wire::Phase::render, {}), rendering = true, tiles_began = Clock::now();
    began = two_in_flight_ = flies(i);
    begun_in_flight_ += began;
    tiles_.expect_next_frame(began);
    if (began) {
      // The next frame's view goes out while this one's last tiles still keep the farm busy (NextViewTiming); then
      // its tiles, after any of this frame's still to hand out. This frame is written when its last tile is in.
      const size_t total = tiles_.tiles_total();
      stages.render_until([&] {
        const size_t left = tiles_.tiles_unassigned();
        return next_view_.due(left, total - left, std::chrono::duration<double>(Clock::now() - tiles_began).count());
      });
      const size_t left_at_switch = tiles_.tiles_unassigned();
      const auto switch_start = Clock::now();
      const Left& next = left_[i + 1];
      switch_view(next.frame, false, stages.run_phase, false, f.frame.number);
      stages.run_phase(wire::Phase::render, {});  // every actor has PHASE render for each frame, and answers it
      next_view_.switched(std::chrono::duration<double>(Clock::now() - switch_start).count());
      log_debug("frame " + std::to_string(next.frame.number) + " began with " + std::to_string(left_at_switch) +
                " tiles of frame " + std::to_string(f.frame.number) + " to hand out");
      tiles_.begin_frame(next.frame.output, next.key, options_.checkpoint_every, options_.restart, 0, frame_number(next),
                         /*in_flight=*/true);
      tiles_began = Clock::now();
      tiles_.serve(out_);
      holds = next.index;
      stages.render_until([this] { return tiles_.earlier_finished(); });
      if (auto st = tiles_.write_earlier(); !st) throw FarmFailure{st.error().message};
      two_in_flight_ = false;
    } else {
      stages.end_render();
      rendering = false;
      tiles_.finish_progress();
      if (!tiles_.finished()) throw FarmFailure{"the renderers stopped before every tile was done"};
      if (auto st = tiles_.write_frame(); !st) throw FarmFailure{st.error().message};
    }
    // A frame's time is from the last image written (or its own start) to its own: frames in flight overlap.
    const auto now = Clock::now();
    written(f, std::chrono::duration<double>(now - last_written_.value_or(start)).count());
    last_written_ = now;
  }
}

void FrameLoop::written(const Left& f, double seconds) {
  ++written_;
  figures_.push_back({f.frame.number, seconds, f.frame.output, std::max(1, tiles_.passes()) * spec_.image.spp});
  if (!record_) return;
  if (auto st = record_->add(f.frame.number, f.key, f.frame.output); !st)
    log_warn(st.error().message + "; a later run will render frame " + std::to_string(f.frame.number) + " again");
  if (options_.quiet) return;
  char line[96];
  std::snprintf(line, sizeof line, " (%zu of %zu) in %.1f s", written_ + skipped_, left_.size() + skipped_, seconds);
  std::string text = "frame " + std::to_string(f.frame.number) + " written to " + f.frame.output + line;
  if (const Value* eta = status(0).find("eta_seconds"); eta && written_ < left_.size())
    std::snprintf(line, sizeof line, "; the job's frames left: about %.0f s", eta->as_double()), text += line;
  log_info(text);
}

Value FrameLoop::status(double current_done) const {
  if (!record_) return Value();
  double mean = 0;
  size_t counted = 0;
  for (size_t i = figures_.size() > 1 ? 1 : 0; i < figures_.size(); ++i) mean += figures_[i].seconds, ++counted;
  if (counted > 0) mean /= static_cast<double>(counted);
  const size_t rendering = written_ < left_.size() ? 1 : 0;
  Value::Map m{{"frames_total", static_cast<int64_t>(left_.size() + skipped_)},
               {"frames_done", static_cast<int64_t>(written_ + skipped_)},
               {"frame", static_cast<int64_t>(rendering ? left_[written_].frame.number : 0)},
               {"frames_in_flight", static_cast<int64_t>(rendering + (two_in_flight_ ? 1 : 0))},
               {"frame_seconds", mean}};
  if (counted > 0)
    m["eta_seconds"] = mean * (static_cast<double>(left_.size() - written_) - rendering * std::min(1.0, current_done));
  return m;
}

void FrameLoop::add_figures(RunFigures& f) const {
  f.frames_rendered = figures_.size();
  f.pixel_samples = 0;
  for (const auto& fig : figures_) f.pixel_samples += static_cast<uint64_t>(fig.samples);
  if (!record_) return;
  Value::Array frames;
  double seconds = 0;
  for (const auto& fig : figures_) {
    frames.push_back(Value::Map{{"frame", static_cast<int64_t>(fig.number)}, {"seconds", fig.seconds}, {"output", fig.output},
                                {"samples", static_cast<int64_t>(fig.samples)}});
    seconds += fig.seconds;
  }
  f.render_seconds = seconds;
  f.frames = Value::Map{{"frames", std::move(frames)}, {"skipped", static_cast<int64_t>(skipped_)},
                        {"replay_seconds", replay_seconds_}, {"restore_seconds", restore_seconds_},
                        {"begun_in_flight", static_cast<int64_t>(begun_in_flight_)},
                        {"setups_kept", static_cast<int64_t>(carried_.kept())}, {"record", record_->folder()}};
}

}  // namespace lf
