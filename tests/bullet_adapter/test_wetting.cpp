// The wet cloth with Bullet (issue 27, paper Fig. 9): the mass balance of a coupled scene with wetting, and
// the extra weight of the water in Bullet's nodes.

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/scene/simulation.hpp>

#include "bullet_test_helpers.hpp"

namespace drench {
namespace {

/// A 0.3 m cloth of 21 x 21 nodes pinned at its corners under a 3 m/s jet of 1,000 particles, 0.1 s,
/// with wetting. No kill region: every kilogram stays in the scene.
SceneConfig wet_jet(const WettingSettings& wetting) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0, 0.1, 0);
  jet.nozzle.radius = 0.02;
  jet.nozzle.speed = 3.0;
  jet.nozzle.max_particles = 1000;
  c.emitters.push_back(jet);
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.3;
  cloth.nodes_x = cloth.nodes_z = 21;
  cloth.substeps = 4;
  c.cloth = cloth;
  c.time.dt = 0.001;
  c.time.duration = 0.1;
  c.wetting = wetting;
  c.effects = {"viscosity", "coupling", "leak_audit", "wetting"};
  return c;
}

double fluid_mass(const Simulation& sim) {
  const ScalarArray& m = sim.particles().masses;
  return std::accumulate(m.begin(), m.end(), 0.0);
}

TEST(Wetting, EveryKilogramIsInTheFluidOrInTheClothAndNothingLeaks) {
  WettingSettings wetting;
  wetting.max_saturation = 20.0;     // room for several particles per node,
  wetting.absorption_rate = 1000.0;  // taken whole in one step: particles are removed
  Simulation sim(wet_jet(wetting), bullet::cloth_engine_factory());
  const double dry_cloth = sim.cloth()->total_mass();
  while (!sim.finished()) {
    ASSERT_TRUE(sim.step().ok()) << "step " << sim.steps_done();
    const double total = fluid_mass(sim) + sim.wetting()->held();
    ASSERT_NEAR(total, sim.emitted_mass(), 1e-9 * sim.emitted_mass()) << "step " << sim.steps_done();
  }
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  EXPECT_GT(sim.wetting_stats().particles_absorbed, 0u);
  EXPECT_GT(sim.wetting()->held(), 0.0);
  EXPECT_NEAR(sim.wetting_stats().absorbed_kg - sim.wetting_stats().dripped_kg, sim.wetting()->held(),
              1e-9 * sim.wetting()->held());
  // Bullet's nodes carry the water: the cloth's mass (unpinned nodes) grew by the water they hold.
  double held_unpinned = 0.0;
  const ClothMesh& mesh = sim.cloth()->mesh();
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if (mesh.inverse_masses[i] > 0.0) held_unpinned += sim.wetting()->water()[i];
  EXPECT_NEAR(sim.cloth()->total_mass(), dry_cloth + held_unpinned,
              bullet::test::bullet_tolerance(1e-12, dry_cloth + held_unpinned, 64.0 * 441));
  ::testing::Test::RecordProperty("held_by_cloth_kg", std::to_string(sim.wetting()->held()));
  ::testing::Test::RecordProperty("particles_absorbed",
                                  static_cast<int>(sim.wetting_stats().particles_absorbed));
}

TEST(Wetting, AClothWetInItsMiddleSagsLowerThanTheDryOne) {
  ClothSettings settings = bullet::test::patch_settings(21, 21);
  settings.size_x = settings.size_z = 0.3;
  settings.center = Vec3::Zero();
  bullet::BulletCloth dry(settings, Vec3(0, -9.81, 0));
  bullet::BulletCloth wet(settings, Vec3(0, -9.81, 0));
  // Water in the middle third, three times the dry node mass (2.0e-5 kg per node of the 15 mm grid):
  // what the jet leaves in a cloth of max_saturation 3.
  const ClothMesh& mesh = wet.mesh();
  const double node_mass = 0.2 * 0.015 * 0.015;
  ScalarArray water(mesh.node_count(), 0.0);
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    const Vec3& x = mesh.positions_t0[i];
    if (std::abs(x.x()) < 0.05 + 1e-9 && std::abs(x.z()) < 0.05 + 1e-9) water[i] = 3.0 * node_mass;
  }
  wet.set_water_masses(water);
  // The undamped cloth swings about its rest shape: the sag is the centre's mean depth over the second
  // second.
  const std::size_t centre = (21 * 21) / 2;
  double sag_dry = 0.0, sag_wet = 0.0;
  for (int s = 0; s < 2000; ++s) {
    for (bullet::BulletCloth* cloth : {&dry, &wet}) {
      cloth->begin_step();
      cloth->step(0.001);
      cloth->end_step(0.001);
    }
    if (s >= 1000) {
      sag_dry -= dry.mesh().positions_t1[centre].y() / 1000.0;
      sag_wet -= wet.mesh().positions_t1[centre].y() / 1000.0;
    }
  }
  ::testing::Test::RecordProperty("sag_dry_mm", std::to_string(1e3 * sag_dry));
  ::testing::Test::RecordProperty("sag_wet_mm", std::to_string(1e3 * sag_wet));
  // A position-based cloth under its own weight sags by the stretch its links allow; the heavier middle
  // pulls the links around it longer: at least 10% more sag (measured: see the recorded properties).
  EXPECT_GT(sag_wet, 1.1 * sag_dry) << "dry " << sag_dry << " m, wet " << sag_wet << " m";
  // Pinned corners stay put.
  EXPECT_EQ(wet.mesh().positions_t1[0], mesh.positions_t0[0]);
}

