// The drench command:
//   drench run SCENE.json --out DIR [--overwrite] [--set json.path=value ...] [--steps N]
//   drench reconstruct DIR [--set json.path=value ...]   the surface again from a run's saved frames
//   drench render DIR [--camera JSON] [--size WxH] [--out DIR] [--water opaque|transparent] [--video]
//                                            a run's frames as PNG (and MP4)
//   drench view SCENE.json [--set ...] [--size WxH] [--frames N --screenshot FILE] [--keys SEQ]   live window
//   drench ccd FILE_OR_DIR... [--list]      point-triangle CCD against labelled queries (*.vf.txt)
//   drench sweep SCENE.json --vary key=v1,v2 ... --out DIR [--overwrite] [--reference REF]   over settings
//   drench reference SCENE.json --out REF [--set ...]   the scene far past its settings, to compare with
// Exit status: 0 success; 1 bad input (scene, file, arguments, an --out folder that is not drench's to
// write), out of memory or another error before the simulation started, or, for `ccd`, a missed collision;
// 2 the simulation became non-finite, blew up or leaked, or failed after it started, or, for `sweep`, a run
// did not end "ok"; 130 (SIGINT) or 143 (SIGTERM): `run`, `reconstruct` or `sweep` was interrupted and
// stopped cleanly (a run's summary.json says "interrupted"; reconstruct left the earlier surfaces).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <new>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/ccd/ccd_query_file.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
#include <drench/common/program.hpp>
#include <drench/io/atomic_file.hpp>
#include <drench/render/render_run.hpp>
#ifdef DRENCH_HAVE_VIEWER
#include <drench/render/viewer.hpp>
#endif
#include <drench/scene/output_folder.hpp>
#include <drench/scene/reconstruct_run.hpp>
#include <drench/scene/run_frames.hpp>
#include <drench/scene/scene_loader.hpp>
#include <drench/scene/scene_resources.hpp>
#include <drench/scene/scene_runner.hpp>
#include <drench/scene/simulation.hpp>

#include "cli_checks.hpp"
#include "stop_signal.hpp"
#include "sweep_command.hpp"

