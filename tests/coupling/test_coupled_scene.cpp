// A whole scene through Simulation with a rigid cloth engine (no Bullet): a jet onto a static patch, the
// paper's rigid-mesh case (sec. 6's V-shaped plane is the same thing). Checks the pipeline end to end.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <drench/scene/simulation.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

/// A static patch as a ClothEngine: every node pinned, nothing moves.
class RigidPatch final : public ClothEngine {
 public:
  explicit RigidPatch(const ClothSettings& s) {
    m_mesh = test::grid_mesh(s.nodes_x, s.size_x, s.center.y(), 0.0, s.center.x() - s.size_x / 2,
                             s.center.z() - s.size_z / 2);
  }
  void begin_step() override { m_mesh.positions_t0 = m_mesh.positions_t1; }
  void apply_impulses(const Vec3Array&) override {}
  void set_carried_masses(const ScalarArray&) override {}
  void step(double) override {}
  ClothMesh& mesh() override { return m_mesh; }
  void end_step(double) override {}
  Vec3Array velocities() const override { return Vec3Array(m_mesh.node_count(), Vec3::Zero()); }
  double total_mass() const override { return 0.0; }

 private:
  ClothMesh m_mesh;
};

SceneConfig jet_on_plate(double dt, bool continuous) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0, 0.1, 0);
  jet.nozzle.radius = 0.01;
  jet.nozzle.speed = 3.0;
  jet.nozzle.max_particles = 1500;
  c.emitters.push_back(jet);
  KillRegionSettings kill;
  kill.point = Vec3(0, -0.2, 0);
  c.kill_regions.push_back(kill);
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.2;
  cloth.nodes_x = cloth.nodes_z = 11;
  c.cloth = cloth;
  c.coupling.continuous = continuous;
  c.time.dt = dt;
  c.time.duration = 0.15;
  c.effects = {"coupling", "leak_audit"};
  return c;
}

// At 4 ms the 3 m/s jet moves 2.4 spacings per step, so the coupler stops whole layers at once; the speed
// bound below catches a splash from the compressed fluid.
TEST(CoupledScene, JetOnAStaticPlateNeverLeaks) {
  for (double dt : {0.001, 0.004}) {
    Simulation sim(jet_on_plate(dt, true),
                   [](const ClothSettings& s, const Vec3&) { return std::make_unique<RigidPatch>(s); });
    while (!sim.finished())
      ASSERT_TRUE(sim.step().ok());
    EXPECT_EQ(sim.leak_stats().leaks, 0u) << "dt " << dt;
    EXPECT_GT(sim.coupling_stats().contacts, 0u) << "dt " << dt;
    EXPECT_EQ(sim.coupling_stats().failsafe_activations, 0u) << "dt " << dt;
    // No splash faster than twice what the jet can reach by falling (3 m/s + sqrt(2 g 0.1 m)): at 4 ms a jet
    // stopped only once per step piles its layers up and splashes at several times that.
    double fastest = 0.0;
    for (const Vec3& v : sim.particles().velocities)
      fastest = std::max(fastest, v.norm());
    EXPECT_LT(fastest, 2.0 * (3.0 + std::sqrt(2.0 * 9.81 * 0.1))) << "dt " << dt;
    // Every particle rests on or above the plate (y = 0) or left sideways beyond its edges.
    for (const Vec3& x : sim.particles().positions) {
      if (std::abs(x.x()) < 0.1 && std::abs(x.z()) < 0.1) {
        EXPECT_GT(x.y(), 0.0);
      }
    }
  }
}

TEST(CoupledScene, JetLeaksThroughAStaticPlateWithRepulsionOnly) {
  Simulation sim(jet_on_plate(0.004, false),
                 [](const ClothSettings& s, const Vec3&) { return std::make_unique<RigidPatch>(s); });
  while (!sim.finished())
    ASSERT_TRUE(sim.step().ok());
  EXPECT_GT(sim.leak_stats().leaks, 0u) << "the audit must see what repulsion alone lets through (Fig. 4)";
}

}  // namespace
}  // namespace drench
