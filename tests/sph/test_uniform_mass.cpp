// The pair loops take m_j from FluidContext::uniform_mass when every particle has the same mass, and from
// the particles' masses otherwise. Both paths must give the same fluid. PCISPH's, DFSPH's and PBF's
// single-precision iterations (which need one mass) must give the fluid of the double ones within float's
// rounding.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <utility>

#include <drench/scene/scene_config.hpp>
#include <drench/sph/boundary_sampling.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // m

/// An 8 x 8 x 8 block of `solver` (PCISPH unless said) without gravity with one particle stacked 0.2 spacing
/// from an interior one, so that pressures and pressure accelerations are not zero; with
/// `lone_heavy_particle`, one more particle of twice the mass far away (no neighbor), which makes the masses
/// differ. The solver's iterations run in `precision`. The block's corner is at `offset` (unit: m); with
/// `floor`, it rests on one layer of boundary points half a spacing below it, 12 x 12 of them (the bottom
/// layer then has boundary neighbors).
FluidSolver compressed_block(bool lone_heavy_particle,
                             IterationPrecision precision = IterationPrecision::DOUBLE,
                             const Vec3& offset = Vec3::Zero(), bool floor = false,
                             PressureSolverKind solver = PressureSolverKind::PCISPH) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = solver;
  settings.pcisph.precision = precision;
  settings.dfsph.precision = precision;
  settings.pbf.precision = precision;
  BoundaryParticles boundary;
  for (int k = -2; floor && k < 10; ++k) {
    for (int i = -2; i < 10; ++i) {
      boundary.positions.push_back(offset + kSpacing * Vec3(i + 0.5, -0.5, k + 0.5));
      boundary.volumes.push_back(kSpacing * kSpacing * kSpacing);
    }
  }
  FluidSolver fluid(settings, Vec3::Zero(), std::move(boundary), {}, false, 10.0);
  BoxEmitterSettings box;
  box.min = offset;
  box.max = offset + Vec3::Constant(8 * kSpacing);
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

/// The largest differences between two runs of the same particles (matched by id).
struct Differences {
  Scalar density = 0.0;       // relative
  Scalar pressure = 0.0;      // (unit: Pa)
  Scalar velocity = 0.0;      // (unit: m/s)
  Scalar position = 0.0;      // (unit: m)
  Scalar fastest = 0.0;       // the fastest particle of `b` (unit: m/s)
  Scalar max_pressure = 0.0;  // the largest pressure of `b` (unit: Pa)
};

/// Three sub-steps of 0.1 ms of `a` and `b`, then their differences.
Differences after_three_substeps(FluidSolver& a, FluidSolver& b) {
  for (int step = 0; step < 3; ++step) {
    EXPECT_TRUE(a.step(1e-4).ok());
    EXPECT_TRUE(b.step(1e-4).ok());
  }
  const ParticleSet& pa = a.particles();
  const ParticleSet& pb = b.particles();
  std::unordered_map<std::uint32_t, std::size_t> in_b;
  for (std::size_t i = 0; i < pb.size(); ++i)
    in_b[pb.ids[i]] = i;
  Differences d;
  for (std::size_t i = 0; i < pa.size(); ++i) {
    const std::size_t k = in_b.at(pa.ids[i]);
    d.density = std::max(d.density, std::abs(pa.densities[i] - pb.densities[k]) / pb.densities[k]);
    d.pressure = std::max(d.pressure, std::abs(pa.pressures[i] - pb.pressures[k]));
    d.velocity = std::max(d.velocity, (pa.velocities[i] - pb.velocities[k]).norm());
    d.position = std::max(d.position, (pa.positions[i] - pb.positions[k]).norm());
    d.fastest = std::max(d.fastest, pb.velocities[k].norm());
    d.max_pressure = std::max(d.max_pressure, pb.pressures[k]);
  }
  return d;
}

/// Single precision against double on the compressed block: the same iteration counts, and densities,
/// pressures and velocities within float's rounding (pressures: PCISPH's pressure is delta times the density
/// error, an amplifier of density rounding).
/// DFSPH's likewise (its pressure is rho^2 kappa, kappa the density error over the factor's denominator).
void expect_single_gives_the_fluid_of_double(const Vec3& offset, bool floor,
                                             PressureSolverKind solver = PressureSolverKind::PCISPH) {
  FluidSolver single = compressed_block(false, IterationPrecision::SINGLE, offset, floor, solver);
  FluidSolver reference = compressed_block(false, IterationPrecision::DOUBLE, offset, floor, solver);
  const Differences d = after_three_substeps(single, reference);
  std::printf(
      "[ measured ] single - double: density %.2g (relative), pressure %.2g of %.3g Pa, velocity %.2g "
      "of %.2g m/s\n",
      d.density, d.pressure, d.max_pressure, d.velocity, d.fastest);
  EXPECT_EQ(single.statistics().pressure_iterations, reference.statistics().pressure_iterations);
  EXPECT_EQ(single.statistics().divergence_iterations, reference.statistics().divergence_iterations);
  EXPECT_LT(d.density, 1e-5);
  if (solver != PressureSolverKind::PBF) {  // PBF has no pressures
    EXPECT_LT(d.pressure, 1e-4 * d.max_pressure);
  }
  EXPECT_LT(d.velocity, 1e-4 * d.fastest);
  EXPECT_GT(d.fastest, 1e-3);  // the stacked particle was pushed apart: the loops did work
  EXPECT_GT(d.velocity, 0.0) << "single precision must be in use (else this test checks nothing)";
}

