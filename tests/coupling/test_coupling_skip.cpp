// Coupling skipped where there is nothing to couple (issue 28): the coupler's step and the cloth inside the
// fluid's sub-steps cost one box test when no particle is within reach, and they skip only then: a particle
// the broad phase could pair with a triangle is always coupled.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_obstacle.hpp>
#include <drench/coupling/coupler.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

using test::grid_mesh;
using test::Particles;

constexpr double kMass = 1.25e-4;  // one particle of water at 5 mm spacing (unit: kg)

/// One coupler step of `particles` against a copy of `mesh`; true when the coupler skipped it.
bool skipped_step(Coupler& coupler, Particles particles, ClothMesh mesh, double dt) {
  const std::uint64_t before = coupler.counter().skipped;
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  return coupler.counter().skipped > before;
}

// Random single particles around a moving 5 x 5 cloth, within a few thicknesses of its box: whenever the
// exact broad phase (brute force) pairs the particle with a triangle for the proximity test (x_t0, margin
// h / 2) or the first CCD round (x_t0 to x_t1, margin 0), the step ran.
TEST(EffectsCouplingSkip, SkipsOnlyWhenNoStageCouldFindAPair) {
  CouplingSettings settings;
  settings.cloth_thickness = 0.01;
  const double h = settings.cloth_thickness;
  ClothMesh mesh = grid_mesh(5, 1.0, 0.0, 1.0);
  std::mt19937 rng(28);
  std::uniform_real_distribution<double> wobble(-0.02, 0.02);
  for (Vec3& x : mesh.positions_t1)
    x += Vec3(wobble(rng), wobble(rng), wobble(rng));
  Box3 around = mesh_box(mesh);
  around.grow(3.0 * h);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_real_distribution<double> move(-2.0 * h, 2.0 * h);
  Coupler coupler(settings);
  const double dt = 0.001;
  int skipped = 0, within_reach = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const Vec3 x0 = around.lo + (around.hi - around.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    const Vec3 x1 = x0 + Vec3(move(rng), move(rng), move(rng));
    Particles particles;
    particles.add(x0, (x1 - x0) / dt, dt, kMass);
    particles.x1[0] = x1;
    std::vector<std::pair<Index, Index>> proximity, ccd;
    find_pairs_brute_force(particles.x0, particles.x0, mesh, 0.5 * h, proximity);
    find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.0, ccd);
    const bool reach = !proximity.empty() || !ccd.empty();
    const bool skip = skipped_step(coupler, particles, mesh, dt);
    within_reach += reach;
    skipped += skip;
    ASSERT_FALSE(reach && skip) << "trial " << trial << ": a particle within reach was not coupled";
  }
  // Both kinds occurred, so the assertion above was exercised.
  EXPECT_GT(skipped, 100);
  EXPECT_GT(within_reach, 100);
  EXPECT_EQ(coupler.counter().passes + coupler.counter().skipped, 4000u);
}

// The reach is closed: a particle resting exactly one thickness below a flat cloth is a proximity candidate
// and is coupled; one a rounding step further away is skipped.
TEST(EffectsCouplingSkip, AParticleExactlyOneThicknessAwayIsCoupled) {
  CouplingSettings settings;
  const double h = settings.cloth_thickness;
  const ClothMesh mesh = grid_mesh(3, 1.0, 0.0, 1.0);
  Coupler coupler(settings);
  const double dt = 0.001;
  Particles at_reach;
  at_reach.add(Vec3(0.5, -h, 0.5), Vec3::Zero(), dt, kMass);
  Particles beyond;
  beyond.add(Vec3(0.5, std::nextafter(-h, -1.0), 0.5), Vec3::Zero(), dt, kMass);
  std::vector<std::pair<Index, Index>> pairs;
  find_pairs_brute_force(at_reach.x0, at_reach.x0, mesh, 0.5 * h, pairs);
  ASSERT_FALSE(pairs.empty());
  find_pairs_brute_force(beyond.x0, beyond.x1, mesh, 0.5 * h, pairs);
  ASSERT_TRUE(pairs.empty());
  EXPECT_FALSE(skipped_step(coupler, at_reach, mesh, dt));
  EXPECT_TRUE(skipped_step(coupler, beyond, mesh, dt));
}

