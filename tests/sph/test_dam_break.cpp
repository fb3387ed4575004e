// Dam break (demos/scenes/dam_break.json): a 1 m cube of water collapsing in a 4 x 3 x 1.5 m box, 1 s.

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "physics_helpers.hpp"

namespace drench {
namespace {

void expect_finite_inside_the_box_conserving_particles_and_losing_energy(
    const std::vector<std::string>& overrides) {
  const SceneConfig config = testing::demo_scene("dam_break.json", overrides);
  Simulation sim(config);
  const std::size_t count = sim.particles().size();
  ASSERT_EQ(count, 8000u);
  const Scalar e0 = testing::total_energy(sim.particles(), config.gravity);
  Scalar e_max = e0;
  while (!sim.finished()) {
    const StepStatus status = sim.step();
    ASSERT_TRUE(status.ok()) << status.describe();
    e_max = std::max(e_max, testing::total_energy(sim.particles(), config.gravity));
  }
  const ParticleSet& p = sim.particles();
  EXPECT_TRUE(testing::all_finite(p));
  EXPECT_EQ(p.size(), count);
  EXPECT_EQ(sim.removed(), 0);
  const BoundarySettings& box = config.boundaries.at(0);
  std::size_t outside = 0;
  for (const Vec3& x : p.positions) {
    if ((x.array() < box.min.array()).any() || (x.array() > box.max.array()).any()) ++outside;
  }
  EXPECT_EQ(outside, 0u);
  const Scalar e1 = testing::total_energy(p, config.gravity);
  std::printf("[ measured ] energy: initial %.2f J, final %.2f J, max %.2f J\n", e0, e1, e_max);
  EXPECT_LT(e1, e0);
  EXPECT_LE(e_max, 1.01 * e0) << "energy rose above its initial value by more than 1%";
}

TEST(DamBreakPcisph, StaysFiniteInsideTheBoxConservesParticlesAndLosesEnergy) {
  expect_finite_inside_the_box_conserving_particles_and_losing_energy({"time.duration=1.0"});
}

TEST(DamBreakDfsph, StaysFiniteInsideTheBoxConservesParticlesAndLosesEnergy) {
  expect_finite_inside_the_box_conserving_particles_and_losing_energy(
      {"time.duration=1.0", "fluid.pressure_solver=dfsph"});
}

}  // namespace
}  // namespace drench
