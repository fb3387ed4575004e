// The pair loops take m_j from FluidContext::uniform_mass when every particle has the same mass, and from
// the particles' masses otherwise. Both paths must give the same fluid. PCISPH's single-precision iterations
// (which need one mass) must give the fluid of the double ones within float's rounding.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "scene/scene_config.hpp"
#include "sph/emitters.hpp"
#include "sph/fluid_solver.hpp"

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // m

/// An 8 x 8 x 8 PCISPH block without gravity with one particle stacked 0.2 spacing from an interior one, so
/// that pressures and pressure accelerations are not zero; with `lone_heavy_particle`, one more particle of
/// twice the mass far away (no neighbor), which makes the masses differ. PCISPH's iterations run in
/// `precision`.
FluidSolver compressed_block(bool lone_heavy_particle,
                             IterationPrecision precision = IterationPrecision::DOUBLE) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pcisph.precision = precision;
  FluidSolver fluid(settings, Vec3::Zero(), BoundaryParticles{}, {}, false, 10.0);
  BoxEmitterSettings box;
  box.max = Vec3::Constant(8 * kSpacing);
  std::uint32_t next_id = 0;
  const Scalar mass = settings.rest_density * kSpacing * kSpacing * kSpacing;
  emit_box(box, kSpacing, mass, fluid.particles(), next_id);
  ParticleSet& p = fluid.particles();
  p.add(p.positions[300] + Vec3(0.2 * kSpacing, 0, 0), Vec3::Zero(), mass, next_id++);
  if (lone_heavy_particle) p.add(Vec3(5.0, 5.0, 5.0), Vec3::Zero(), 2.0 * mass, next_id++);
  return fluid;
}

TEST(ParticleSet, CommonMassIsTheSharedMassOrZero) {
  ParticleSet p;
  EXPECT_EQ(p.common_mass(), 0.0);
  p.add(Vec3::Zero(), Vec3::Zero(), 0.001, 0);
  p.add(Vec3::Ones(), Vec3::Zero(), 0.001, 1);
  EXPECT_EQ(p.common_mass(), 0.001);
  p.add(Vec3::Ones(), Vec3::Zero(), 0.001 * (1.0 + 1e-15), 2);
  EXPECT_EQ(p.common_mass(), 0.0);
}

TEST(FluidContext, UniformMassPathGivesTheFluidOfPerParticleMasses) {
  FluidSolver uniform = compressed_block(false);
  FluidSolver mixed = compressed_block(true);
  ASSERT_GT(uniform.particles().common_mass(), 0.0);
  ASSERT_EQ(mixed.particles().common_mass(), 0.0);
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(uniform.step(1e-4).ok());
    ASSERT_TRUE(mixed.step(1e-4).ok());
  }
  const ParticleSet& a = uniform.particles();
  const ParticleSet& b = mixed.particles();
  std::unordered_map<std::uint32_t, std::size_t> in_b;
  for (std::size_t i = 0; i < b.size(); ++i)
    in_b[b.ids[i]] = i;
  Scalar fastest = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const std::size_t k = in_b.at(a.ids[i]);
    // m sum W against sum m W: a few roundings apart (rho ~ 1000 kg/m^3, pressures ~ 1e3 Pa)
    EXPECT_NEAR(a.densities[i], b.densities[k], 1e-9) << "id " << a.ids[i];
    EXPECT_NEAR(a.pressures[i], b.pressures[k], 1e-6) << "id " << a.ids[i];
    EXPECT_LT((a.velocities[i] - b.velocities[k]).norm(), 1e-12) << "id " << a.ids[i];
    fastest = std::max(fastest, a.velocities[i].norm());
  }
  // The stacked particle was pushed apart: the pressure loops did work on both paths.
  EXPECT_GT(fastest, 1e-3);
}

/// Three sub-steps of the compressed block in single and in double precision: the same iteration counts, and
/// densities, pressures and velocities within float's rounding. Measured: densities 3.4e-7 apart (relative),
/// pressures 4.6 Pa of 53.6 kPa (the stacked particle's: PCISPH's pressure is delta times the density error,
/// an amplifier of density rounding), velocities 1.7e-5 of 5.9 m/s.
TEST(Pcisph, SinglePrecisionIterationsGiveTheFluidOfDouble) {
  FluidSolver single = compressed_block(false, IterationPrecision::SINGLE);
  FluidSolver reference = compressed_block(false, IterationPrecision::DOUBLE);
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(single.step(1e-4).ok());
    ASSERT_TRUE(reference.step(1e-4).ok());
  }
  const ParticleSet& a = single.particles();
  const ParticleSet& b = reference.particles();
  std::unordered_map<std::uint32_t, std::size_t> in_b;
  for (std::size_t i = 0; i < b.size(); ++i)
    in_b[b.ids[i]] = i;
  Scalar fastest = 0.0, density = 0.0, pressure = 0.0, velocity = 0.0, max_pressure = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const std::size_t k = in_b.at(a.ids[i]);
    density = std::max(density, std::abs(a.densities[i] - b.densities[k]) / b.densities[k]);
    pressure = std::max(pressure, std::abs(a.pressures[i] - b.pressures[k]));
    velocity = std::max(velocity, (a.velocities[i] - b.velocities[k]).norm());
    fastest = std::max(fastest, b.velocities[k].norm());
    max_pressure = std::max(max_pressure, b.pressures[k]);
  }
  EXPECT_EQ(single.statistics().pressure_iterations, reference.statistics().pressure_iterations);
  EXPECT_LT(density, 1e-5);
  EXPECT_LT(pressure, 1e-4 * max_pressure);
  EXPECT_LT(velocity, 1e-4 * fastest);
  EXPECT_GT(fastest, 1e-3);  // the stacked particle was pushed apart: the loops did work
}

}  // namespace
}  // namespace drench