/// Near the origin, where floats are finest (the differences are printed as [ measured ]).
TEST(Pcisph, SinglePrecisionIterationsGiveTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3::Zero(), false);
}

/// 1 km from the origin, on a floor of boundary points: a float there is 61 um coarse, 0.6% of the spacing,
/// so this holds only because the float records are taken relative to the fluid's centre (boundary points
/// included).
TEST(Pcisph, SinglePrecisionFarFromTheOriginOverAFloorGivesTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3(1000.0, -200.0, 300.0), true);
}

TEST(Dfsph, SinglePrecisionIterationsGiveTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3::Zero(), false, PressureSolverKind::DFSPH);
}

TEST(Dfsph, SinglePrecisionFarFromTheOriginOverAFloorGivesTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3(1000.0, -200.0, 300.0), true, PressureSolverKind::DFSPH);
}

/// PBF's constraint and move passes likewise (no pressures: its frames carry 0).
TEST(Pbf, SinglePrecisionIterationsGiveTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3::Zero(), false, PressureSolverKind::PBF);
}

TEST(Pbf, SinglePrecisionFarFromTheOriginOverAFloorGivesTheFluidOfDouble) {
  expect_single_gives_the_fluid_of_double(Vec3(1000.0, -200.0, 300.0), true, PressureSolverKind::PBF);
}

/// Particles of differing masses take the double loops whatever the setting: the same bits as double.
void expect_double_when_masses_differ(PressureSolverKind solver) {
  FluidSolver single = compressed_block(true, IterationPrecision::SINGLE, Vec3::Zero(), false, solver);
  FluidSolver reference = compressed_block(true, IterationPrecision::DOUBLE, Vec3::Zero(), false, solver);
  const Differences d = after_three_substeps(single, reference);
  EXPECT_EQ(d.position, 0.0);
  EXPECT_EQ(d.velocity, 0.0);
  EXPECT_EQ(d.pressure, 0.0);
  EXPECT_GT(d.fastest, 1e-3);
}

TEST(Pcisph, SinglePrecisionFallsBackToDoubleWhenMassesDiffer) {
  expect_double_when_masses_differ(PressureSolverKind::PCISPH);
}

TEST(Dfsph, SinglePrecisionFallsBackToDoubleWhenMassesDiffer) {
  expect_double_when_masses_differ(PressureSolverKind::DFSPH);
}

/// PBF's float passes carry each particle's mass (wetting makes them differ in the game-like level): its
/// single precision serves differing masses too.
TEST(Pbf, SinglePrecisionWithDifferingMassesGivesTheFluidOfDouble) {
  FluidSolver single =
      compressed_block(false, IterationPrecision::SINGLE, Vec3::Zero(), false, PressureSolverKind::PBF);
  FluidSolver reference =
      compressed_block(false, IterationPrecision::DOUBLE, Vec3::Zero(), false, PressureSolverKind::PBF);
  // A particle inside the block half absorbed by a cloth: its neighbors' sums take its mass.
  for (FluidSolver* fluid : {&single, &reference})
    fluid->particles().masses[100] *= 0.5;
  ASSERT_EQ(single.particles().common_mass(), 0.0);
  const Differences d = after_three_substeps(single, reference);
  std::printf("[ measured ] single - double: density %.2g (relative), velocity %.2g of %.2g m/s\n", d.density,
              d.velocity, d.fastest);
  EXPECT_LT(d.density, 1e-5);
  EXPECT_LT(d.velocity, 1e-4 * d.fastest);
  EXPECT_GT(d.fastest, 1e-3);
  EXPECT_GT(d.velocity, 0.0) << "single precision must be in use (else this test checks nothing)";
}

/// A particle at infinity is reported by name and harms no other. Single precision centres its float records
/// on the finite particles and takes double when the fluid reaches too far from that centre; with neither
/// guard, every record became NaN and the report named another particle (both checked by mutation).
void expect_particle_at_infinity_kept_to_itself(PressureSolverKind solver) {
  FluidSolver fluid = compressed_block(false, IterationPrecision::SINGLE, Vec3::Zero(), false, solver);
  ParticleSet& p = fluid.particles();
  const std::uint32_t id = 100000;
  p.add(Vec3(std::numeric_limits<Scalar>::infinity(), 0.0, 0.0), Vec3::Zero(), p.masses[0], id);
  const StepStatus status = fluid.step(1e-4);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.non_finite_particle, static_cast<std::int64_t>(id));
  std::size_t finite = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    finite += p.positions[i].allFinite() && p.velocities[i].allFinite();
  EXPECT_EQ(finite, p.size() - 1);
}

TEST(Pcisph, SinglePrecisionKeepsAParticleAtInfinityToItself) {
  expect_particle_at_infinity_kept_to_itself(PressureSolverKind::PCISPH);
}

TEST(Dfsph, SinglePrecisionKeepsAParticleAtInfinityToItself) {
  expect_particle_at_infinity_kept_to_itself(PressureSolverKind::DFSPH);
}

TEST(Pbf, SinglePrecisionKeepsAParticleAtInfinityToItself) {
  expect_particle_at_infinity_kept_to_itself(PressureSolverKind::PBF);
}

}  // namespace
}  // namespace drench
