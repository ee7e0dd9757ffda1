// A walkthrough of Lost Empire as one job against the same frames as separate `lightfarm run`s (one run a frame:
// how a sequence is rendered without jobs).
//
// The job: examples/lost_empire.lua with --set frames=N (the network: --set lighting=network), one farm rendering
// frame 1..N. The separate runs: the same script with --set frame=K, a job of that one frame alone, for an evenly
// spread sample of the frames (--separate, default 6: frames 1, ..., N); their mean time stands for every frame's,
// and N times it for the N separate runs. Printed and written as JSON:
//   - the job's wall time against the N separate runs' (goal: <= 0.4), per run (each run's job with frames in
//     flight against its own separate runs, right after it: the machine's speed drifts over minutes), and the
//     median over the runs with its spread;
//   - the job's time per frame after the first against its first frame's (goal: <= 0.5), median and spread;
//   - the share of the machine's CPU time the job left idle (actors' and director's CPU-seconds against wall time
//     times the CPUs it may use), and the same for the separate runs;
//   - the job with frames in flight (the default) against the same job one frame at a time (--set in_flight=0), in
//     turn, --runs times: the wall time and idle share of each, also within the render stage alone (the goal's
//     "idle between frames": every frame and the switches between them, without the director reading the scene
//     before launch), the ratio of the two times, and whether every frame of the two is the same bit for bit;
//   - the first frame's time is the setup stage and its render; a later frame's, PHASE frame to its image written;
//   - whether each sampled frame of the job equals its separate run bit for bit (it does where no setup the job
//     keeps asked an op that sees the camera: the network's path tracer does not learn from the view);
//   - resume: the job run again with every frame done (verify the record, launch nothing): its wall time; and with
//     the second half's images deleted: its wall time, the part spent restoring the carried cache the job's folder
//     kept (the director's restore stage: publish, PHASE frame and setup) and the part spent replaying views
//     (none while the folder keeps the cache);
//   - error against path-traced references (lighting=pathtrace at --reference-spp, kept in --cache) of the first,
//     middle and last sampled frames: the job's frame and the separate run's (relative RMSE, bench/image_error.hpp;
//     --reference-spp 0: none);
//   - flicker between the middle sampled frame and the next: the temporal RMSE (what changed from one frame to the
//     next that the references do not change) of the job's two frames and of two separate runs, and how much each
//     one's error changed.
//
//   build/bench/walkthrough_bench [--frames N] [--separate K] [--lighting network|direct] [--width W --height H]
//                                 [--spp S] [--reference-spp S] [--cache DIR] [--runs R] [--json FILE]
#include <sched.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <string>

#include "bench/bench_util.hpp"
#include "bench/image_error.hpp"
#include "render/images/image.hpp"

namespace {

struct Args {
  int frames = 24, separate = 6;
  std::string lighting = "network";
  int width = 320, height = 240, spp = 16;
  int reference_spp = 1024;
  int runs = 1;
  std::string cache = (bench::fs::temp_directory_path() / "lightfarm-walkthrough-references").string();
  std::string json = "bench-walkthrough.json";
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--frames") a.frames = std::max(2, std::atoi(v.c_str()));
    else if (k == "--separate") a.separate = std::max(2, std::atoi(v.c_str()));
    else if (k == "--lighting") a.lighting = v;
    else if (k == "--width") a.width = std::atoi(v.c_str());
    else if (k == "--height") a.height = std::atoi(v.c_str());
    else if (k == "--spp") a.spp = std::atoi(v.c_str());
    else if (k == "--json") a.json = v;
    else if (k == "--reference-spp") a.reference_spp = std::atoi(v.c_str());
    else if (k == "--cache") a.cache = v;
    else if (k == "--runs") a.runs = std::max(1, std::atoi(v.c_str()));
  }
  a.separate = std::min(a.separate, a.frames);
  return a;
}

int cpu_count() {
  cpu_set_t set;
  CPU_ZERO(&set);
  return sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 1;
}

bool same_pixels(const std::string& a, const std::string& b) {
  auto x = lf::read_image(a), y = lf::read_image(b);
  return x.ok() && y.ok() && x->pixels == y->pixels;
}