namespace {

using drench::cli::finite_positive;
using drench::cli::non_empty;
using drench::cli::non_negative_number;
using drench::cli::quoted_argument;
using drench::cli::shorten_long_words;
using drench::cli::whole_number;

/// What the command is doing, for the message of an error that carries no context (out of memory).
const char* g_activity = "starting";
/// Whether `drench run` has started simulating: an error then exits 2, else 1.
bool g_simulation_started = false;

/// A summary figure, NaN where summary.json holds null (a non-finite figure, docs/output.md).
double figure(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

/// `drench run`; `final_status`, when given, receives summary.json's "status" ("ok" or the flags raised).
int run_command(const std::string& scene_path, const std::string& out_dir,
                const std::vector<std::string>& overrides, std::int64_t steps, bool quiet, bool overwrite,
                double max_output, std::string* final_status = nullptr) {
  // The folder first, before the scene is read: a run that could not write there is refused at once.
  drench::check_output_folder(out_dir, "--out", "run", drench::run_output_patterns(), overwrite);
  // Everything is validated before the output folder is touched: a bad scene writes nothing.
  g_activity = "reading the scene";
  const nlohmann::json document = drench::read_scene_document(scene_path, overrides);
  const drench::SceneConfig config =
      drench::parse_scene(document, drench::scene_source(scene_path, overrides));
  drench::check_scene_resources(config, out_dir, max_output);
  g_activity = "setting up the simulation";
  drench::Simulation simulation(config, drench::bullet::cloth_engine_factory());
  // The manifest is the folder's first file, so that --overwrite knows later what this run wrote.
  drench::prepare_output_folder(out_dir, "--out", "run", drench::run_output_patterns(), overwrite);

  drench::RunOptions options;
  options.out_dir = out_dir;
  if (steps >= 0) options.max_steps = steps;
  options.scene_sha256 = drench::sha256_hex(drench::canonical_scene_text(document));
  options.scene_document = document;
  options.progress = !quiet;
  if (!quiet) {
    if (config.time.adaptive) {
      std::fprintf(stderr, "drench %s: %s, %zu particles, %g s in steps of %g to %g s, %d threads\n",
                   DRENCH_VERSION, scene_path.c_str(), simulation.particles().size(), config.time.duration,
                   config.time.dt_min, config.time.dt, drench::thread_count());
    } else {
      std::fprintf(stderr, "drench %s: %s, %zu particles, %lld steps of %g s, %d threads\n", DRENCH_VERSION,
                   scene_path.c_str(), simulation.particles().size(),
                   static_cast<long long>(options.max_steps.value_or(simulation.total_steps())),
                   config.time.dt, drench::thread_count());
    }
  }
  options.stop = &drench::stop_requested();
  drench::install_stop_handler(true);
  g_activity = "simulating";
  g_simulation_started = true;
  const drench::RunResult result = drench::run_scene(simulation, options);
  const auto& s = result.summary;
  if (final_status) *final_status = s["status"].get<std::string>();
  std::printf(
      "%lld steps, %g s simulated in %.2f s wall; %lld particles (%lld removed); density error mean "
      "%.3g%% max %.3g%%; %lld frames in %s\n",
      s["steps"].get<long long>(), figure(s["sim_time_s"]), figure(s["wall_s"]),
      s["particles"].get<long long>(), s["removed"].get<long long>(),
      100 * figure(s["density_error"]["mean"]), 100 * figure(s["density_error"]["max"]),
      s["frames"].get<long long>(), out_dir.c_str());
  if (s.contains("contacts")) {
    std::printf("coupling: %lld contacts, %lld sub-step stops, %lld CCD impacts, %lld fail-safe",
                s["contacts"].get<long long>(), s["obstacle_stops"].get<long long>(),
                s["ccd_impacts"].get<long long>(), s["failsafe_activations"].get<long long>());
    if (s.contains("leaks")) std::printf(", %lld leaks", s["leaks"].get<long long>());
    std::printf("\n");
  }
  if (!result.status.ok()) {
    std::fprintf(stderr, "drench: simulation stopped: %s\n", result.status.describe().c_str());
    return 2;
  }
  if (result.interrupted) {
    std::fprintf(stderr,
                 "drench: interrupted by signal %d after step %lld; summary.json says \"interrupted\"\n",
                 drench::stop_signal(), s["steps"].get<long long>());
    return drench::stopped_exit_status();
  }
  if (result.status.failed()) {
    std::fprintf(stderr, "drench: simulation failed: %s\n", result.status.describe().c_str());
    return 2;
  }
  return 0;
}

/// `drench reference`: the scene run with reference_overrides() on top of the user's, then reference.json
/// beside its files (docs/output.md), written only when the run ended "ok": a reference that blew up or
/// leaked is none.
int reference_command(const std::string& scene_path, const std::string& out_dir,
                      const std::vector<std::string>& overrides,
                      const drench::ReferenceRefinement& refinement, bool quiet, bool overwrite,
                      double max_output, const std::string& command_line) {
  drench::check_output_folder(out_dir, "--out", "run", drench::run_output_patterns(), overwrite);
  g_activity = "reading the scene";
  const nlohmann::json scene = drench::read_scene_document(scene_path, overrides);
  drench::parse_scene(scene, drench::scene_source(scene_path, overrides));
  const std::vector<std::string> refined = drench::reference_overrides(scene, refinement);
  std::vector<std::string> all = overrides;
  all.insert(all.end(), refined.begin(), refined.end());
  if (!quiet) {
    std::string list;
    for (const std::string& assignment : refined)
      list += " --set " + assignment;
    std::fprintf(stderr, "drench reference: the scene with%s\n", list.c_str());
  }
  std::string run_status;
  const int status = run_command(scene_path, out_dir, all, -1, quiet, overwrite, max_output, &run_status);
  // A warning that ends a plain run with exit 0 (a pressure solve that stopped at its iteration limit) still
  // means the refined run is not the converged answer a reference must be.
  if (status != 0 || run_status != "ok") {
    std::fprintf(stderr, "drench: reference: the run did not end \"ok\", so %s has no reference.json%s\n",
                 out_dir.c_str(),
                 status == 0 ? (" (" + run_status +
                                "); a reference must converge: lower --eta-divisor or raise the pressure "
                                "solver's max_iterations")
                                   .c_str()
                             : "");
    return status != 0 ? status : 2;
  }
  nlohmann::json record;
  record["command"] = command_line;
  record["scene"] = scene_path;
  record["overrides"] = overrides;
  // What a sweep of the same scene and --set's hashes: `drench sweep --reference` checks it.
  record["scene_sha256"] = drench::sha256_hex(drench::canonical_scene_text(scene));
  record["refinement"] = {{"dt_divisor", refinement.dt_divisor},
                          {"eta_divisor", refinement.eta_divisor},
                          {"cloth_substeps_factor", refinement.cloth_substeps_factor},
                          {"double_precision", refinement.double_precision}};
  record["reference_overrides"] = refined;
  nlohmann::json effective = scene;
  for (const std::string& assignment : refined)
    drench::apply_override(effective, assignment);
  record["run_scene_sha256"] = drench::sha256_hex(drench::canonical_scene_text(effective));
  record["version"] = DRENCH_VERSION;
  drench::write_file_atomic((std::filesystem::path(out_dir) / "reference.json").string(),
                            record.dump(2) + "\n");
  std::printf("reference: %s/reference.json\n", out_dir.c_str());
  return 0;
}

int reconstruct_command(const std::string& run_dir, const std::vector<std::string>& overrides, bool quiet) {
  drench::ReconstructOptions options;
  options.run_dir = run_dir;
  options.overrides = overrides;
  options.progress = !quiet;
  options.stop = &drench::stop_requested();
  drench::install_stop_handler(true);
  g_activity = "reconstructing the surfaces";
  const drench::ReconstructResult result = drench::reconstruct_run(options);
  if (result.interrupted) {
    std::fprintf(stderr,
                 "drench: interrupted by signal %d; the earlier surfaces and reconstruct.json in %s are "
                 "untouched\n",
                 drench::stop_signal(), run_dir.c_str());
    return drench::stopped_exit_status();
  }
  std::printf(
      "%lld frames reconstructed in %.2f s: %llu surface triangles, %llu crossings of the cloth and "
      "obstacles; surface_NNNN.ply and reconstruct.json in %s\n",
      static_cast<long long>(result.frames), result.wall_seconds,
      static_cast<unsigned long long>(result.surface_triangles),
      static_cast<unsigned long long>(result.surface_intersections), run_dir.c_str());
  return 0;
}

int render_command(drench::render::RenderOptions options, const std::string& size, const std::string& water,
                   bool quiet) {
  g_activity = "rendering";
  drench::render::parse_image_size(size, options.width, options.height);
  options.water.shading = drench::render::parse_water_shading(water);
  options.progress = !quiet;
  // Said before the frames are drawn, so that nobody waits minutes for a video that will not come.
  if (options.video && drench::find_program("ffmpeg").empty())
    std::fprintf(
        stderr,
        "drench: --video: ffmpeg is not installed (Debian: sudo apt-get install ffmpeg); drawing the "
        "PNGs only\n");
  const drench::render::RenderResult r = drench::render::render_run(options);
  const double frames = static_cast<double>(std::max<std::int64_t>(r.frames, 1));
  std::printf(
      "%lld frames rendered at %dx%d in %.2f s: %.3f s a frame (draw %.3f, PNG %.3f, read %.3f); "
      "frame_NNNN.png in %s\n",
      static_cast<long long>(r.frames), options.width, options.height, r.wall_seconds,
      r.wall_seconds / frames, r.draw_seconds / frames, r.write_seconds / frames, r.read_seconds / frames,
      r.out_dir.c_str());
  if (!quiet) {
    const auto& c = r.camera;
    std::printf(
        "camera: {\"position\": [%.4g, %.4g, %.4g], \"target\": [%.4g, %.4g, %.4g], \"fov_deg\": %g}; %s\n",
        c.position.x(), c.position.y(), c.position.z(), c.target.x(), c.target.y(), c.target.z(), c.fov_deg,
        r.gl.c_str());
  }
  if (!r.video_path.empty()) std::printf("video: %s (%.2f s)\n", r.video_path.c_str(), r.video_seconds);
  if (!r.video_note.empty()) std::fprintf(stderr, "drench: --video: %s\n", r.video_note.c_str());
  if (!r.water_note.empty()) std::fprintf(stderr, "drench: --water transparent: %s\n", r.water_note.c_str());
  return 0;
}

int view_command(const std::string& scene_path, const std::vector<std::string>& overrides,
                 const std::string& size, std::int64_t frames, const std::string& screenshot,
                 const std::string& keys) {
#ifdef DRENCH_HAVE_VIEWER
  drench::render::ViewOptions options;
  drench::render::parse_image_size(size, options.width, options.height);
  options.frames = frames;
  options.screenshot = screenshot;
  options.keys = keys;
  drench::render::check_view_options(options);
  const nlohmann::json document = drench::read_scene_document(scene_path, overrides);
  options.config = drench::parse_scene(document, drench::scene_source(scene_path, overrides));
  drench::check_scene_resources(options.config, "", 0.0);  // memory only: the viewer writes no frames
  options.has_surface = document.contains("surface") || options.config.has_effect("surface");
  options.cloth_factory = drench::bullet::cloth_engine_factory();
  const drench::render::ViewResult r = drench::render::run_viewer(options);
  const double frames_drawn = static_cast<double>(std::max<std::int64_t>(r.frames, 1));
  std::printf(
      "view: %lld frames in %.1f s (%.1f fps; draw %.1f ms a frame); %lld steps in %.1f s of stepping (%.1f "
      "steps/s); %s\n",
      static_cast<long long>(r.frames), r.seconds, r.frames / std::max(r.seconds, 1e-9),
      1e3 * r.draw_seconds / frames_drawn, static_cast<long long>(r.steps), r.stepping_seconds,
      r.steps / std::max(r.stepping_seconds, 1e-9), r.gl.c_str());
  if (r.surface_seconds > 0) std::printf("surface: the last reconstruction took %.3f s\n", r.surface_seconds);
  if (!r.screenshot.empty()) std::printf("screenshot: %s\n", r.screenshot.c_str());
  return 0;
#else
  (void)scene_path, (void)overrides, (void)size, (void)frames, (void)screenshot, (void)keys;
  throw drench::Error(
      "drench view was not built: GLFW was not found when drench was configured (Debian: libglfw3-dev; "
      "scripts/setup installs it); configure again, or use drench render for images");
#endif
}

/// One query file of `drench ccd`, with the figures of one pass of the solver over it.
struct CcdFileRun {
  std::string name;  ///< relative to the directory argument it was found in, else as given
  std::vector<drench::ccd::CcdBenchmarkQuery> queries;
  std::size_t false_negatives = 0, false_positives = 0, exact = 0;
  double seconds = 0.0;             ///< wall time of the solver loop alone (unit: s)
  std::vector<std::string> listed;  ///< `--list` lines: misses and false positives
};

/// Runs point_triangle_ccd over every query of `run` and fills in its figures.
void run_ccd_file(CcdFileRun& run) {
  using drench::ccd::CcdResult;
  std::vector<CcdResult> results(run.queries.size());
  // Only the solver is timed: parsing and bookkeeping stay outside, as in bench/bench_ccd.cpp.
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < run.queries.size(); ++i)
    results[i] = drench::ccd::point_triangle_ccd(run.queries[i].query);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  for (std::size_t i = 0; i < results.size(); ++i) {
    const drench::ccd::CcdBenchmarkQuery& q = run.queries[i];
    if (results[i].path == drench::ccd::CcdPath::EXACT) ++run.exact;
    if (q.collides && !results[i].hit) {
      ++run.false_negatives;
      run.listed.push_back("missed " + run.name + " " + q.id);
    } else if (!q.collides && results[i].hit) {
      ++run.false_positives;
      run.listed.push_back("false-positive " + run.name + " " + q.id);
    }
  }
}

void print_ccd_row(int name_width, const std::string& name, std::size_t queries, std::size_t false_negatives,
                   std::size_t false_positives, std::size_t exact, double seconds) {
  char us_per_query[32] = "-";
  if (queries > 0) std::snprintf(us_per_query, sizeof us_per_query, "%.3f", 1e6 * seconds / queries);
  std::printf("%-*s %8zu %9zu %9zu %8zu %10s\n", name_width, name.c_str(), queries, false_negatives,
              false_positives, exact, us_per_query);
}

int ccd_command(const std::vector<std::string>& paths, bool list) {
  namespace fs = std::filesystem;
  // Every file is read before the solver runs, so a bad file is reported before any figure is printed.
  std::vector<CcdFileRun> runs;
  for (const std::string& argument : paths) {
    std::error_code error;
    const bool directory = fs::is_directory(argument, error);
    for (const std::string& file : drench::ccd::list_ccd_query_files(argument)) {
      CcdFileRun run;
      run.name = directory ? fs::path(file).lexically_relative(argument).generic_string() : file;
      run.queries = drench::ccd::read_ccd_query_file(file);
      runs.push_back(std::move(run));
    }
  }
  for (CcdFileRun& run : runs)
    run_ccd_file(run);

  int name_width = 5;  // "total"
  for (const CcdFileRun& run : runs)
    name_width = std::max(name_width, static_cast<int>(run.name.size()));
  std::printf("%-*s %8s %9s %9s %8s %10s\n", name_width, "file", "queries", "false-neg", "false-pos", "exact",
              "us/query");
  std::size_t queries = 0, positives = 0, false_negatives = 0, false_positives = 0, exact = 0;
  double seconds = 0.0;
  for (const CcdFileRun& run : runs) {
    print_ccd_row(name_width, run.name, run.queries.size(), run.false_negatives, run.false_positives,
                  run.exact, run.seconds);
    queries += run.queries.size();
    for (const auto& q : run.queries)
      positives += q.collides ? 1 : 0;
    false_negatives += run.false_negatives;
    false_positives += run.false_positives;
    exact += run.exact;
    seconds += run.seconds;
  }
  // The total's time per query weighs files by their query count, as one run over all queries would.
  print_ccd_row(name_width, "total", queries, false_negatives, false_positives, exact, seconds);
  if (list) {
    for (const CcdFileRun& run : runs) {
      for (const std::string& line : run.listed)
        std::printf("%s\n", line.c_str());
    }
  }
  if (false_negatives > 0) {
    std::fprintf(stderr, "drench: %zu of %zu collisions missed\n", false_negatives, positives);
    return 1;
  }
  return 0;
}

/// `message` on one line: an error from a library (OpenVDB, the standard library) may span several.
std::string one_line(std::string message) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  return message;
}

