// A whole scene through Simulation with a rigid cloth engine (no Bullet): a jet onto a static patch, the
// paper's rigid-mesh case (sec. 6's V-shaped plane is the same thing). Checks the pipeline end to end.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

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

// A leak is never silent (issue 39): the step that leaks says LEAKED, names a particle that did cross the
// plate (y = 0, from above to below, within its edges) and a face of it, and the run counts as failed.
TEST(CoupledScene, AStepThatLeaksSaysSoAndNamesTheParticleAndFace) {
  Simulation sim(jet_on_plate(0.004, false),
                 [](const ClothSettings& s, const Vec3&) { return std::make_unique<RigidPatch>(s); });
  std::uint64_t leaks_before = 0;
  bool named = false;
  while (!sim.finished() && !named) {
    const StepStatus status = sim.step();
    ASSERT_TRUE(status.ok()) << status.describe();
    const bool leaked = sim.leak_stats().leaks > leaks_before;
    leaks_before = sim.leak_stats().leaks;
    ASSERT_EQ(leaked, (status.flags & StepStatus::LEAKED) != 0) << "at step " << sim.steps_done();
    if (!leaked) {
      EXPECT_FALSE(status.failed());
      continue;
    }
    EXPECT_TRUE(status.failed());
    EXPECT_NE(status.describe().find("LEAKED: particle id " + std::to_string(status.leaked_particle)),
              std::string::npos)
        << status.describe();
    ASSERT_GE(status.leaked_triangle, 0);
    ASSERT_LT(status.leaked_triangle, static_cast<std::int64_t>(sim.contact_mesh()->triangle_count()));
    const ParticleSet& p = sim.particles();
    const auto it = std::find(p.ids.begin(), p.ids.end(), static_cast<std::uint32_t>(status.leaked_particle));
    ASSERT_NE(it, p.ids.end()) << "the named particle is not in the fluid";
    const std::size_t i = static_cast<std::size_t>(it - p.ids.begin());
    EXPECT_GT(p.positions_t0[i].y(), 0.0);
    EXPECT_LT(p.positions[i].y(), 0.0);
    named = true;
  }
  EXPECT_TRUE(named) << "no step leaked: the scene no longer tests the LEAKED status";
}

/// A patch whose engine moves node `node` by `displacement` in every step and reports `velocity` for it: a
/// cloth blowing up, as far as the coupled step can tell.
class BlowingUpPatch final : public ClothEngine {
 public:
  BlowingUpPatch(const ClothSettings& s, Index node, const Vec3& displacement, const Vec3& velocity)
      : m_node(node), m_displacement(displacement), m_velocity(velocity) {
    m_mesh = test::grid_mesh(s.nodes_x, s.size_x, s.center.y(), 1.0, s.center.x() - s.size_x / 2,
                             s.center.z() - s.size_z / 2);
  }
  void begin_step() override { m_mesh.positions_t0 = m_mesh.positions_t1; }
  void apply_impulses(const Vec3Array&) override {}
  void set_carried_masses(const ScalarArray&) override {}
  void step(double) override { m_mesh.positions_t1[m_node] += m_displacement; }
  ClothMesh& mesh() override { return m_mesh; }
  void end_step(double) override {}
  Vec3Array velocities() const override {
    Vec3Array v(m_mesh.node_count(), Vec3::Zero());
    v[m_node] = m_velocity;
    return v;
  }
  double total_mass() const override { return 1.0; }

 private:
  ClothMesh m_mesh;
  Index m_node;
  Vec3 m_displacement, m_velocity;
};

