// FluidSolver's fluid.max_speed: a particle over it stops the step before a sub-step, naming the particle,
// where the CFL rule would otherwise cut the step into hundreds of sub-steps for that particle alone. And a
// moving boundary at rest kept (keep_moving_boundary) rather than set again.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>

#include <drench/common/error.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>
#include "../assertions.hpp"

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // m

/// A resting 4 x 4 x 4 block of PCISPH without gravity and, 1 m away, a lone particle (no neighbor, so
/// nothing slows it) moving at `speed` along x (unit: m/s). Returns that particle's id through `id`.
FluidSolver block_and_fast_particle(std::optional<double> max_speed, double speed, std::uint32_t& id) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.max_speed = max_speed;
  FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0);
  BoxEmitterSettings box;
  box.max = Vec3::Constant(4 * kSpacing);
  std::uint32_t next_id = 0;
  const double mass = settings.rest_density * kSpacing * kSpacing * kSpacing;
  emit_box(box, kSpacing, mass, fluid.particles(), next_id);
  id = next_id;
  fluid.particles().add(Vec3::Constant(1.0), Vec3(speed, 0.0, 0.0), mass, next_id++);
  return fluid;
}

TEST(FluidSolver, StopsBeforeASubstepWhenAParticleIsOverMaxSpeedAndNamesIt) {
  std::uint32_t id = 0;
  FluidSolver fluid = block_and_fast_particle(1000.0, 1500.0, id);
  const Vec3Array before = fluid.particles().positions;
  const StepStatus status = fluid.step(1e-3);
  EXPECT_FALSE(status.ok());
  EXPECT_TRUE(status.flags & StepStatus::RUNAWAY_PARTICLE);
  EXPECT_EQ(status.runaway_particle, static_cast<std::int64_t>(id));
  EXPECT_DOUBLE_EQ(status.runaway_speed, 1500.0);
  // No sub-step was taken: nothing moved.
  EXPECT_EQ(fluid.statistics().substeps, 0);
  EXPECT_EQ(fluid.particles().positions, before);
  EXPECT_NE(
      status.describe().find("RUNAWAY_PARTICLE: particle id " + std::to_string(id) + " moved at 1500 m/s"),
      std::string::npos)
      << status.describe();
}

// Below the limit the step is as before: one sub-step the CFL rule allows (cfl 0.4 x 1 cm / 20 m/s = 0.2 ms).
TEST(FluidSolver, AParticleUnderMaxSpeedStepsAsBefore) {
  std::uint32_t id = 0;
  FluidSolver fluid = block_and_fast_particle(1000.0, 20.0, id);
  EXPECT_TRUE(fluid.step(1e-4).ok());
  EXPECT_EQ(fluid.statistics().substeps, 1);
}

// What the limit saves: without it the same particle makes the CFL rule cut a 1 ms step into
// 1 ms / (0.4 x 1 cm / 1500 m/s) = 375 sub-steps (376 where the division rounds up).
TEST(FluidSolver, WithoutMaxSpeedAFastParticleIsSubstepped) {
  std::uint32_t id = 0;
  FluidSolver fluid = block_and_fast_particle(std::nullopt, 1500.0, id);
  EXPECT_TRUE(fluid.step(1e-3).ok());
  EXPECT_GE(fluid.statistics().substeps, 375);
  EXPECT_LE(fluid.statistics().substeps, 376);
}

// An infinite velocity is a non-finite state, reported as such, not a runaway particle.
TEST(FluidSolver, AnInfiniteVelocityIsNonFiniteNotRunaway) {
  std::uint32_t id = 0;
  FluidSolver fluid = block_and_fast_particle(1000.0, std::numeric_limits<double>::infinity(), id);
  const StepStatus status = fluid.step(1e-3);
  EXPECT_TRUE(status.flags & StepStatus::NON_FINITE_STATE);
  EXPECT_FALSE(status.flags & StepStatus::RUNAWAY_PARTICLE);
  EXPECT_EQ(status.non_finite_particle, static_cast<std::int64_t>(id));
}

// A lone particle at 1 m/s with a CFL factor of 1e-12 (in range) has a CFL limit of 1e-14 s: one step of
// 1 ms ends after 2^20 sub-steps of dt / 2^20 (kMaxSubstepHalvings; one more for the rounding of what
// remains), and covers the whole step. When each sub-step was capped at a millionth of what remained of the
// step, this step took 12.5 million.
TEST(FluidSolver, AStepTakesAtMost2To20Substeps) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.cfl = 1e-12;
  FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0);
  const double mass = settings.rest_density * kSpacing * kSpacing * kSpacing;
  fluid.particles().add(Vec3::Zero(), Vec3(1.0, 0.0, 0.0), mass, 0);
  const double dt = 1e-3;
  ASSERT_TRUE(fluid.step(dt).ok());
  EXPECT_LE(fluid.statistics().max_substeps_per_step, (1 << kMaxSubstepHalvings) + 1);
  EXPECT_GE(fluid.statistics().max_substeps_per_step, (1 << kMaxSubstepHalvings) - 1);
  // No force acts on it: it moved 1 m/s x 1 ms, the whole step.
  EXPECT_NEAR(fluid.particles().positions[0].x(), 1.0 * dt, 1e-12);
}