constexpr unsigned long long kMaxCount = std::numeric_limits<std::int64_t>::max();
constexpr unsigned long long kMaxThreads = 1024;

int dispatch(int argc, char** argv);

}  // namespace

// Every error ends as one line and an exit status, never as an abort: drench's own errors (bad input, 1),
// running out of memory and errors from other libraries (1 before the simulation started, 2 after).
int main(int argc, char** argv) {
  try {
    return dispatch(argc, argv);
  } catch (const drench::Error& e) {
    std::fprintf(stderr, "drench: %s\n", one_line(e.what()).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "drench: out of memory while %s; try a smaller scene (fewer particles or cloth nodes)\n",
                 g_activity);
    return g_simulation_started ? 2 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "drench: error while %s: %s\n", g_activity, one_line(e.what()).c_str());
    return g_simulation_started ? 2 : 1;
  } catch (...) {
    std::fprintf(stderr, "drench: unknown error while %s\n", g_activity);
    return g_simulation_started ? 2 : 1;
  }
}

namespace {

int dispatch(int argc, char** argv) {
  CLI::App app{"drench: SPH fluid with two-way cloth contact (Huber, Eberhardt & Weiskopf 2013)"};
  app.set_version_flag("--version", DRENCH_VERSION);
  app.require_subcommand(1);

  std::string scene_path, out_dir;
  std::vector<std::string> overrides;
  std::int64_t steps = -1;
  int threads = 0;
  bool quiet = false, overwrite = false;
  CLI::App* run = app.add_subcommand("run", "simulate a scene, writing frames and summary.json");
  run->add_option("scene", scene_path, "scene file (JSON, SI units; see docs/scenes.md)")->required();
  run->add_option("--out", out_dir, "output folder (frames/, summary.json)")->required();
  run->add_option("--set", overrides, "override a scene value, e.g. --set time.dt=0.004 (repeatable)");
  run->add_option("--steps", steps, "stop after N steps")->check(whole_number(0, kMaxCount));
  run->add_option("--threads", threads,
                  "threads (default: OMP_NUM_THREADS, else the CPUs this process may use)")
      ->check(whole_number(1, kMaxThreads));
  run->add_flag("--overwrite", overwrite,
                "replace an earlier drench run in --out (only the files its drench_run.json lists)");
  run->add_flag("--quiet", quiet, "no banner and no progress line");
  double max_output = drench::kDefaultMaxOutputBytes;
  run->add_option("--max-output", max_output,
                  "refuse a scene whose frames would exceed BYTES (default 10 GiB)")
      ->check(finite_positive());

  std::string reconstruct_dir;
  CLI::App* reconstruct = app.add_subcommand(
      "reconstruct",
      "reconstruct the fluid's surface again from a run's saved frames (frames/surface_NNNN.ply)");
  reconstruct->add_option("dir", reconstruct_dir, "the --out folder of a drench run (scene.json, frames/)")
      ->required();
  reconstruct->add_option(
      "--set", overrides,
      "override a value of the run's scene, e.g. --set surface.cell_size=0.004 (repeatable)");
  reconstruct
      ->add_option("--threads", threads,
                   "threads (default: OMP_NUM_THREADS, else the CPUs this process may use)")
      ->check(whole_number(1, kMaxThreads));
  reconstruct->add_flag("--quiet", quiet, "no progress line");

  drench::render::RenderOptions render_options;
  std::string render_size = "1280x720", render_water = "opaque";
  CLI::App* render = app.add_subcommand(
      "render", "draw a run's frames as PNG images, headless (render/frame_NNNN.png), and optionally an MP4");
  render->add_option("dir", render_options.run_dir, "the --out folder of a drench run (scene.json, frames/)")
      ->required();
  render
      ->add_option("--camera", render_options.camera_json,
                   "camera as JSON, replacing the scene's `camera` key, e.g. "
                   "'{\"position\": [0, 0.4, 1.2], \"target\": [0, 0, 0], \"fov_deg\": 45}'")
      ->check(non_empty());
  render->add_option("--size", render_size, "image size WIDTHxHEIGHT in pixels")->capture_default_str();
  render->add_option("--out", render_options.out_dir, "folder of the images (default: DIR/render)")
      ->check(non_empty());
  render
      ->add_option("--water", render_water,
                   "the fluid's surface: opaque (blue) or transparent (water: reflection, refraction, "
                   "absorption; the cloth seen through it)")
      ->capture_default_str();
  render->add_flag("--overwrite", render_options.overwrite,
                   "replace an earlier drench render in --out (only the files its drench_run.json lists)");
  render->add_flag("--video", render_options.video,
                   "also write video.mp4 through ffmpeg, when it is installed");
  render->add_flag("--quiet", quiet, "no progress line and no camera line");

  std::string view_size = "1280x720", view_screenshot, view_keys;
  std::int64_t view_frames = 0;
  CLI::App* view = app.add_subcommand(
      "view", "run a scene live in a window: orbit, pan and zoom, pause, step, restart (docs/viewer.md)");
  view->add_option("scene", scene_path, "scene file (JSON, SI units; see docs/scenes.md)")->required();
  view->add_option("--set", overrides, "override a scene value, e.g. --set time.dt=0.004 (repeatable)");
  view->add_option("--threads", threads,
                   "threads of the simulation (default: OMP_NUM_THREADS, else the CPUs this process may use)")
      ->check(whole_number(1, kMaxThreads));
  view->add_option("--size", view_size, "window size WIDTHxHEIGHT in pixels")->capture_default_str();
  view->add_option("--frames", view_frames, "quit after N drawn frames")->check(whole_number(0, kMaxCount));
  view->add_option("--screenshot", view_screenshot, "with --frames: write the last frame as PNG to FILE");
  view->add_option("--keys", view_keys,
                   "keys to press, one per frame from the first, e.g. ' . . p p' (space pauses, . steps)");

  std::vector<std::string> ccd_paths;
  bool ccd_list = false;
  CLI::App* ccd = app.add_subcommand(
      "ccd",
      "check the point-triangle CCD against labelled queries: misses, false positives, time per query");
  ccd->add_option("paths", ccd_paths, "query files (*.vf.txt) or folders searched for them recursively")
      ->required();
  ccd->add_flag("--list", ccd_list, "also print the ids of missed collisions and false positives");

  drench::ReferenceRefinement refinement;
  CLI::App* reference = app.add_subcommand(
      "reference",
      "run a scene far past its settings (dt / 8, eta / 10, 4x cloth sub-steps, double sums) as the answer "
      "`drench sweep --reference` measures errors against; reference.json in --out");
  reference->add_option("scene", scene_path, "scene file (JSON, SI units; see docs/scenes.md)")->required();
  reference->add_option("--out", out_dir, "output folder (frames/, summary.json, reference.json)")
      ->required();
  reference->add_option("--set", overrides, "override a scene value before it is refined (repeatable)");
  reference
      ->add_option("--threads", threads,
                   "threads (default: OMP_NUM_THREADS, else the CPUs this process may use)")
      ->check(whole_number(1, kMaxThreads));
  reference->add_option("--dt-divisor", refinement.dt_divisor, "time.dt divided by this")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  reference->add_option("--eta-divisor", refinement.eta_divisor, "PCISPH's and DFSPH's eta divided by this")
      ->check(CLI::Range(1.0, 1e6))
      ->capture_default_str();
  reference
      ->add_option("--substeps-factor", refinement.cloth_substeps_factor, "cloth.substeps multiplied by this")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  reference->add_flag("--overwrite", overwrite,
                      "replace an earlier drench run in --out (only the files its drench_run.json lists)");
  reference->add_flag("--quiet", quiet, "no banner and no progress line");

  drench::SweepOptions sweep_options;
  std::vector<std::string> vary, cases;
  CLI::App* sweep = app.add_subcommand(
      "sweep", "run a scene over settings (each a drench run): sweep.csv, report.md and pareto.png in --out");
  sweep->add_option("scene", sweep_options.scene_path, "scene file (JSON)")->required();
  sweep->add_option("--out", sweep_options.out_dir, "output folder (runs/NNN/, sweep.csv, report.md)")
      ->required();
  sweep->add_option(
      "--vary", vary,
      "a setting and its values, e.g. --vary time.dt=0.001,0.002,0.004 (repeatable; values split at "
      "commas outside JSON brackets and quotes)");
  sweep->add_option("--case", cases,
                    "settings that go together as one, e.g. --case 'no-slip:coupling.slip=\"no_slip\";"
                    "effects=[...]' (repeatable)");
  sweep->add_flag("--one-at-a-time", sweep_options.one_at_a_time,
                  "vary each setting alone around the scene's values instead of running the grid");
  sweep->add_option("--repeat", sweep_options.repeats, "runs of each setting")
      ->check(whole_number(1, std::numeric_limits<int>::max()))
      ->capture_default_str();
  sweep->add_option("--jobs", sweep_options.jobs, "runs side by side (their times then share the cores)")
      ->check(whole_number(1, kMaxThreads))
      ->capture_default_str();
  sweep
      ->add_option("--threads", sweep_options.threads,
                   "threads per run (default: OMP_NUM_THREADS, else the CPUs this process may use, / jobs)")
      ->check(whole_number(1, kMaxThreads));
  sweep
      ->add_option("--timeout", sweep_options.timeout_s,
                   "stop a run after this many seconds of wall time; its row says so (default: no limit)")
      ->check(non_negative_number());
  sweep
      ->add_option("--speed-bound", sweep_options.speed_bound_mps,
                   "the scene's speed bound (m/s): a run whose fastest particle or node went faster is drawn "
                   "apart and never on the Pareto front (default: none)")
      ->check(finite_positive());
  sweep->add_option(
      "--error", sweep_options.error_key,
      "the sweep.csv column pareto.png plots against wall time (default: density_error_mean; with "
      "--reference cloth_rms_m, or front_m without a cloth)");
  sweep
      ->add_option("--reference", sweep_options.reference_dir,
                   "a `drench reference` folder: each run's frames are compared with it (docs/output.md)")
      ->check(non_empty());
  sweep->add_option("--gauge", sweep_options.comparison.gauges_x,
                    "with --reference: x of a water-height gauge (m, repeatable), e.g. for the dam break");
  sweep
      ->add_option(
          "--gauge-width", sweep_options.comparison.gauge_width,
          "with --gauge: width in x of a gauge's column (m; default: the reference's particle spacing)")
      ->check(finite_positive());
  sweep
      ->add_option("--gauge-depth", sweep_options.comparison.gauge_depth,
                   "with --gauge: depth in z of the channel a gauge's column spans (m; default: the z extent "
                   "of the reference's first frame's water plus one spacing)")
      ->check(finite_positive());
  sweep
      ->add_option("--cell-size", sweep_options.comparison.cell_size,
                   "with --reference: edge of the mass grid's cells (m; default: four of the reference's "
                   "particle spacings)")
      ->check(finite_positive());
  sweep->add_option("--set", sweep_options.overrides, "override a scene value in every run (repeatable)");
  sweep->add_flag("--overwrite", sweep_options.overwrite,
                  "replace an earlier sweep in --out (only the files its drench_run.json lists)");
  sweep->add_flag("--quiet", sweep_options.quiet, "no line per finished run");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" that exit 0 and print as CLI11 prints them.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    // Every other mistake on the command line is bad input: exit 1, as documented, not CLI11's own codes.
    std::fprintf(stderr, "drench: %s\nRun with --help for more information.\n",
                 shorten_long_words(one_line(e.what())).c_str());
    return 1;
  }
  if (threads > 0) {
    drench::set_thread_count(threads);
  } else if (const std::string problem = drench::omp_num_threads_problem(); !problem.empty()) {
    // The library would use every CPU instead, without a word.
    std::fprintf(stderr, "drench: %s: unset it or pass --threads N\n", problem.c_str());
    return 1;
  }
  {
    if (run->parsed())
      return run_command(scene_path, out_dir, overrides, steps, quiet, overwrite, max_output);
    if (reconstruct->parsed()) return reconstruct_command(reconstruct_dir, overrides, quiet);
    if (render->parsed()) return render_command(render_options, render_size, render_water, quiet);
    if (view->parsed())
      return view_command(scene_path, overrides, view_size, view_frames, view_screenshot, view_keys);
    if (ccd->parsed()) return ccd_command(ccd_paths, ccd_list);
    if (reference->parsed()) {
      std::string command_line;
      for (int i = 0; i < argc; ++i)
        command_line += (i ? " " : "drench") + (i ? std::string(argv[i]) : std::string());
      return reference_command(scene_path, out_dir, overrides, refinement, quiet, overwrite, max_output,
                               command_line);
    }
    if (sweep->parsed()) {
      for (const std::string& argument : vary)
        sweep_options.axes.push_back(drench::parse_sweep_axis(argument));
      for (const std::string& argument : cases)
        sweep_options.cases.push_back(drench::parse_sweep_case(argument));
      std::error_code error;
      sweep_options.program = std::filesystem::read_symlink("/proc/self/exe", error).string();
      if (error) sweep_options.program = argv[0];
      for (int i = 0; i < argc; ++i)
        sweep_options.command_line += (i ? " " : "drench") + (i ? std::string(argv[i]) : std::string());
      g_activity = "sweeping";
      const int failed = drench::run_sweep(sweep_options);
      std::printf("sweep: %s/sweep.csv, report.md and pareto.png; %d run(s) not ok\n",
                  sweep_options.out_dir.c_str(), failed);
      if (drench::stop_signal() != 0) {
        std::fprintf(stderr, "drench: sweep interrupted by signal %d; its rows so far are in sweep.csv\n",
                     drench::stop_signal());
        return drench::stopped_exit_status();
      }
      return failed > 0 ? 2 : 0;
    }
  }
  return 0;
}

}  // namespace
