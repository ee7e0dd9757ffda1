// The lighting network at its default settings against the path tracer, on every scene the project has and on
// variants nobody tuned for: how long the network takes to reach the 256-spp path tracer's error, as a fraction of
// the path tracer's time. Goal: at most 1/3, with no setting but the image's samples (the quality knob) changed.
//
// Scenes: Lost Empire as examples/lost_empire.lua sets it up; Lost Empire with its main blocks given a glossy lobe
// from the script, and given glTF's metal-roughness model as exporters write it (a dielectric under a rough coat);
// Blender's glTF material-ball grid under an HDRI (without its sun) by examples/material_balls.lua's network and
// path tracer; McGuire's CornellBox-Glossy with the light quad of tests/bias_matrix.hpp, and with its walls
// glossy too; McGuire's other boxes as their files give them (original, glossy floor, mirror, sphere, water and
// the four empty ones); the built-in Cornell box. The network is examples/lost_empire.lua's (`lighting = "network"`), with
// each scene's lines swapped in as bias_matrix.hpp swaps them; the path tracer is examples/pathtrace.lua's (Lost
// Empire: its own script's `lighting = "pathtrace"`). Each is rendered at a low and a high sample count; the
// network's time to the path tracer's 256-spp error is read off the line through its two points in log-log (error
// against time), so it is not a point the bench happened to render.
//
// Each scene is rendered at the exposure its example shows it at (Lost Empire 2, the Cornell boxes 0), the same for
// both methods: it is the scale of adaptive sampling's threshold, which is on by default.
//
// Relative RMSE over the average of the channels, relative to the reference's mean, leaving out the pixels that
// see the light (bench/image_error.hpp). References: pathtrace at --reference-spp, kept in --cache between runs.
// Every render is deterministic (fixed seeds), so --runs repeats them for their times only: a point's time is the
// median over the runs, its spread the min and max.
//
// --network-set k=v (repeatable) adds a script setting to the network's runs: what a setting would do against the
// defaults, with the same references and path-tracer points.
//
//   build/bench/defaults_bench [--runs N] [--reference-spp N] [--scenes a,b] [--cache DIR] [--json FILE]
//                              [--network-set k=v ...]
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "bench/bench_util.hpp"
#include "bench/image_error.hpp"
#include "tests/bias_matrix.hpp"

namespace {

struct Args {
  int runs = 1;
  int reference_spp = 2048;
  std::string only;  // ",a,b," or empty for all
  std::string cache = (bench::fs::temp_directory_path() / "lightfarm-defaults-references").string();
  std::string json = "bench-defaults.json";
  std::vector<std::string> network_sets;  // --network-set k=v: a setting tried against the defaults, on every scene
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--runs") a.runs = std::max(1, std::atoi(argv[i + 1]));
    else if (k == "--reference-spp") a.reference_spp = std::atoi(argv[i + 1]);
    else if (k == "--scenes") a.only = "," + std::string(argv[i + 1]) + ",";
    else if (k == "--cache") a.cache = argv[i + 1];
    else if (k == "--json") a.json = argv[i + 1];
    else if (k == "--network-set") a.network_sets.push_back(argv[i + 1]);
  }
  return a;
}

