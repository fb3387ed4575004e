// The drench command: `drench run SCENE.json --out DIR [--set json.path=value ...] [--steps N]`.
// Exit status: 0 success; 1 bad input (scene, file, arguments); 2 the simulation became non-finite.

#include <omp.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "scene/scene_loader.hpp"
#include "scene/scene_runner.hpp"
#include "scene/simulation.hpp"

namespace {

int run_command(const std::string& scene_path, const std::string& out_dir,
                const std::vector<std::string>& overrides, std::int64_t steps, bool quiet) {
  // Everything is validated before the output folder is touched: a bad scene writes nothing.
  const nlohmann::json document = drench::read_scene_document(scene_path, overrides);
  const drench::SceneConfig config =
      drench::parse_scene(document, drench::scene_source(scene_path, overrides));
  drench::Simulation simulation(config);

  drench::RunOptions options;
  options.out_dir = out_dir;
  if (steps >= 0) options.max_steps = steps;
  options.scene_sha256 = drench::sha256_hex(drench::canonical_scene_text(document));
  options.progress = !quiet;
  if (!quiet) {
    std::fprintf(stderr, "drench %s: %s, %zu particles, %lld steps of %g s, %d threads\n", DRENCH_VERSION,
                 scene_path.c_str(), simulation.particles().size(),
                 static_cast<long long>(options.max_steps.value_or(simulation.total_steps())), config.time.dt,
                 omp_get_max_threads());
  }
  const drench::RunResult result = drench::run_scene(simulation, options);
  const auto& s = result.summary;
  std::printf(
      "%lld steps, %g s simulated in %.2f s wall; %lld particles (%lld removed); density error mean "
      "%.3g%% max %.3g%%; %lld frames in %s\n",
      s["steps"].get<long long>(), s["sim_time_s"].get<double>(), s["wall_s"].get<double>(),
      s["particles"].get<long long>(), s["removed"].get<long long>(),
      100 * s["density_error"]["mean"].get<double>(), 100 * s["density_error"]["max"].get<double>(),
      s["frames"].get<long long>(), out_dir.c_str());
  if (!result.status.ok()) {
    std::fprintf(stderr, "drench: simulation stopped: %s\n", result.status.describe().c_str());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"drench: SPH fluid with two-way cloth contact (Huber, Eberhardt & Weiskopf 2013)"};
  app.set_version_flag("--version", DRENCH_VERSION);
  app.require_subcommand(1);

  std::string scene_path, out_dir;
  std::vector<std::string> overrides;
  std::int64_t steps = -1;
  int threads = 0;
  bool quiet = false;
  CLI::App* run = app.add_subcommand("run", "simulate a scene, writing frames and summary.json");
  run->add_option("scene", scene_path, "scene file (JSON, SI units; see docs/scenes.md)")->required();
  run->add_option("--out", out_dir, "output folder (frames/, summary.json)")->required();
  run->add_option("--set", overrides, "override a scene value, e.g. --set time.dt=0.004 (repeatable)");
  run->add_option("--steps", steps, "stop after N steps")->check(CLI::NonNegativeNumber);
  run->add_option("--threads", threads, "OpenMP threads (default: all cores)")->check(CLI::PositiveNumber);
  run->add_flag("--quiet", quiet, "no banner and no progress line");

  CLI11_PARSE(app, argc, argv);
  if (threads > 0) omp_set_num_threads(threads);
  try {
    if (run->parsed()) return run_command(scene_path, out_dir, overrides, steps, quiet);
  } catch (const drench::Error& e) {
    std::fprintf(stderr, "drench: %s\n", e.what());
    return 1;
  }
  return 0;
}