// The cloth's blow-up checks beside fluid.max_speed (issue 39): a node faster than cloth.max_speed stops
// the run as RUNAWAY_NODE naming it; an edge stretched beyond cloth.max_strain as CLOTH_OVERSTRETCHED naming
// its nodes; within the limits, or with the limits off (null), nothing is said.
TEST(CoupledScene, ABlownUpClothStopsTheRunNamingTheNodeOrEdge) {
  SceneConfig config = jet_on_plate(0.001, true);
  config.cloth->max_speed = 50.0;
  config.cloth->max_strain = 1.2;
  const auto run = [&](const SceneConfig& c, const Vec3& displacement, const Vec3& velocity) {
    Simulation sim(c, [&](const ClothSettings& s, const Vec3&) {
      return std::make_unique<BlowingUpPatch>(s, 5, displacement, velocity);
    });
    StepStatus status;
    for (int i = 0; i < 5 && status.ok(); ++i)
      status |= sim.step();
    return std::make_pair(status, sim.max_cloth_strain());
  };
  // Node 5 of the 11 x 11 patch (0.02 m edges) at 60 m/s, not moving: over the speed limit only.
  auto [fast, fast_strain] = run(config, Vec3::Zero(), Vec3(0, 60, 0));
  EXPECT_EQ(fast.flags & (StepStatus::RUNAWAY_NODE | StepStatus::CLOTH_OVERSTRETCHED),
            StepStatus::RUNAWAY_NODE);
  EXPECT_FALSE(fast.ok());
  EXPECT_EQ(fast.runaway_node, 5);
  EXPECT_DOUBLE_EQ(fast.runaway_node_speed, 60.0);
  EXPECT_NE(fast.describe().find("RUNAWAY_NODE: cloth node 5 moved at 60 m/s"), std::string::npos)
      << fast.describe();
  EXPECT_EQ(fast_strain, 0.0);
  // Node 5 pulled 1 cm along -z per step at 1 m/s, away from node 16 (its neighbour along z, 0.02 m): their
  // edge reaches a strain of 0.5 after one step, 1.0 after two, 1.5 after three, over the limit of 1.2.
  auto [torn, torn_strain] = run(config, Vec3(0, 0, -0.01), Vec3(0, 0, -1));
  EXPECT_EQ(torn.flags & (StepStatus::RUNAWAY_NODE | StepStatus::CLOTH_OVERSTRETCHED),
            StepStatus::CLOTH_OVERSTRETCHED);
  EXPECT_EQ(torn.overstretched_edge[0], 5);
  EXPECT_EQ(torn.overstretched_edge[1], 16);
  EXPECT_NEAR(torn.edge_strain, 1.5, 1e-9);
  EXPECT_NEAR(torn_strain, 1.5, 1e-9);
  EXPECT_NE(torn.describe().find("CLOTH_OVERSTRETCHED: the cloth edge between nodes 5 and 16"),
            std::string::npos)
      << torn.describe();
  // The same cloths with the limits off: five steps, no flag; the strain is still measured.
  config.cloth->max_speed.reset();
  config.cloth->max_strain.reset();
  EXPECT_TRUE(run(config, Vec3::Zero(), Vec3(0, 60, 0)).first.ok());
  const auto [off, off_strain] = run(config, Vec3(0, 0, -0.01), Vec3(0, 0, -1));
  EXPECT_TRUE(off.ok());
  EXPECT_NEAR(off_strain, 2.5, 1e-9);
}

/// A free square sheet (no pins, no forces) and a free box under it that its engine steps together, as
/// Bullet steps a cloth with a body: the sheet's nodes cannot go below the box's top face plus `margin`,
/// and a node that would is stopped there by an inelastic impulse whose opposite the box takes (Bullet's
/// soft-rigid contact, in small). Everything conserves linear momentum, so what the coupling does is all
/// that can change the total.
struct SheetOverBox {
  ClothMesh sheet;
  Vec3Array v;            // the sheet's node velocities (unit: m/s)
  ScalarArray carried;    // the water's mass on each node for the current step (unit: kg)
  Vec3Array predicted;    // the nodes' end positions as step() left them (unit: m)
  Vec3 centre, half;      // the box (unit: m)
  Vec3 velocity;          // the box's (unit: m/s)
  double box_mass = 1.0;  // (unit: kg)
  double margin = 0.0;    // (unit: m)

  double node_mass(std::size_t i) const { return 1.0 / sheet.inverse_masses[i]; }
  Vec3Array box_nodes() const {
    Vec3Array x(8);
    for (int c = 0; c < 8; ++c)
      x[c] = centre + half.cwiseProduct(Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1));
    return x;
  }
  void step(double dt) {
    centre += velocity * dt;
    const double top = centre.y() + half.y() + margin;
    for (std::size_t i = 0; i < sheet.node_count(); ++i) {
      Vec3& x = sheet.positions_t1[i];
      x = sheet.positions_t0[i] + v[i] * dt;
      if (x.y() >= top) continue;
      // The node with its carried water (carried_water.hpp) stops on the face: it takes the box's normal
      // velocity, the box the opposite impulse.
      const double impulse = (node_mass(i) + carried[i]) * (velocity.y() - v[i].y());
      v[i].y() = velocity.y();
      velocity.y() -= impulse / box_mass;
      x.y() = top;
    }
    predicted = sheet.positions_t1;
    carried.assign(sheet.node_count(), 0.0);
  }
};

