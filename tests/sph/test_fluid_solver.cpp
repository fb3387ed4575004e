// FluidSolver's fluid.max_speed: a particle over it stops the step before a sub-step, naming the particle,
// where the CFL rule would otherwise cut the step into hundreds of sub-steps for that particle alone.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include <drench/scene/scene_config.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>

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

}  // namespace
}  // namespace drench