TEST(Wetting, WaterMassesAreCheckedAndPinnedNodesStayPinned) {
  bullet::BulletCloth cloth(bullet::test::patch_settings(5, 5), Vec3(0, -9.81, 0));
  const double dry_node = 1.0 / cloth.mesh().inverse_masses[12];
  EXPECT_THROW(cloth.set_water_masses(ScalarArray(3, 0.0)), std::invalid_argument);
  ScalarArray water(25, 1e-3);
  water[7] = -1.0;
  EXPECT_THROW(cloth.set_water_masses(water), std::invalid_argument);
  water[7] = 1e-3;
  cloth.set_water_masses(water);
  cloth.begin_step();
  for (std::size_t i = 0; i < 25; ++i) {
    const bool corner = i == 0 || i == 4 || i == 20 || i == 24;
    EXPECT_EQ(cloth.mesh().inverse_masses[i] == 0.0, corner) << "node " << i;
  }
  // Twice: the water replaces, it does not add up.
  cloth.set_water_masses(water);
  cloth.begin_step();
  EXPECT_NEAR(1.0 / cloth.mesh().inverse_masses[12], dry_node + 1e-3,
              bullet::test::bullet_tolerance(1e-12, dry_node, 8.0));
}

}  // namespace

/// The water of every node of `cloth` as set_water_masses takes it: `per_node` times (1 + its index mod 5)
/// for the first `wet` nodes, none for the rest (a tear's new nodes).
ScalarArray some_water(const bullet::BulletCloth& cloth, std::size_t wet, double per_node) {
  ScalarArray water(cloth.mesh().node_count(), 0.0);
  for (std::size_t i = 0; i < wet; ++i)
    water[i] = per_node * static_cast<double>(1 + i % 5);
  return water;
}

/// The water on the nodes Bullet moves (pinned ones weigh nothing in Bullet).
double moving_water(const bullet::BulletCloth& cloth, const ScalarArray& water) {
  double sum = 0.0;
  for (std::size_t i = 0; i < water.size(); ++i)
    if (cloth.mesh().inverse_masses[i] > 0.0) sum += water[i];
  return sum;
}

// A wet cloth torn by Bullet's refine, which makes its new nodes of its old nodes' wet masses: the dry masses
// follow, so the cloth weighs its dry mass plus its water after the tear, also when it is torn twice before
// the water is set again; a cutLink's new nodes weigh Bullet's 1 kg each, dry.
TEST(Wetting, ATornClothWeighsItsDryMassPlusItsWater) {
  bullet::BulletCloth cloth(bullet::test::patch_settings(9, 9), Vec3(0, -9.81, 0));
  const double dry = cloth.total_mass();
  const std::size_t nodes = cloth.mesh().node_count();
  const ScalarArray water = some_water(cloth, nodes, 2e-4);
  cloth.set_water_masses(water);
  const double wet = moving_water(cloth, water);
  ASSERT_NEAR(cloth.total_mass(), dry + wet, bullet::test::bullet_tolerance(1e-12, dry + wet, 4.0 * 81));
  bullet::test::refine_across(cloth.body(), 0.12);
  cloth.begin_step();
  bullet::test::refine_across(cloth.body(), -0.05);  // torn again before the water is set
  cloth.begin_step();
  ASSERT_GT(cloth.mesh().node_count(), nodes + 16) << "two cuts across 9 rows";
  cloth.set_water_masses(some_water(cloth, nodes, 2e-4));
  const std::size_t now = cloth.mesh().node_count();
  EXPECT_NEAR(cloth.total_mass(), dry + wet, bullet::test::bullet_tolerance(1e-12, dry + wet, 16.0 * now))
      << "dry " << dry << " kg, water " << wet << " kg";

  bullet::BulletCloth cut(bullet::test::patch_settings(9, 9), Vec3(0, -9.81, 0));
  cut.set_water_masses(water);
  ASSERT_TRUE(cut.body().cutLink(40, 41, 0.5)) << "the middle node and the next along x";
  cut.begin_step();
  ASSERT_EQ(cut.mesh().node_count(), nodes + 2);
  cut.set_water_masses(some_water(cut, nodes, 2e-4));
  EXPECT_NEAR(cut.total_mass(), dry + wet + 2.0, bullet::test::bullet_tolerance(1e-12, 2.0, 4.0 * 83));
}

}  // namespace drench
