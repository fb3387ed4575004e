// Adhesion (the coupler's adhere stage, coupler_stages.hpp): a droplet of water under a horizontal plate
// clings to it with adhesion and falls without, and the plate carries the droplet's weight.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <drench/coupling/coupler.hpp>
#include <drench/sph/fluid_solver.hpp>

namespace drench {
namespace {

constexpr Scalar kSpacing = 0.001;  // m
constexpr Scalar kSigma = 0.072;    // N/m, water
constexpr Scalar kDt = 0.0005;      // s
constexpr int kSteps = 400;         // 0.2 s: a free droplet falls 0.2 m in it

struct Hanging {
  Scalar centre_y = 0.0;         ///< the droplet's centre of mass at the end (unit: m)
  Scalar plate_impulse_y = 0.0;  ///< what the plate took over the second half (unit: N s)
  Scalar weight_impulse = 0.0;   ///< the droplet's weight times that time (unit: N s)
};

/// A half ball of water of radius 3 mm, flat side up, a particle spacing under a static plate at y = 0 (a
/// 2 cm grid, inverse mass 0), under gravity, with surface tension; the plate has the work of adhesion
/// `work` (N/m), or none when 0.
Hanging hang(Scalar work) {
  FluidSettings settings;
  settings.particle_spacing = kSpacing;
  settings.pressure_solver = PressureSolverKind::DFSPH;
  const SurfaceTensionSettings tension{kSigma};
  const Vec3 gravity(0.0, -9.81, 0.0);
  FluidSolver fluid(settings, gravity, BoundaryParticles{}, {}, true, 10.0, &tension);
  const Scalar radius = 3.0 * kSpacing;
  std::uint32_t id = 0;
  for (int i = -3; i <= 3; ++i)
    for (int j = 0; j <= 3; ++j)
      for (int k = -3; k <= 3; ++k) {
        const Vec3 offset = kSpacing * Vec3(i, -j, k);
        if (offset.norm() <= radius)
          fluid.particles().add(offset - Vec3(0.0, kSpacing, 0.0), Vec3::Zero(), fluid.particle_mass(), id++);
      }
  ClothMesh plate = ClothMesh::grid(21, 0.02, 0.0, 0.0, -0.01, -0.01);
  CouplingSettings coupling;
  coupling.cloth_thickness = 0.5 * kSpacing;
  Coupler coupler(coupling, false);
  if (work > 0.0) {
    AdhesionSettings adhesion;
    adhesion.work.assign(plate.triangle_count(), work);
    adhesion.range = 2.0 * kSpacing;
    adhesion.rest_density = settings.rest_density;
    coupler.set_adhesion(adhesion);
  }
  Hanging result;
  Scalar mass = 0.0;
  for (const Scalar m : fluid.particles().masses)
    mass += m;
  for (int step = 1; step <= kSteps; ++step) {
    EXPECT_TRUE(fluid.step(kDt).ok()) << step;
    ParticleSet& p = fluid.particles();
    const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses, nullptr};
    CouplingStepStats stats;
    coupler.step(view, plate, kDt, stats);
    if (step > kSteps / 2) {
      for (const Vec3& j : coupler.node_impulses())
        result.plate_impulse_y += j.y();
      result.weight_impulse += mass * gravity.y() * kDt;
    }
  }
  for (const Vec3& x : fluid.particles().positions)
    result.centre_y += x.y() / static_cast<Scalar>(fluid.particles().size());
  return result;
}

TEST(Adhesion, DropletClingsUnderAPlateWithAdhesionAndFallsWithout) {
  // Water on a face it wets fully: Dupre's sigma (1 + cos 0) = 0.144 N/m.
  const Hanging wet = hang(2.0 * kSigma);
  const Hanging dry = hang(0.0);
  std::printf(
      "[ measured ] centre after 0.2 s: %.4f m with adhesion, %.4f m without; plate took %.3g N s, "
      "weight %.3g N s over the last 0.1 s\n",
      wet.centre_y, dry.centre_y, wet.plate_impulse_y, wet.weight_impulse);
  // Hanging: its centre stays within its own radius (3 mm) of where it started (-2.2 mm).
  EXPECT_GT(wet.centre_y, -0.0052);
  // Fallen: free fall takes it 0.196 m down in 0.2 s; half of that is far from the plate's reach (2 mm).
  EXPECT_LT(dry.centre_y, -0.09);
  // What holds the droplet, the plate takes: its weight over the time, within 20% (the droplet still
  // wobbles).
  EXPECT_NEAR(wet.plate_impulse_y, wet.weight_impulse, 0.2 * std::abs(wet.weight_impulse));
}

}  // namespace
}  // namespace drench
