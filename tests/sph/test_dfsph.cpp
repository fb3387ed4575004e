// DFSPH (Bender & Koschier 2017) on blocks of fluid without gravity: a block at rest density stays still (the
// divergence-free solve invents no motion), a block moving as one keeps its velocity (its divergence is
// zero), and a compressed block relaxes to the rest density within eta.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include <drench/sph/boundary_sampling.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.02;  // m
constexpr int kSide = 10;          // particles along each side of the block
constexpr Scalar kDt = 0.005;      // s, a scene step as the dam break's

FluidSettings dfsph_settings() {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = PressureSolverKind::DFSPH;
  return settings;
}

/// A fluid without gravity, in a closed box whose inside [0, kSide spacing]^3 holds the block at rest
/// spacing exactly (`closed`), or in free space; with XSPH viscosity 0.01 (the scenes') when `viscous`.
FluidSolver make_fluid(const FluidSettings& settings, bool closed, bool viscous = false) {
  const Vec3 box_max = Vec3::Constant(kSide * kSpacing);
  BoundaryParticles walls;
  std::vector<BoundarySettings> guards;
  if (closed) {
    walls = sample_box_container(Vec3::Zero(), box_max, kSpacing, 2, false);
    BoundarySettings guard;
    guard.max = box_max;
    guards.push_back(guard);
  }
  return FluidSolver(settings, Vec3::Zero(), std::move(walls), std::move(guards), viscous, 10.0);
}

/// Adds kSide^3 particles on a cubic lattice of `spacing` centred in the box, moving at `velocity`.
void add_block(FluidSolver& fluid, Scalar spacing, const Vec3& velocity) {
  BoxEmitterSettings box;
  const Vec3 centre = Vec3::Constant(0.5 * kSide * kSpacing);
  box.min = centre - Vec3::Constant(0.5 * kSide * spacing);
  box.max = centre + Vec3::Constant(0.5 * kSide * spacing);
  box.velocity = velocity;
  std::uint32_t next_id = 0;
  const Scalar mass = fluid.settings().rest_density * kSpacing * kSpacing * kSpacing;
  ASSERT_EQ(emit_box(box, spacing, mass, fluid.particles(), next_id), std::size_t(kSide * kSide * kSide));
}

/// Mean over particles of max(rho_i - rho0, 0) / rho0 of the densities the last sub-step started from.
Scalar mean_density_error(const FluidSolver& fluid) {
  const Scalar rho0 = fluid.settings().rest_density;
  Scalar sum = 0.0;
  for (const Scalar rho : fluid.particles().densities)
    sum += std::max(rho - rho0, 0.0);
  return sum / (fluid.particles().size() * rho0);
}

TEST(Dfsph, StillBlockAtRestDensityStaysStill) {
  FluidSolver fluid = make_fluid(dfsph_settings(), true);
  add_block(fluid, kSpacing, Vec3::Zero());
  for (int step = 0; step < 100; ++step)
    ASSERT_TRUE(fluid.step(kDt).ok());
  const Scalar speed = fluid.max_speed();
  std::printf("[ measured ] max speed after 0.5 s: %.3g m/s, density error %.3g\n", speed,
              mean_density_error(fluid));
  // A micrometre per second: rounding, nothing a step of 5 ms would show (a millionth of a spacing).
  EXPECT_LT(speed, 1e-6);
  EXPECT_EQ(fluid.statistics().divergence_iterations, 0);
}

TEST(Dfsph, BlockMovingAsOneKeepsItsVelocity) {
  FluidSolver fluid = make_fluid(dfsph_settings(), false);
  const Vec3 velocity(1.0, 0.5, 0.0);
  add_block(fluid, kSpacing, velocity);
  for (int step = 0; step < 20; ++step)
    ASSERT_TRUE(fluid.step(kDt).ok());
  Scalar deviation = 0.0;
  for (const Vec3& v : fluid.particles().velocities)
    deviation = std::max(deviation, (v - velocity).norm());
  std::printf("[ measured ] largest deviation from the block's velocity after 0.1 s: %.3g m/s\n", deviation);
  EXPECT_LT(deviation, 1e-9);
}

TEST(Dfsph, CompressedBlockRelaxesToRestDensityWithinEta) {
  const FluidSettings settings = dfsph_settings();
  // Viscous, so that the block comes to rest: without it, it still sloshed at 0.18 m/s after 1 s.
  FluidSolver fluid = make_fluid(settings, true, true);
  // 0.95 spacing: the inside compressed by 1 / 0.95^3 - 1 = 17%, in a box that holds it at rest density.
  add_block(fluid, 0.95 * kSpacing, Vec3::Zero());
  ASSERT_TRUE(fluid.step(kDt).ok());
  const Scalar initial = mean_density_error(fluid);
  for (int step = 1; step < 200; ++step)
    ASSERT_TRUE(fluid.step(kDt).ok());
  const Scalar final_error = mean_density_error(fluid);
  std::printf("[ measured ] mean density error: first sub-step %.4f, after 1 s %.3g (eta %.4g); %.3g m/s\n",
              initial, final_error, settings.dfsph.eta, fluid.max_speed());
  ASSERT_GT(initial, 0.05) << "the block must start compressed";
  EXPECT_LE(final_error, settings.dfsph.eta);
}

}  // namespace
}  // namespace drench