// A scene: the network's and the path tracer's scripts, and what they are run with besides the sample count.
struct Case {
  std::string name;
  std::string network_script, pathtrace_script;
  std::vector<std::string> network_sets, pathtrace_sets;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<Case> cases(const std::string& src, const std::string& pid) {
  std::vector<Case> out;
  const std::string lost_empire = bench::shared_scene("lost_empire/lost_empire.obj");
  const std::string mcguire = bench::shared_scene("cornell_box_mcguire/");
  if (!lost_empire.empty()) {
    // The example with its scene path made absolute, so the script runs from a temporary folder.
    std::string text = read_file(src + "/examples/lost_empire.lua");
    const std::string relative = "../../shared/scenes/lost_empire/lost_empire.obj";
    text.replace(text.find(relative), relative.size(), lost_empire);
    // The example's own exposure (2), which is adaptive sampling's scale (display white) for both.
    const std::vector<std::string> network{"lighting=network"}, pathtrace{"lighting=pathtrace"};
    const std::string plain = bench::temp_script(pid + "lost_empire.lua", text);
    out.push_back({"lost_empire", plain, plain, network, pathtrace});
    // The blocks most of the view is made of, with the Phong lobe an exporter gives every material (not Sand,
    // whose Kd leaves no room for it).
    std::string glossy = text;
    const std::string after = "camera   {";
    std::string lobes;
    for (const char* m : {"Stone", "Grass", "Dirt", "Cobblestone", "Wooden_Plank", "Gravel", "Log"})
      lobes += std::string("material \"") + m + "\" { type = \"glossy\", ks = {0.2, 0.2, 0.2}, ns = 40 }\n";
    glossy.insert(glossy.find(after), lobes);
    const std::string shiny = bench::temp_script(pid + "lost_empire_glossy.lua", glossy);
    out.push_back({"lost_empire_glossy", shiny, shiny, network, pathtrace});
    // The same blocks as a glTF exporter writes every material: metal-roughness, a dielectric under a rough coat.
    std::string coated = text;
    std::string bases;
    for (const char* m : {"Stone", "Grass", "Dirt", "Cobblestone", "Wooden_Plank", "Gravel", "Log", "Sand"})
      bases += std::string("material \"") + m + "\" { metallic = 0, roughness = 0.6 }\n";
    coated.insert(coated.find(after), bases);
    const std::string metal_rough = bench::temp_script(pid + "lost_empire_metal_rough.lua", coated);
    out.push_back({"lost_empire_metal_rough", metal_rough, metal_rough, network, pathtrace});
  }
  // Blender's glTF material-ball grid under an HDRI, by examples/material_balls.lua's own network and path tracer;
  // without the file's sun, whose sub-degree glints on the smooth balls and their caustics on the floor are rare
  // samples of thousands of times a pixel's value (one such pixel made a single render's error 0.06 or 0.79).
  if (const std::string balls = bench::shared_scene("gltf/balls.glb"); !balls.empty()) {
    // The example's paths (the file and the HDRI folder) made absolute.
    std::string text = read_file(src + "/examples/material_balls.lua");
    const std::string relative = "../../shared/scenes/gltf/", absolute = balls.substr(0, balls.size() - 9);
    for (size_t at = text.find(relative); at != std::string::npos; at = text.find(relative, at + absolute.size()))
      text.replace(at, relative.size(), absolute);
    const std::string script = bench::temp_script(pid + "material_balls.lua", text);
    out.push_back({"material_balls", script, script, {"lighting=network", "sun=0", "width=320", "height=180"},
                   {"lighting=pathtrace", "sun=0", "width=320", "height=180"}});
  }
  if (!mcguire.empty()) {
    std::vector<lf::bias::Scene> boxes;
    for (const lf::bias::Scene& s : lf::bias::scenes(mcguire)) {
      const std::string name = s.name;
      if (name == "glossy" || name == "glossy_walls" || name == "cornell") boxes.push_back(s);
    }
    // McGuire's other boxes as their files give them (each MTL has its own emitting light), seen as the glossy one.
    static const std::vector<std::pair<const char*, const char*>> files{
        {"cornellbox_original", "CornellBox-Original"}, {"cornellbox_glossy_floor", "CornellBox-Glossy-Floor"},
        {"cornellbox_mirror", "CornellBox-Mirror"},     {"cornellbox_sphere", "CornellBox-Sphere"},
        {"cornellbox_water", "CornellBox-Water"},       {"cornellbox_empty_co", "CornellBox-Empty-CO"},
        {"cornellbox_empty_rg", "CornellBox-Empty-RG"}, {"cornellbox_empty_squashed", "CornellBox-Empty-Squashed"},
        {"cornellbox_empty_white", "CornellBox-Empty-White"}};
    for (const auto& [name, file] : files) {
      std::string lines = "scene { file = \"" + mcguire + file + ".obj\" }\ncamera { eye = {0, 1, 3.6}, at = {0, 1, 0}, fov = 38 }\n";
      // Its OBJ names CornellBox-Glossy.mtl, which has no light: the glossy box's light quad, as bias_matrix.hpp adds it.
      if (std::string(file) == "CornellBox-Glossy-Floor")
        lines += "light { quad = {{-0.2, 1.57, 0.2}, {-0.2, 1.57, -0.2}, {0.2, 1.57, -0.2}, {0.2, 1.57, 0.2}}, radiance = {17, 12, 4} }\n";
      boxes.push_back({name, lines});
    }
    for (const lf::bias::Scene& s : boxes) {
      const std::string name = s.name;
      const std::string net = lf::bias::with_scene(src + "/examples/lost_empire.lua", s);
      const std::string pt = lf::bias::with_scene(src + "/examples/pathtrace.lua", s);
      const std::string shown = name == "cornell" || name.rfind("cornellbox_", 0) == 0 ? name : "cornellbox_" + name;
      out.push_back({shown, bench::temp_script(pid + shown + "_network.lua", net),
                     bench::temp_script(pid + shown + "_pathtrace.lua", pt),
                     // exposure 0: examples/pathtrace.lua's, where the lost_empire.lua network would be at 2
                     {"lighting=network", "exposure=0", "width=256", "height=256"},
                     {"width=256", "height=256"}});
    }
  }
  return out;
}

struct Point {
  std::string method;
  int spp = 0;
  double seconds = 0;
  bench::Spread spread;
  double rmse = 0;
};

}  // namespace