std::string frame_file(const std::string& dir, int k) {
  char name[64];
  std::snprintf(name, sizeof name, "/walk.%04d.exr", k);
  return dir + name;
}

// The share of the machine's CPU the farm left idle in its render stage: every frame's render and the switches
// between frames, without the stages before it (the director reading the scene alone, the launch, the first
// frame's setup). From the farm's CPU sampled every 500 ms (run_farm's sample_cpu), between the first sample in
// the stage and the last.
double render_stage_idle(const bench::FarmRun& run, int cpus) {
  double start = 0;
  for (const char* stage : {"prepare", "launch", "hello", "configure", "setup"}) start += run.phase(stage);
  const double end = start + run.phase("render");
  const std::pair<double, double>* from = nullptr;
  const std::pair<double, double>* to = nullptr;
  for (const auto& sample : run.cpu_samples) {
    if (!from && sample.first >= start) from = &sample;
    if (sample.first <= end) to = &sample;
  }
  if (!from || !to || to->first <= from->first) return 0;
  return 1 - (to->second - from->second) / ((to->first - from->first) * cpus);
}

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/walkthrough_bench [--frames N] [--separate K] [--lighting network|direct]"
                            " [--width W --height H] [--spp S] [--reference-spp S] [--cache DIR] [--runs R]"
                            " [--json FILE]",
                            {"--frames", "--separate", "--lighting", "--width", "--height", "--spp", "--json", "--reference-spp",
                             "--cache", "--runs"});
  const Args args = parse(argc, argv);
  if (bench::shared_scene("lost_empire/lost_empire.obj").empty()) return 0;
  const std::string script = std::string(LIGHTFARM_SOURCE_DIR) + "/examples/lost_empire.lua";
  const auto dir = bench::fs::temp_directory_path() / ("lightfarm-walkthrough-" + std::to_string(::getpid()));
  bench::fs::create_directories(dir);
  const std::vector<std::string> look{"lighting=" + args.lighting, "width=" + std::to_string(args.width),
                                      "height=" + std::to_string(args.height), "spp=" + std::to_string(args.spp),
                                      "frames=" + std::to_string(args.frames)};
  const int cpus = cpu_count();

  // Separate runs of single frames, evenly spread over the walk: their mean wall time, their CPU-seconds and which
  // of them equal the job's frames (files single.K.exr for run 0, singleR.K.exr after).
  struct SeparateSample {
    std::vector<double> seconds;
    std::vector<int> frames;
    double cpu = 0;
    int identical = 0;
    double wall() const { return std::accumulate(seconds.begin(), seconds.end(), 0.0); }
    double mean() const { return wall() / static_cast<double>(seconds.size()); }
  };
  auto separate_sample = [&](int r) {
    SeparateSample out;
    for (int i = 0; i < args.separate; ++i) {
      const int k = 1 + static_cast<int>(std::lround(static_cast<double>(i) * (args.frames - 1) / (args.separate - 1)));
      std::vector<std::string> sets = look;
      sets.push_back("frame=" + std::to_string(k));
      const std::string out_file =
          (dir / ("single" + (r == 0 ? std::string() : std::to_string(r)) + "." + std::to_string(k) + ".exr")).string();
      const auto one = bench::run_farm(script, sets, out_file);
      out.seconds.push_back(one.wall_seconds);
      out.frames.push_back(k);
      out.cpu += one.cpu_seconds;
      out.identical += same_pixels(out_file, frame_file(dir.string(), k));
    }
    return out;
  };

  // The job, one farm, with frames in flight; and, in turn, the same job one frame at a time, then the separate runs.
  // The machine's speed drifts by 10-25 % over minutes, so each run compares its own job with its own separate runs
  // and the job / separate figure is the median over the runs.
  const auto job = bench::run_farm(script, look, (dir / "walk.####.exr").string(), false, {}, true);
  std::vector<SeparateSample> separates;
  std::vector<double> job_over_separate;
  std::vector<double> flying_seconds, one_seconds, flying_idle, one_idle, flying_render_idle, one_render_idle, ratios;
  int same_frames = 0;
  for (int r = 0; r < args.runs; ++r) {
    const std::string fly_dir = (dir / ("fly" + std::to_string(r))).string(), one_dir = (dir / ("one" + std::to_string(r))).string();
    bench::fs::create_directories(fly_dir);
    bench::fs::create_directories(one_dir);
    std::vector<std::string> one_at_a_time = look;
    one_at_a_time.push_back("in_flight=0");
    const auto one = bench::run_farm(script, one_at_a_time, one_dir + "/walk.####.exr", false, {}, true);
    const auto fly = r == 0 ? job : bench::run_farm(script, look, fly_dir + "/walk.####.exr", false, {}, true);
    flying_seconds.push_back(fly.wall_seconds), one_seconds.push_back(one.wall_seconds);
    flying_idle.push_back(1 - fly.cpu_seconds / (fly.wall_seconds * cpus));
    one_idle.push_back(1 - one.cpu_seconds / (one.wall_seconds * cpus));
    flying_render_idle.push_back(render_stage_idle(fly, cpus));
    one_render_idle.push_back(render_stage_idle(one, cpus));
    ratios.push_back(fly.wall_seconds / one.wall_seconds);
    separates.push_back(separate_sample(r));
    job_over_separate.push_back(fly.wall_seconds / (separates.back().mean() * args.frames));
    if (r > 0) continue;
    for (int k = 1; k <= args.frames; ++k) same_frames += same_pixels(frame_file(dir.string(), k), frame_file(one_dir, k));
  }
  const auto ratio_spread = bench::spread(ratios);
  std::printf("frames in flight against one at a time (%d run%s, in turn):\n", args.runs, args.runs == 1 ? "" : "s");
  for (int r = 0; r < args.runs; ++r)
    std::printf("  run %d: in flight %.1f s (%.1f%% idle; render stage %.1f%%), one at a time %.1f s (%.1f%% idle; render "
                "stage %.1f%%), ratio %.3f; separate runs %.2f s a frame, job in flight / separate runs %.3f\n", r + 1,
                flying_seconds[r], 100 * flying_idle[r], 100 * flying_render_idle[r], one_seconds[r], 100 * one_idle[r],
                100 * one_render_idle[r], ratios[r], separates[r].mean(), job_over_separate[r]);
  std::printf("  time in flight / one at a time: median %.3f (%.3f-%.3f); %d of %d frames identical\n",
              ratio_spread.median, ratio_spread.min, ratio_spread.max, same_frames, args.frames);
  std::fflush(stdout);
  const auto frame_seconds = bench::json_numbers(job.stats, "seconds");  // the job's frames, in order
  std::vector<double> later(frame_seconds.begin() + (frame_seconds.empty() ? 0 : 1), frame_seconds.end());
  // The first frame's setup is the setup stage; a later frame's (what depends on the view) is in its own seconds.
  const double first = frame_seconds.empty() ? 0 : job.phase("setup") + frame_seconds.front();
  const auto later_spread = bench::spread(later);
  const double job_idle = 1 - job.cpu_seconds / (job.wall_seconds * cpus);
  std::printf("job: %d frames in %.1f s (%.1f CPU-s; %.0f%% of %d CPUs idle); first frame %.2f s, later frames "
              "%.2f s (%.2f-%.2f)\n", args.frames, job.wall_seconds, job.cpu_seconds, 100 * job_idle, cpus, first,
              later_spread.median, later_spread.min, later_spread.max);
  std::printf("  phases: setup %.2f s, render %.2f s (the setups of frames after the first are in render)\n",
              job.phase("setup"), job.phase("render"));
  std::fflush(stdout);

  // The first run's separate runs, frame by frame.
  const SeparateSample& separate = separates.front();
  const std::vector<int>& sampled = separate.frames;
  std::printf("separate runs (run 1):");
  for (size_t i = 0; i < sampled.size(); ++i) std::printf(" %d: %.2f s", sampled[i], separate.seconds[i]);
  std::printf("\n");
  const double mean_separate = separate.mean();
  const double separate_idle = 1 - separate.cpu / (separate.wall() * cpus);
  const int identical = separate.identical;
  std::printf("  mean %.2f s a frame: %d separate runs ~ %.1f s (%.0f%% of %d CPUs idle)\n", mean_separate, args.frames,
              mean_separate * args.frames, 100 * separate_idle, cpus);
  std::printf("  %d of %d sampled frames identical to the job's\n", identical, args.separate);

  // Resume with every frame done: the scene loaded for its key, the record verified, nothing launched.
  std::fflush(stdout);
  const auto again = bench::run_farm(script, look, (dir / "walk.####.exr").string());
  std::printf("resume with every frame done: %.2f s\n", again.wall_seconds);

  // A resume mid-job: the second half's images deleted, the job run again. It restores the carried cache as kept
  // after the first frame it renders (or, without one, replays the views of the first half) before rendering.
  for (int k = args.frames / 2 + 1; k <= args.frames; ++k)
    bench::fs::rename(frame_file(dir.string(), k), frame_file(dir.string(), k) + ".first.exr");
  const auto half = bench::run_farm(script, look, (dir / "walk.####.exr").string());
  const double replay = bench::json_number(half.stats, "replay_seconds");
  const double restore = bench::json_number(half.stats, "restore_seconds");
  int resumed_identical = 0;
  for (int k = args.frames / 2 + 1; k <= args.frames; ++k)
    resumed_identical += same_pixels(frame_file(dir.string(), k), frame_file(dir.string(), k) + ".first.exr");
  std::printf("resume with frames %d-%d to render: %.1f s, of which restoring the kept cache %.2f s, replaying views "
              "%.2f s; %d of %d frames identical to the uninterrupted job's\n", args.frames / 2 + 1, args.frames,
              half.wall_seconds, restore, replay, resumed_identical, args.frames - args.frames / 2);
  std::fflush(stdout);

  // Quality: the job's frames and the separate runs' against path-traced references.
  std::string errors_json, flicker_json;
  // Frame k's path-traced reference, rendered once into --cache.
  auto reference_of = [&](int k) {
    char name[160];
    std::snprintf(name, sizeof name, "/walk%d_frame%d_%dx%d_%dspp.exr", args.frames, k, args.width, args.height,
                  args.reference_spp);
    const std::string ref_path = args.cache + name;
    if (!bench::fs::exists(ref_path)) {
      std::vector<std::string> sets = look;
      sets[0] = "lighting=pathtrace";
      sets[3] = "spp=" + std::to_string(args.reference_spp);
      sets.push_back("frame=" + std::to_string(k));
      bench::run_farm(script, sets, ref_path);
    }
    return lf::read_image(ref_path);
  };
  auto separate_of = [&](int k) { return lf::read_image((dir / ("single." + std::to_string(k) + ".exr")).string()); };
  if (args.reference_spp > 0) {
    bench::fs::create_directories(args.cache);
    for (size_t i : {size_t{0}, sampled.size() / 2, sampled.size() - 1}) {
      const int k = sampled[i];
      auto ref = reference_of(k), in_job = lf::read_image(frame_file(dir.string(), k)), alone = separate_of(k);
      if (!ref || !in_job || !alone) continue;
      const double e_job = bench::relative_rmse(*in_job, *ref), e_alone = bench::relative_rmse(*alone, *ref);
      std::printf("frame %d against a %d-spp path-traced reference: job %.4f, separate run %.4f (job / separate %.3f)\n",
                  k, args.reference_spp, e_job, e_alone, e_job / e_alone);
      char entry[200];
      std::snprintf(entry, sizeof entry, "%s{\"frame\": %d, \"job\": %.5f, \"separate\": %.5f}",
                    errors_json.empty() ? "" : ", ", k, e_job, e_alone);
      errors_json += entry;
    }
    // Flicker: between the middle sampled frame and the next, what changed from one frame to the other that the
    // references do not change (the temporal RMSE), and how much the error itself changed. The next frame's
    // separate run is rendered here.
    const int k = sampled[sampled.size() / 2], next = k < args.frames ? k + 1 : k - 1;
    std::vector<std::string> sets = look;
    sets.push_back("frame=" + std::to_string(next));
    bench::run_farm(script, sets, (dir / ("single." + std::to_string(next) + ".exr")).string());
    auto r0 = reference_of(k), r1 = reference_of(next), j0 = lf::read_image(frame_file(dir.string(), k)),
         j1 = lf::read_image(frame_file(dir.string(), next)), s0 = separate_of(k), s1 = separate_of(next);
    if (r0 && r1 && j0 && j1 && s0 && s1) {
      const double t_job = bench::relative_temporal_rmse(*j0, *j1, *r0, *r1);
      const double t_alone = bench::relative_temporal_rmse(*s0, *s1, *r0, *r1);
      const double d_job = bench::relative_rmse(*j1, *r1) - bench::relative_rmse(*j0, *r0);
      const double d_alone = bench::relative_rmse(*s1, *r1) - bench::relative_rmse(*s0, *r0);
      std::printf("flicker, frames %d to %d: temporal error job %.4f, separate runs %.4f (job / separate %.3f); "
                  "change of the error job %+.4f, separate runs %+.4f\n", k, next, t_job, t_alone, t_job / t_alone,
                  d_job, d_alone);
      char entry[240];
      std::snprintf(entry, sizeof entry, "{\"frames\": [%d, %d], \"temporal_job\": %.5f, \"temporal_separate\": %.5f, "
                    "\"error_change_job\": %.5f, \"error_change_separate\": %.5f}", k, next, t_job, t_alone, d_job, d_alone);
      flicker_json = entry;
    }
  }

  const auto ratio = bench::spread(job_over_separate);
  const double per_frame = first > 0 ? later_spread.median / first : 0;
  std::printf("\njob / separate runs: median %.3f (%.3f-%.3f over %d run%s; goal <= 0.4)\nlater frame / first frame: "
              "%.3f (%.3f-%.3f; goal <= 0.5)\n", ratio.median, ratio.min, ratio.max, args.runs, args.runs == 1 ? "" : "s",
              per_frame, first > 0 ? later_spread.min / first : 0, first > 0 ? later_spread.max / first : 0);

  std::ofstream(args.json) << "{\n  \"frames\": " << args.frames << ", \"lighting\": \"" << args.lighting
                           << "\", \"width\": " << args.width << ", \"height\": " << args.height << ", \"spp\": " << args.spp
                           << ",\n  \"job_seconds\": " << job.wall_seconds << ", \"job_cpu_seconds\": " << job.cpu_seconds
                           << ", \"job_idle_share\": " << job_idle << ",\n  \"in_flight_over_one_at_a_time\": {\"median\": "
                           << ratio_spread.median << ", \"min\": " << ratio_spread.min << ", \"max\": " << ratio_spread.max
                           << ", \"runs\": " << args.runs << ", \"one_at_a_time_idle_share\": " << bench::spread(one_idle).median
                           << ", \"in_flight_idle_share\": " << bench::spread(flying_idle).median
                           << ", \"in_flight_render_stage_idle_share\": " << bench::spread(flying_render_idle).median
                           << ", \"one_at_a_time_render_stage_idle_share\": " << bench::spread(one_render_idle).median
                           << ", \"identical_frames\": " << same_frames << "},\n  \"first_frame_seconds\": " << first
                           << ", \"later_frame_seconds\": {\"median\": " << later_spread.median << ", \"min\": "
                           << later_spread.min << ", \"max\": " << later_spread.max << "},\n  \"separate_mean_seconds\": "
                           << mean_separate << ", \"separate_sampled\": " << args.separate
                           << ", \"separate_idle_share\": " << separate_idle << ", \"identical_frames\": " << identical
                           << ",\n  \"job_over_separate\": {\"median\": " << ratio.median << ", \"min\": " << ratio.min
                           << ", \"max\": " << ratio.max << "}, \"later_over_first\": " << per_frame
                           << ", \"resume_all_done_seconds\": " << again.wall_seconds
                           << ", \"resume_half_seconds\": " << half.wall_seconds << ", \"replay_seconds\": " << replay << ", \"restore_seconds\": " << restore
                           << ", \"resumed_identical\": " << resumed_identical
                           << ",\n  \"reference_spp\": " << args.reference_spp << ", \"errors\": [" << errors_json << "]"
                           << (flicker_json.empty() ? "" : ",\n  \"flicker\": " + flicker_json) << "\n}\n";
  bench::fs::remove_all(dir);
  return 0;
}