class SheetEngine final : public ClothEngine {
 public:
  explicit SheetEngine(SheetOverBox& world) : m_world(world) {}
  void begin_step() override { m_world.sheet.positions_t0 = m_world.sheet.positions_t1; }
  void apply_impulses(const Vec3Array& impulses) override {
    for (std::size_t i = 0; i < m_world.v.size(); ++i)
      m_world.v[i] += impulses[i] / (m_world.node_mass(i) + m_world.carried[i]);
  }
  void set_carried_masses(const ScalarArray& carried) override { m_world.carried = carried; }
  void step(double dt) override { m_world.step(dt); }
  ClothMesh& mesh() override { return m_world.sheet; }
  void end_step(double dt) override {
    for (std::size_t i = 0; i < m_world.v.size(); ++i)
      m_world.v[i] += (m_world.sheet.positions_t1[i] - m_world.predicted[i]) / dt;
  }
  Vec3Array velocities() const override { return m_world.v; }
  double total_mass() const override { return 0.0; }

 private:
  SheetOverBox& m_world;
};

/// A box body's surface at the start of a step (key 1): 12 triangles counter-clockwise seen from outside
/// over its 8 corners (corner c at centre + half * (+-1, +-1, +-1) by its bits x, y, z), every corner moving
/// at `velocity` (unit: m/s); positions_t1 = positions_t0.
RigidSurface box_surface(RigidMotion motion, const Vec3Array& corners, const Vec3& velocity) {
  RigidSurface s;
  s.key = 1;
  s.motion = motion;
  const Index quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    s.triangles.push_back({q[0], q[1], q[2]});
    s.triangles.push_back({q[0], q[2], q[3]});
  }
  s.positions_t0 = s.positions_t1 = corners;
  s.velocities_t0.assign(corners.size(), velocity);
  return s;
}

class BoxBody final : public RigidBodySource {
 public:
  explicit BoxBody(SheetOverBox& world) : m_world(world) {}
  void begin_step(std::vector<RigidSurface>& surfaces) override {
    surfaces.assign(1, box_surface(RigidMotion::DYNAMIC, m_world.box_nodes(), m_world.velocity));
  }
  void step(double) override {}  // the sheet's engine steps the box
  void end_positions(std::vector<RigidSurface>& surfaces) override {
    surfaces[0].positions_t1 = m_world.box_nodes();
  }
  void apply_impulses(std::size_t, const RigidSurface& surface, const Vec3* node_impulses) override {
    for (std::size_t i = 0; i < surface.positions_t0.size(); ++i)
      m_world.velocity += node_impulses[i] / m_world.box_mass;
  }

 private:
  SheetOverBox& m_world;
};

/// The level's last resorts in small (issue 41: water caught between a ball and the hammock): a layer of
/// water between a free sheet falling at 0.5 m/s and a box rising at 0.5 m/s, no gravity, the default
/// "carried_water" scheme, which shows the coupler the sheet's nodes and the box's as kinematic. The water is
/// squeezed until the fail-safe and the impact zones act.
struct Squeeze {
  static constexpr double kDt = 0.004;
  SheetOverBox world;
  std::unique_ptr<BoxBody> box;
  std::unique_ptr<Simulation> sim;