// Settings built in code (a game's SceneConfig) are held to the ranges a scene file is: a zero spacing or
// PBF sub-steps of 0 are named before anything is built, where they divided by zero or looped without end.
TEST(FluidSolver, RefusesSettingsOutOfRangeNamingTheField) {
  const auto refused = [](const std::function<void(FluidSettings&)>& change, const std::string& message) {
    FluidSettings settings;
    change(settings);
    return test::throws_containing<SceneError>(
        [&] { FluidSolver(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0); }, {message});
  };
  EXPECT_TRUE(refused([](FluidSettings& s) { s.particle_spacing = 0.0; },
                      "fluid.particle_spacing must be > 0, got 0"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.rest_density = std::numeric_limits<double>::quiet_NaN(); },
                      "fluid.rest_density must be > 0, got nan"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.cfl = 2.0; }, "fluid.cfl must be in (0, 1], got 2"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.wcsph.speed_of_sound = 1e5; },
                      "fluid.wcsph.speed_of_sound must be in (0, 2000], got 100000"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.pbf.scorr_n = 2147483647; },
                      "fluid.pbf.scorr_n must be in [1, 16], got 2147483647"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.pbf.substeps = 0; },
                      "fluid.pbf.substeps must be in [1, 1000], got 0"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.pbf.iterations = 1001; },
                      "fluid.pbf.iterations must be in [1, 1000], got 1001"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.pcisph.min_iterations = 5, s.pcisph.max_iterations = 4; },
                      "fluid.pcisph.max_iterations must be >= fluid.pcisph.min_iterations = 5, got 4"));
  EXPECT_TRUE(
      refused([](FluidSettings& s) { s.dfsph.eta = 0.0; }, "fluid.dfsph.eta must be in (0, 1), got 0"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.pbf.scorr_substep = -1.0; },
                      "fluid.pbf.scorr_substep must be > 0, got -1"));
  EXPECT_TRUE(refused([](FluidSettings& s) { s.viscosity.coefficient = -0.01; },
                      "fluid.viscosity.coefficient must be >= 0, got -0.01"));
  // The defaults, and the scene file's extremes, pass.
  EXPECT_NO_THROW(check_fluid_settings(FluidSettings{}));
  FluidSettings extreme;
  extreme.cfl = 1.0;
  extreme.substep_halvings = kMaxSubstepHalvings;
  extreme.pbf.substeps = extreme.pbf.iterations = kMaxPassesPerStep;
  extreme.max_speed = std::nullopt;
  EXPECT_NO_THROW(check_fluid_settings(extreme));
}

TEST(FluidSolver, KeepingAMovingBoundaryAtRestGivesTheBitsOfSettingItAgain) {
  // A block falling onto a body's floor of boundary points that does not move. Set again every step, its
  // grid is rebuilt; kept, it is not, but the next search is fresh all the same: every solver (WCSPH keeps
  // Verlet lists over sub-steps and steps) must reach the very same state, and the body the same impulses.
  Vec3Array floor, normals;
  ScalarArray volumes;
  for (int i = -2; i < 8; ++i) {
    for (int k = -2; k < 8; ++k) {
      floor.push_back(Vec3((i + 0.5) * kSpacing, -0.6 * kSpacing, (k + 0.5) * kSpacing));
      volumes.push_back(kSpacing * kSpacing * kSpacing);
      normals.push_back(Vec3::UnitY());
    }
  }
  for (const PressureSolverKind solver : {PressureSolverKind::WCSPH, PressureSolverKind::PCISPH,
                                          PressureSolverKind::DFSPH, PressureSolverKind::PBF}) {
    FluidSettings settings;
    settings.particle_spacing = kSpacing;
    settings.pressure_solver = solver;
    const auto make = [&] {
      FluidSolver fluid(settings, Vec3(0, -9.81, 0), BoundaryParticles{}, {}, false, 10.0);
      BoxEmitterSettings box;
      box.min = Vec3(0, 0.5 * kSpacing, 0);
      box.max = Vec3(6 * kSpacing, 4.5 * kSpacing, 6 * kSpacing);
      std::uint32_t next_id = 0;
      emit_box(box, kSpacing, settings.rest_density * kSpacing * kSpacing * kSpacing, fluid.particles(),
               next_id);
      fluid.set_moving_boundary(floor, volumes, normals);
      return fluid;
    };
    FluidSolver set_again = make(), kept = make();
    Vec3 pushed = Vec3::Zero();
    for (int step = 0; step < 20; ++step) {
      set_again.set_moving_boundary(floor, volumes, normals);
      kept.keep_moving_boundary();
      ASSERT_TRUE(set_again.step(0.004).ok()) << pressure_solver_name(solver);
      ASSERT_TRUE(kept.step(0.004).ok()) << pressure_solver_name(solver);
      ASSERT_EQ(set_again.particles().positions, kept.particles().positions)
          << pressure_solver_name(solver) << " step " << step;
      ASSERT_EQ(set_again.particles().velocities, kept.particles().velocities)
          << pressure_solver_name(solver);
      ASSERT_EQ(set_again.moving_boundary_impulses(), kept.moving_boundary_impulses())
          << pressure_solver_name(solver);
      for (const Vec3& j : kept.moving_boundary_impulses())
        pushed += j;
    }
    // The water lands on the floor and pushes it down: the comparison covered a boundary in use.
    EXPECT_LT(pushed.y(), 0.0) << pressure_solver_name(solver);
  }
}

}  // namespace
}  // namespace drench
