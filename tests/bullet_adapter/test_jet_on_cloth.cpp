// The coupled scene with Bullet cloth (issue 4): a reduced jet-on-cloth never leaks with continuous handling
// and does without it; a resting puddle gives the cloth its weight.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "bullet_adapter/bullet_cloth.hpp"
#include "common/triangle_geometry.hpp"
#include "scene/simulation.hpp"

namespace drench {
namespace {

/// The paper's Fig. 3 scene, reduced: a 0.3 m cloth of 21 x 21 nodes pinned at its corners, a 3 m/s jet of
/// 2,000 particles (5 mm spacing) from 0.15 m above its centre, 0.2 s, a kill plane 0.5 m below.
SceneConfig reduced_jet_on_cloth(double dt, bool continuous) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0, 0.15, 0);
  jet.nozzle.radius = 0.02;
  jet.nozzle.speed = 3.0;
  jet.nozzle.max_particles = 2000;
  c.emitters.push_back(jet);
  KillRegionSettings kill;
  kill.point = Vec3(0, -0.5, 0);
  c.kill_regions.push_back(kill);
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.3;
  cloth.nodes_x = cloth.nodes_z = 21;
  c.cloth = cloth;
  c.coupling.continuous = continuous;
  c.time.dt = dt;
  c.time.duration = 0.2;
  c.effects = {"viscosity", "coupling", "leak_audit"};
  return c;
}

struct RunFigures {
  std::uint64_t leaks, ccd_impacts, obstacle_stops, failsafe, created, alive, removed;
  double fastest_particle, fastest_node;
};

RunFigures run(const SceneConfig& config) {
  Simulation sim(config, bullet::cloth_engine_factory());
  RunFigures r{};
  while (!sim.finished()) {
    EXPECT_TRUE(sim.step().ok());
    for (const Vec3& v : sim.particles().velocities)
      r.fastest_particle = std::max(r.fastest_particle, v.norm());
    for (const Vec3& v : sim.cloth()->velocities())
      r.fastest_node = std::max(r.fastest_node, v.norm());
  }
  r.leaks = sim.leak_stats().leaks;
  r.ccd_impacts = sim.coupling_stats().ccd_impacts;
  r.obstacle_stops = sim.coupling_stats().obstacle_stops;
  r.failsafe = sim.coupling_stats().failsafe_activations;
  r.created = static_cast<std::uint64_t>(sim.created());
  r.alive = sim.particles().size();
  r.removed = static_cast<std::uint64_t>(sim.removed());
  return r;
}

// DISABLED until the coupled jet is stable (issue 4 notes). On this light cloth (node mass 4.1e-5 kg, a third
// of a particle's) the jet drives Bullet's nodes and the particles far past the speed bound within 0.1 s of
// contact. Measured with the obstacle's impulses entering before Bullet's step: dt 1 ms, 13 leaks, 103
// fail-safe activations, particles at 319 m/s, nodes at 930 m/s; dt 4 ms, 175 leaks, 749 fail-safe, nodes at
// 2,506 m/s. Step by step (a probe on branch wip/carried-water): Bullet's step raises the cloth's kinetic
// energy 30-300% per step once the coupler's corrections move a wet node 20-60 mm against its links per step;
// the coupler then lowers it again, a two-step oscillation that grows (partitioned coupling of a light
// structure with a heavy fluid: the added-mass instability). Branch wip/carried-sub meets this test's speed,
// leak and fail-safe bounds at dt 1 ms in a probe (particles 5.4 m/s, nodes 4.4 m/s, 0 leaks, 0 fail-safe;
// 4 cloth sub-steps) with the fluid side seeing the cloth as kinematic, the cloth's share of every impulse
// given at its next step, and the water near the cloth carried as node mass (rest lengths kept, as
// set_node_masses does). At dt 4 ms particles still reach 18 m/s, splashing off the jet's impact in the fluid
// step; a nearly rigid cloth (1,000 kg/m^2) splashes at 20 m/s there too.
TEST(JetOnCloth, DISABLED_NeverLeaksWithContinuousHandling) {
  // Nothing can go faster than twice the jet speed plus a free fall from the nozzle to the kill plane.
  const double speed_limit = 2.0 * (3.0 + std::sqrt(2.0 * 9.81 * 0.65));
  for (double dt : {0.001, 0.004}) {
    const RunFigures r = run(reduced_jet_on_cloth(dt, true));
    EXPECT_EQ(r.leaks, 0u) << "dt " << dt;
    EXPECT_EQ(r.created, 2000u) << "dt " << dt;
    EXPECT_EQ(r.alive + r.removed, r.created) << "particles are conserved except kill-plane removals";
    EXPECT_GT(r.ccd_impacts + r.obstacle_stops, 0u) << "dt " << dt;
    EXPECT_LE(1000 * r.failsafe, r.ccd_impacts) << "fail-safe at most 0.1% of impacts, dt " << dt;
    EXPECT_LT(r.fastest_particle, speed_limit) << "dt " << dt;
    EXPECT_LT(r.fastest_node, speed_limit) << "dt " << dt;
    RecordProperty("ccd_impacts_dt_" + std::to_string(dt), static_cast<int>(r.ccd_impacts));
  }
}