  Squeeze() {
    world.sheet = test::grid_mesh(9, 0.12, 0.015, 1.0 / 0.01, -0.06, -0.06);  // 10 g nodes
    world.v.assign(world.sheet.node_count(), Vec3(0.0, -0.5, 0.0));
    world.carried.assign(world.sheet.node_count(), 0.0);
    world.centre = Vec3(0.0, -0.015, 0.0);
    world.half = Vec3(0.06, 0.01, 0.06);  // the top face at y = -0.005
    world.velocity = Vec3(0.0, 0.5, 0.0);
    world.margin = 0.001;  // the cloth thickness: the water is squeezed out of the gap
    SceneConfig config;
    config.gravity = Vec3::Zero();
    config.fluid.particle_spacing = 0.01;
    config.time.dt = kDt;
    config.time.duration = 30 * kDt;
    config.effects = {"coupling", "leak_audit"};
    EmitterSettings layer;  // 6 x 6 particles at y = 0.005
    layer.box.min = Vec3(-0.03, 0.0, -0.03);
    layer.box.max = Vec3(0.03, 0.01, 0.03);
    config.emitters.push_back(layer);
    box = std::make_unique<BoxBody>(world);
    sim = std::make_unique<Simulation>(config, std::make_unique<SheetEngine>(world),
                                       std::vector<TriangleMesh>{}, box.get());
  }
  /// The ids of the particles inside the box where its engine holds it: deeper than `depth` (unit: m)
  /// behind every face.
  std::set<std::uint32_t> inside_box(double depth) const {
    std::set<std::uint32_t> inside;
    const ParticleSet& p = sim->particles();
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (((world.half - (p.positions[i] - world.centre).cwiseAbs()).array() > depth).all())
        inside.insert(p.ids[i]);
    }
    return inside;
  }
};

// The impact zones take the box's motion as given: a zone holding the box's nodes gives its water and the
// sheet's nodes the box's motion, so the box's faces end where its engine puts them and no water enters the
// box (a signed distance below -1e-9 m to every face: rounding is less). The leak audit between steps
// (audit_face_jumps) would count any: when the zones moved the box's nodes by the zone's mean displacement,
// all 36 particles entered the box and it counted each.
TEST(CoupledScene, ImpactZonesLeaveNoWaterInsideABox) {
  Squeeze squeeze;
  Simulation& sim = *squeeze.sim;
  std::set<std::uint32_t> entered;
  while (!sim.finished()) {
    ASSERT_TRUE(sim.step().ok());
    const std::set<std::uint32_t> inside = squeeze.inside_box(1e-9);
    entered.insert(inside.begin(), inside.end());
  }
  ASSERT_GT(sim.coupling_stats().stopped_particles, 0u) << "the squeeze must reach the impact zones";
  EXPECT_TRUE(entered.empty()) << entered.size() << " particles entered the box";
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  EXPECT_EQ(sim.coupling_stats().zone_ignored_shift, 0.0);  // the box's nodes never moved
  EXPECT_EQ(sim.coupling_stats().squeezed_out, 0u);         // one fixed motion: none is squeezed out
}

// The zones move the sheet's nodes, which its engine takes as a velocity: water, sheet, box, what the sheet
// is owed and the water squeezed out keep their momentum to rounding.
TEST(CoupledScene, WaterSqueezedBetweenABoxAndASheetKeepsTheMomentum) {
  Squeeze squeeze;
  Simulation& sim = *squeeze.sim;
  SheetOverBox& world = squeeze.world;
  const auto momentum = [&] {
    const ParticleSet& p = sim.particles();
    Vec3 total = world.box_mass * world.velocity;
    for (std::size_t i = 0; i < p.size(); ++i)
      total += p.masses[i] * p.velocities[i];
    for (std::size_t i = 0; i < world.v.size(); ++i)
      total += world.node_mass(i) * world.v[i];
    for (const Vec3& owed : sim.pending_cloth_impulses())
      total += owed;
    return Vec3(total + sim.coupling_stats().squeezed_out_momentum);
  };
  ASSERT_TRUE(sim.step().ok());  // emits the water
  const Vec3 start = momentum();
  double drift = 0.0;
  while (!sim.finished()) {
    const StepStatus status = sim.step();
    ASSERT_TRUE(status.ok()) << "step " << sim.steps_done() << ": " << status.describe();
    drift = std::max(drift, (momentum() - start).norm());
  }
  const CouplingStepStats& stats = sim.coupling_stats();
  std::printf(
      "[ measured ] %llu fail-safe particles, %llu in zones, zones' moves owed back to the sheet %.3g N s, "
      "moved the box by %.3g m, largest drift %.3g N s\n",
      static_cast<unsigned long long>(stats.failsafe_activations),
      static_cast<unsigned long long>(stats.stopped_particles), stats.zone_cloth_momentum,
      stats.zone_ignored_shift, drift);
  ASSERT_GT(stats.stopped_particles, 0u) << "the squeeze must reach the impact zones, else it tests nothing";
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  // Rounding (measured 2.3e-9 N s; the water pressed against the box's boundary particles pushes hard):
  // when the zones' moves of the sheet went unbooked, 2.6e-2 N s.
  EXPECT_LT(drift, 1e-7);
}

