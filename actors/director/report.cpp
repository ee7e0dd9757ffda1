#include "actors/director/report.hpp"

#include <sys/resource.h>

#include <cstdio>
#include <fstream>

#include "actors/director/job_record.hpp"

namespace lf {

namespace {
double num(const Value& stats, const char* key) {
  const Value* v = stats.find(key);
  return v && v->is_number() ? v->as_double() : 0.0;
}

// Every camera sample the run rendered.
double samples_rendered(const FarmSpec& spec, const RunFigures& f) {
  const double per_pixel = f.pixel_samples > 0 ? static_cast<double>(f.pixel_samples)
                                                : static_cast<double>(spec.image.spp) * static_cast<double>(f.frames_rendered);
  return static_cast<double>(spec.image.width) * spec.image.height * per_pixel;
}
}  // namespace

void print_report(const FarmSpec& spec, const Supervisor& supervisor, const RunFigures& f) {
  const double samples = samples_rendered(spec, f);
  std::fprintf(stderr, "\n%-12s %9s %7s\n", "phase", "seconds", "share");
  for (const auto& [name, secs] : f.stage_seconds)
    std::fprintf(stderr, "%-12s %9.3f %6.1f%%\n", name.c_str(), secs, 100.0 * secs / f.total_seconds);
  std::fprintf(stderr, "%-12s %9.3f %6.1f%%\n\n", "total", f.total_seconds, 100.0);
  if (f.frames_rendered == 0) {
    std::printf("nothing to render: every frame of the job is done (%s)\n", JobRecord::folder_for(spec.image.output).c_str());
    return;
  }
  std::fprintf(stderr, "%-14s %-10s %8s %9s %11s %9s %9s %8s %7s %6s\n", "actor", "kind", "pid", "requests", "points",
               "MiB in", "MiB out", "busy s", "cpu s", "peakq");
  for (const auto& a : spec.actors) {
    const ActorRecord& s = supervisor.at(a.name);
    if (!a.has_process()) {
      std::fprintf(stderr, "%-14s %-10s %8s  dispatched by its clients\n", a.name.c_str(), "pool", "-");
      continue;
    }
    if (s.lost) {
      std::fprintf(stderr, "%-14s %-10s %8d  lost: %s\n", a.name.c_str(), a.kind.c_str(),
                   static_cast<int>(supervisor.host_pid(s)), s.loss.c_str());
      continue;
    }
    std::fprintf(stderr, "%-14s %-10s %8d %9.0f %11.0f %9.2f %9.2f %8.3f %7.3f %6.0f\n", a.name.c_str(),
                 a.kind.c_str(), static_cast<int>(supervisor.host_pid(s)), num(s.stats, "requests"), num(s.stats, "points"),
                 num(s.stats, "bytes_in") / 1048576.0, num(s.stats, "bytes_out") / 1048576.0,
                 num(s.stats, "busy_seconds"), num(s.stats, "cpu_seconds"), num(s.stats, "peak_queue"));
  }
  // What each LightOp says about its own work (STATS detail): cache coverage, photons, ...
  bool header = false;
  for (const auto& a : spec.actors) {
    const ActorRecord& s = supervisor.at(a.name);
    const Value* detail = s.stats.find("detail");
    if (s.lost || a.is_multiplexer() || a.is_ring_node() || !detail || !detail->is_map() || detail->as_map().empty())
      continue;
    if (!header) std::fprintf(stderr, "\n%-14s %s\n", "lightop", "figures");
    header = true;
    std::string line;
    for (const auto& [key, v] : detail->as_map()) {
      if (!v.is_number()) continue;
      char number[32];
      if (v.is_int()) std::snprintf(number, sizeof number, "%lld", static_cast<long long>(v.as_int()));
      else std::snprintf(number, sizeof number, "%.3g", v.as_double());
      line += (line.empty() ? "" : ", ") + key + " " + number;
    }
    std::fprintf(stderr, "%-14s %s\n", a.name.c_str(), line.c_str());
  }
  std::fprintf(stderr, "\nrender: %.2f M samples/s\n", samples / f.render_seconds / 1e6);
  const std::string shaded =
      spec.image.shaded_per_pixel() < spec.image.spp ? ", " + std::to_string(spec.image.shade_spp) + " shaded" : "";
  const Value* frames = f.frames.find("frames");
  std::string what = spec.image.output;
  if (frames && frames->is_array() && !frames->as_array().empty()) {
    const auto& list = frames->as_array();
    what = std::to_string(list.size()) + " frame" + (list.size() == 1 ? ": " : "s: ") + list.front().find("output")->as_string();
    if (list.size() > 1) what += (list.size() > 2 ? " ... " : ", ") + list.back().find("output")->as_string();
  }
  // A time-limited frame alone: the samples its passes gave (a job's frames each said theirs).
  const std::string spp = spec.image.time_limit > 0 && f.frames_rendered == 1 && f.pixel_samples > 0
                              ? std::to_string(f.pixel_samples) + " spp in " +
                                    std::to_string(f.pixel_samples / static_cast<uint64_t>(spec.image.spp)) + " passes"
                              : std::to_string(spec.image.spp) + " spp";
  std::printf("wrote %s (%dx%d, %s%s)\n", what.c_str(), spec.image.width, spec.image.height, spp.c_str(), shaded.c_str());
}

Status write_stats_json(const FarmSpec& spec, const Supervisor& supervisor, const RunFigures& f,
                        const std::string& path) {
  const double samples = samples_rendered(spec, f);
  Value::Map phases;
  Value::Map director_phases;
  for (size_t i = 0; i < f.stage_seconds.size(); ++i) {
    phases[f.stage_seconds[i].first] = f.stage_seconds[i].second;
    if (i < f.stage_cpu_seconds.size()) director_phases[f.stage_seconds[i].first] = f.stage_cpu_seconds[i];
  }
  phases["total"] = f.total_seconds;
  Value::Array actors;
  double shading_requests = 0, messages = 0, actors_cpu = 0;
  for (const auto& a : spec.actors) {
    const ActorRecord& st = supervisor.at(a.name);
    if (a.is_renderer()) shading_requests += num(st.stats, "requests");
    messages += num(st.stats, "messages_out");
    actors_cpu += num(st.stats, "cpu_seconds");
  }
  struct rusage director_usage {};
  ::getrusage(RUSAGE_SELF, &director_usage);
  auto secs = [](const timeval& t) { return static_cast<double>(t.tv_sec) + t.tv_usec * 1e-6; };
  const double director_cpu = secs(director_usage.ru_utime) + secs(director_usage.ru_stime);
  for (const auto& a : spec.actors) {
    const ActorRecord& s = supervisor.at(a.name);
    Value entry = s.stats.is_map() ? s.stats : Value(Value::Map{});
    entry.as_map()["name"] = a.name;
    entry.as_map()["kind"] = a.kind;
    if (a.has_process()) entry.as_map()["pid"] = static_cast<int64_t>(supervisor.host_pid(s));
    else entry.as_map()["dispatched_by_clients"] = true;
    if (s.lost) entry.as_map()["lost"] = s.loss;
    actors.push_back(std::move(entry));
  }
  Value doc = Value::Map{{"script", spec.script},
                         {"output", spec.image.output},
                         {"image", spec.image.to_value()},
                         {"phases_seconds", std::move(phases)},
                         {"phases_director_cpu_seconds", std::move(director_phases)},
                         {"render_samples_per_second", f.render_seconds > 0 ? samples / f.render_seconds : 0.0},
                         {"first_tile_seconds", f.first_tile_seconds},
                         {"render_seconds", f.render_seconds},
                         {"pixel_samples", samples / (static_cast<double>(spec.image.width) * spec.image.height)},
                         {"totals", Value::Map{{"renderer_shading_requests", shading_requests},
                                               {"messages_sent", messages},
                                               {"actors_cpu_seconds", actors_cpu},
                                               {"director_cpu_seconds", director_cpu}}},
                         {"actors", std::move(actors)}};
  if (!f.radiosity.is_nil()) doc.as_map()["radiosity"] = f.radiosity;
  if (!f.scene.is_nil()) doc.as_map()["scene"] = f.scene;
  if (!f.frames.is_nil()) doc.as_map()["job"] = f.frames;
  std::ofstream out(path);
  out << to_json(doc, 2) << "\n";
  if (!out) return make_error("could not write stats to '" + path + "'");
  return Ok{};
}

}  // namespace lf