TEST(JetOnCloth, LeaksWithRepulsionOnlyAtALargeStep) {
  // The paper's Fig. 4, left: repulsion alone lets particles through.
  EXPECT_GT(run(reduced_jet_on_cloth(0.004, false)).leaks, 0u);
}

/// A puddle of water (16 x 3 x 16 particles, 5 mm spacing) placed on a 0.3 m cloth of 21 x 21 nodes pinned at
/// its corners, one cloth thickness above it, g = -9.81.
SceneConfig puddle(bool with_water) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  if (with_water) {
    EmitterSettings box;
    box.kind = EmitterSettings::Kind::BOX;
    box.box.min = Vec3(-0.04, 0.001, -0.04);
    box.box.max = Vec3(0.04, 0.001 + 0.015, 0.04);
    c.emitters.push_back(box);
  }
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.3;
  cloth.nodes_x = cloth.nodes_z = 21;
  cloth.damping = 0.05;  // settles in the simulated time
  c.cloth = cloth;
  c.time.dt = 0.001;
  c.time.duration = 1.0;
  c.effects = {"viscosity", "coupling"};
  return c;
}

/// Distance from x to the closest point of the cloth mesh (end positions).
double distance_to_cloth(const Vec3& x, const ClothMesh& mesh) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : mesh.triangles) {
    const Vec3& a = mesh.positions_t1[t[0]];
    const Vec3& b = mesh.positions_t1[t[1]];
    const Vec3& c = mesh.positions_t1[t[2]];
    const Vec3 w = closest_point_barycentric(x, a, b, c);
    best = std::min(best, (x - (w[0] * a + w[1] * b + w[2] * c)).norm());
  }
  return best;
}

TEST(JetOnCloth, ARestingPuddlePassesItsWeightToTheCloth) {
  Simulation empty(puddle(false), bullet::cloth_engine_factory());
  Simulation wet(puddle(true), bullet::cloth_engine_factory());
  const double mass = wet.fluid().particle_mass() * static_cast<double>(wet.particles().size());
  ASSERT_GT(wet.particles().size(), 500u);
  // Settle for 0.8 s, then average the vertical impulse on the cloth over the last 0.2 s.
  double impulse_before = 0.0;
  std::int64_t steps_measured = 0;
  while (!wet.finished()) {
    ASSERT_TRUE(wet.step().ok());
    ASSERT_TRUE(empty.step().ok());
    if (wet.time() <= 0.8 + 1e-9) {
      impulse_before = wet.coupling_stats().vertical_impulse_on_cloth;
    } else {
      ++steps_measured;
    }
  }
  const double dt = 0.001;
  const double per_step = (wet.coupling_stats().vertical_impulse_on_cloth - impulse_before) / steps_measured;
  // The cloth is pushed down by the water's weight: -M g dt in y per step, within 5%.
  EXPECT_NEAR(per_step, -mass * 9.81 * dt, 0.05 * mass * 9.81 * dt);
  RecordProperty("impulse_per_step_over_m_g_dt", std::to_string(-per_step / (mass * 9.81 * dt)));
  EXPECT_EQ(wet.coupling_stats().failsafe_activations, 0u);

  // The wet cloth's centre node sags below the empty one's.
  const std::size_t centre = (21 * 21) / 2;
  EXPECT_LT(wet.cloth()->mesh().positions_t1[centre].y(),
            empty.cloth()->mesh().positions_t1[centre].y() - 1e-3);

  // The bottom layer of the puddle rests about one cloth thickness above the cloth.
  std::vector<double> bottom;
  for (const Vec3& x : wet.particles().positions) {
    const double d = distance_to_cloth(x, wet.cloth()->mesh());
    if (d < 0.5 * 0.005) bottom.push_back(d);
  }
  ASSERT_GT(bottom.size(), 50u);
  std::nth_element(bottom.begin(), bottom.begin() + bottom.size() / 2, bottom.end());
  const double median = bottom[bottom.size() / 2];
  RecordProperty("median_distance_over_thickness", std::to_string(median / 0.001));
  EXPECT_GE(median, 0.5 * 0.001);
  EXPECT_LE(median, 1.5 * 0.001);
}

}  // namespace
}  // namespace drench