/// A box the game moves down at a constant speed until its bottom face is `floor` (unit: m) above y = 0:
/// a kinematic body, which takes nothing from the water.
class LoweredBox final : public RigidBodySource {
 public:
  Vec3 centre = Vec3(0.0, 0.025, 0.0), half = Vec3(0.06, 0.01, 0.06);  // the bottom face at y = 0.015
  double speed = 0.5;                                                  // (unit: m/s)
  double floor = 0.0;

  Vec3Array nodes() const {
    Vec3Array x(8);
    for (int c = 0; c < 8; ++c)
      x[c] = centre + half.cwiseProduct(Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1));
    return x;
  }
  void begin_step(std::vector<RigidSurface>& surfaces) override {
    surfaces.assign(1, box_surface(RigidMotion::KINEMATIC, nodes(), Vec3::Zero()));
  }
  void step(double dt) override { centre.y() = std::max(centre.y() - speed * dt, floor + half.y()); }
  void end_positions(std::vector<RigidSurface>& surfaces) override { surfaces[0].positions_t1 = nodes(); }
  void apply_impulses(std::size_t, const RigidSurface&, const Vec3*) override {}
};

// Water under a box the game lowers onto the ground until its bottom face rests on it: no motion keeps a
// particle caught in the closing gap out of both the box and the ground, so the impact zones squeeze it out,
// counted, with its mass booked. No particle ever ends a step inside the box or under the ground (a signed
// distance below -1e-9 m: rounding is less), and none leaks.
TEST(CoupledScene, WaterCaughtBetweenALoweredBoxAndTheGroundIsSqueezedOut) {
  SceneConfig config;
  config.gravity = Vec3::Zero();
  config.fluid.particle_spacing = 0.01;
  config.time.dt = 0.004;
  config.time.duration = 20 * config.time.dt;  // the box reaches its floor after 8 steps
  config.effects = {"coupling", "leak_audit"};
  EmitterSettings layer;  // 6 x 6 particles at y = 0.005
  layer.box.min = Vec3(-0.03, 0.0, -0.03);
  layer.box.max = Vec3(0.03, 0.01, 0.03);
  config.emitters.push_back(layer);
  const ClothMesh grid = test::grid_mesh(9, 0.24, 0.0, 0.0, -0.12, -0.12);
  LoweredBox box;
  Simulation sim(config, nullptr, {TriangleMesh{grid.positions_t0, grid.triangles}}, &box);
  const double particle_mass = sim.fluid().particle_mass();
  std::size_t inside = 0, below = 0, emitted = 0;
  while (!sim.finished()) {
    const StepStatus status = sim.step();
    ASSERT_TRUE(status.ok()) << "step " << sim.steps_done() << ": " << status.describe();
    if (emitted == 0) emitted = sim.particles().size();
    for (const Vec3& x : sim.particles().positions) {
      inside += ((box.half - (x - box.centre).cwiseAbs()).array() > 1e-9).all();
      below += x.y() < -1e-9;
    }
  }
  const CouplingStepStats& stats = sim.coupling_stats();
  std::printf("[ measured ] %llu particles squeezed out of %zu, %llu in zones\n",
              static_cast<unsigned long long>(stats.squeezed_out), emitted,
              static_cast<unsigned long long>(stats.stopped_particles));
  ASSERT_EQ(emitted, 36u);
  EXPECT_GT(stats.squeezed_out, 0u);
  EXPECT_EQ(sim.particles().size() + stats.squeezed_out, emitted);
  EXPECT_NEAR(stats.squeezed_out_mass, static_cast<double>(stats.squeezed_out) * particle_mass,
              1e-12 * particle_mass);
  EXPECT_EQ(sim.removed(), static_cast<std::int64_t>(stats.squeezed_out));
  EXPECT_EQ(inside, 0u);
  EXPECT_EQ(below, 0u);
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  EXPECT_EQ(stats.zone_ignored_shift, 0.0);
}

}  // namespace
}  // namespace drench