int main(int argc, char** argv) {
  bench::check_command_line(argc, argv,
                            "build/bench/defaults_bench [--runs N] [--reference-spp N] [--scenes a,b] [--cache DIR]"
                            " [--json FILE] [--network-set k=v ...]",
                            {"--runs", "--reference-spp", "--scenes", "--cache", "--json", "--network-set"});
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // a long run shows its lines as they come, also into a file
  const Args args = parse(argc, argv);
  const std::string src = LIGHTFARM_SOURCE_DIR;
  const std::string pid = std::to_string(::getpid()) + "-";
  bench::fs::create_directories(args.cache);
  const std::string out = (bench::fs::temp_directory_path() / ("lightfarm-defaults-" + pid + "image.exr")).string();
  std::printf("the network at its defaults against pathtrace; reference pathtrace at %d spp; %d run(s)\n\n",
              args.reference_spp, args.runs);
  std::printf("%-20s %-10s %5s %9s %13s %10s\n", "scene", "method", "spp", "seconds", "(min-max)", "rel. RMSE");
  lf::Value::Array rows;
  std::vector<double> ratios;
  for (const Case& c : cases(src, pid)) {
    if (!args.only.empty() && args.only.find("," + c.name + ",") == std::string::npos) continue;
    const std::string ref_path = args.cache + "/" + c.name + "-" + std::to_string(args.reference_spp) + ".exr";
    if (!bench::fs::exists(ref_path)) {
      std::vector<std::string> sets = c.pathtrace_sets;
      sets.push_back("spp=" + std::to_string(args.reference_spp));
      double seconds = 0;
      bench::render_image(c.pathtrace_script, sets, ref_path, seconds);
      std::printf("%-20s reference rendered in %.0f s\n", c.name.c_str(), seconds);
    }
    const auto reference = lf::read_image(ref_path);
    if (!reference) return std::fprintf(stderr, "%s\n", reference.error().message.c_str()), 1;
    std::vector<Point> points;
    for (int spp : {64, 256}) points.push_back({"pathtrace", spp});
    for (int spp : {16, 64}) points.push_back({"network", spp});
    for (Point& p : points) {
      std::vector<std::string> sets = p.method == "network" ? c.network_sets : c.pathtrace_sets;
      if (p.method == "network") sets.insert(sets.end(), args.network_sets.begin(), args.network_sets.end());
      sets.push_back("spp=" + std::to_string(p.spp));
      const std::string& script = p.method == "network" ? c.network_script : c.pathtrace_script;
      std::vector<double> times;
      for (int r = 0; r < args.runs; ++r) {
        double seconds = 0;
        const lf::Image image = bench::render_image(script, sets, out, seconds);
        times.push_back(seconds);
        if (r == 0) p.rmse = bench::relative_rmse(image, *reference);
      }
      p.spread = bench::spread(times);
      p.seconds = p.spread.median;
      std::printf("%-20s %-10s %5d %9.2f %6.2f-%-6.2f %10.4f\n", c.name.c_str(), p.method.c_str(), p.spp, p.seconds,
                  p.spread.min, p.spread.max, p.rmse);
      rows.emplace_back(lf::Value::Map{{"scene", c.name}, {"method", p.method}, {"spp", p.spp}, {"seconds", p.spread.to_value()},
                                       {"rel_rmse", p.rmse}});
    }
    // The network's error against time as a line in log-log through its two points; where it meets the 256-spp
    // path tracer's error.
    const Point &pt = points[1], &lo = points[2], &hi = points[3];
    const double slope = std::log(hi.rmse / lo.rmse) / std::log(hi.seconds / lo.seconds);
    const double t = lo.seconds * std::exp(std::log(pt.rmse / lo.rmse) / slope);
    const double ratio = t / pt.seconds;
    ratios.push_back(ratio);
    std::printf("%-20s the network reaches pathtrace 256 spp's error %.4f in %.2f s: %.2f of its %.2f s (goal <= 0.33)%s\n\n",
                c.name.c_str(), pt.rmse, t, ratio, pt.seconds, slope >= 0 ? " [error does not fall with time: no estimate]" : "");
    rows.emplace_back(lf::Value::Map{{"scene", c.name}, {"time_ratio_to_pathtrace_256", ratio}});
  }
  bench::fs::remove(out);
  std::printf("time ratios: median %.2f, min %.2f, max %.2f (goal <= 0.33 on every scene)\n", bench::median(ratios),
              bench::spread(ratios).min, bench::spread(ratios).max);
  const lf::Value doc = lf::Value::Map{{"reference_spp", args.reference_spp}, {"runs", args.runs}, {"rows", rows}};
  std::ofstream(args.json) << lf::to_json(doc, 2) << "\n";
  std::printf("wrote %s\n", args.json.c_str());
  return 0;
}