// A skipped step leaves what the carried water and the wetting read (Coupler::node_impulses,
// Coupler::impulse_links) as a step without contacts does, not as the last step that had some.
TEST(EffectsCouplingSkip, ASkippedStepLeavesTheOutputsOfAStepWithoutContacts) {
  const ClothMesh start = grid_mesh(2, 1.0, 0.0, 1.0);
  Coupler coupler(CouplingSettings{});
  const double dt = 0.01;
  const std::vector<std::uint32_t> ids{3};
  CouplingStepStats stats;

  Particles hit;
  hit.add(Vec3(0.3, 0.05, 0.2), Vec3(0, -10.0, 0), dt, kMass);
  FluidView view = hit.view();
  view.ids = &ids;
  ClothMesh mesh = start;
  coupler.step(view, mesh, dt, stats);
  ASSERT_EQ(coupler.impulse_links().size(), 1u);
  ASSERT_EQ(coupler.counter().passes, 1u);

  Particles far;
  far.add(Vec3(0.3, 1.0, 0.2), Vec3(0, -1.0, 0), dt, kMass);
  const Particles far_before = far;
  view = far.view();
  view.ids = &ids;
  mesh = start;
  const CouplingStepStats stats_before = stats;
  EXPECT_EQ(coupler.step(view, mesh, dt, stats), COUPLING_OK);
  EXPECT_EQ(coupler.counter().skipped, 1u);
  EXPECT_TRUE(coupler.impulse_links().empty());
  ASSERT_EQ(coupler.node_impulses().size(), mesh.node_count());
  for (const Vec3& j : coupler.node_impulses())
    EXPECT_EQ(j, Vec3::Zero());
  EXPECT_EQ(far.x1, far_before.x1);
  EXPECT_EQ(far.v, far_before.v);
  EXPECT_EQ(mesh.positions_t1, start.positions_t1);
  EXPECT_EQ(stats.contacts, stats_before.contacts);
  EXPECT_EQ(stats.ccd_iterations, stats_before.ccd_iterations) << "a skipped step runs no CCD round";
}

// Friction is a stage of the coupler only when it is built with it (the "friction" effect).
TEST(EffectsCouplingSkip, FrictionRunsOnlyWhenTheCouplerIsBuiltWithIt) {
  Particles particles;
  const double dt = 0.01;
  particles.add(Vec3(0.3, 0.05, 0.2), Vec3(1.0, -10.0, 0), dt, kMass);
  for (const bool with_friction : {false, true}) {
    Coupler coupler(CouplingSettings{}, with_friction);
    Particles copy = particles;
    ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 1.0);
    CouplingStepStats stats;
    coupler.step(copy.view(), mesh, dt, stats);
    EXPECT_EQ(coupler.counter().passes, 1u);
    EXPECT_EQ(coupler.friction_counter().constructed, with_friction ? 1u : 0u);
    EXPECT_EQ(coupler.friction_counter().passes, with_friction ? 1u : 0u);
  }
}

// The cloth inside the fluid's sub-steps: a sub-step whose particles all stay clear of the cloth's box is
// one test; one that crosses the cloth is a pass and stops the particle.
TEST(EffectsCouplingSkip, TheSubstepObstacleSkipsOnlySubstepsClearOfTheCloth) {
  const ClothMesh cloth = grid_mesh(3, 1.0, 0.0, 1.0);
  ClothObstacle obstacle(0.001, BroadPhaseKind::FCL, true);
  EXPECT_EQ(obstacle.counter().constructed, 1u);
  obstacle.begin_step(cloth, Vec3Array(cloth.node_count(), Vec3::Zero()));
  ParticleSet particles;
  particles.add(Vec3(0.5, 0.5, 0.5), Vec3(0, -1.0, 0), kMass, 0);
  const double dt = 0.01;
  Vec3Array before = particles.positions;
  particles.positions[0] += dt * particles.velocities[0];
  obstacle.apply(before, particles, dt);
  EXPECT_EQ(obstacle.counter().skipped, 1u);
  EXPECT_EQ(obstacle.counter().passes, 0u);

  before[0] = Vec3(0.5, 0.005, 0.5);
  particles.positions[0] = Vec3(0.5, -0.005, 0.5);
  obstacle.apply(before, particles, dt);
  EXPECT_EQ(obstacle.counter().passes, 1u);
  EXPECT_EQ(obstacle.stops(), 1u);
  EXPECT_GE(particles.velocities[0].y(), 0.0);
}

}  // namespace
}  // namespace drench
