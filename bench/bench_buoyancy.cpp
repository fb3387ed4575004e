// Issue 40's buoyancy benchmark: a ball of 5 cm radius settles in a tank of water (demos/buoyancy_tank.hpp,
// the scene of test RigidBodies.ABallOfHalfTheWatersDensityFloatsHalfSubmergedAtTwoSpacings) at one particle
// spacing and one ball density; prints its settled draft as one JSON object on stdout. bench/buoyancy.py runs
// it over spacings and densities and sets the drafts beside Archimedes'.
//
//   build/bench/bench_buoyancy --spacing 0.008 --density 750 --threads 1
//
// Output: spacing_m, density_kg_m3, rest_density_kg_m3, draft (mean over the window, a fraction of the
// ball's height), draft_min and draft_max (its spread over the window), samples, particles, wall_s (the
// whole run, scene set-up included), failed_step and failure (0 and "" when every step was fine). Exit 1
// when a step failed or the options were wrong.

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include <drench/common/parallel.hpp>
#include "../demos/buoyancy_tank.hpp"
#include "../demos/cli_checks.hpp"

namespace {}  // namespace

int main(int argc, char** argv) {
  double spacing = 0.01, density = 500.0;
  int threads = 1;
  std::string solver = "pcisph";
  double dt = buoyancy::kDt;
  CLI::App app{"a ball settling in a tank of water: its draft against Archimedes'"};
  app.add_option("--spacing", spacing, "the water's particle spacing (unit: m)")
      ->check(drench::cli::finite_positive());
  app.add_option("--density", density, "the ball's density (unit: kg/m^3)")
      ->check(drench::cli::finite_positive());
  app.add_option("--solver", solver, "the water's pressure solver")
      ->check(CLI::IsMember({"wcsph", "pcisph", "dfsph", "pbf"}));
  app.add_option("--dt", dt, "the step (unit: s), at most 0.03")->check(CLI::Range(1e-6, 0.03));
  app.add_option("--threads", threads, "threads of drench's loops")
      ->check(CLI::Range(1, drench::kMaxThreadCount));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 1;
  }
  try {
    drench::set_thread_count(threads);
    const auto start = std::chrono::steady_clock::now();
    drench::PressureSolverKind kind = drench::PressureSolverKind::PCISPH;
    for (auto k : {drench::PressureSolverKind::WCSPH, drench::PressureSolverKind::PCISPH,
                   drench::PressureSolverKind::DFSPH, drench::PressureSolverKind::PBF})
      if (solver == drench::pressure_solver_name(k)) kind = k;
    const buoyancy::Draft draft = buoyancy::settled_draft(spacing, density, kind, dt);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const nlohmann::json out = {
        {"spacing_m", spacing},
        {"density_kg_m3", density},
        {"solver", solver},
        {"dt_s", dt},
        {"rest_density_kg_m3", draft.rest_density},
        // NaN is not JSON: a failed run's mean is null.
        {"draft", std::isfinite(draft.mean) ? nlohmann::json(draft.mean) : nlohmann::json()},
        {"draft_min", draft.min},
        {"draft_max", draft.max},
        {"samples", draft.samples},
        {"particles", draft.particles},
        {"threads", threads},
        {"wall_s", wall},
        {"failed_step", draft.failed_step},
        {"failure", draft.failure},
    };
    std::cout << out.dump() << '\n';
    return draft.failure.empty() ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_buoyancy: %s\n", e.what());
    return 1;
  }
}
