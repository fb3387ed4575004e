// The coupled scene with Bullet cloth (issue 4): a reduced jet-on-cloth never leaks with continuous handling
// and does without it; a resting puddle gives the cloth its weight.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/scene/simulation.hpp>

#include "../temp_dir.hpp"
#include "bullet_test_helpers.hpp"

namespace drench {

using bullet::test::bullet_tolerance;
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

/// The fastest particle and cloth node seen so far (unit: m/s).
struct Fastest {
  double particle = 0.0, node = 0.0;
  void update(const Simulation& sim) {
    for (const Vec3& v : sim.particles().velocities)
      particle = std::max(particle, v.norm());
    for (const Vec3& v : sim.cloth()->velocities())
      node = std::max(node, v.norm());
  }
};

struct RunFigures {
  std::uint64_t leaks, ccd_impacts, obstacle_stops, failsafe, created, alive, removed;
  double fastest_particle, fastest_node;
};

RunFigures run(const SceneConfig& config) {
  Simulation sim(config, bullet::cloth_engine_factory());
  RunFigures r{};
  Fastest fastest;
  while (!sim.finished()) {
    EXPECT_TRUE(sim.step().ok());
    fastest.update(sim);
  }
  r.fastest_particle = fastest.particle;
  r.fastest_node = fastest.node;
  r.leaks = sim.leak_stats().leaks;
  r.ccd_impacts = sim.coupling_stats().ccd_impacts;
  r.obstacle_stops = sim.coupling_stats().obstacle_stops;
  r.failsafe = sim.coupling_stats().failsafe_activations;
  r.created = static_cast<std::uint64_t>(sim.created());
  r.alive = sim.particles().size();
  r.removed = static_cast<std::uint64_t>(sim.removed());
  return r;
}

/// The bounds every coupled jet run must meet: no leak, particles conserved, contact happened, the fail-safe
/// rare, and nothing faster than twice the jet speed plus a free fall from the nozzle to the kill plane.
void expect_sound_jet(const RunFigures& r, const std::string& label) {
  const double speed_limit = 2.0 * (3.0 + std::sqrt(2.0 * 9.81 * 0.65));
  EXPECT_EQ(r.leaks, 0u) << label;
  EXPECT_EQ(r.created, 2000u) << label;
  EXPECT_EQ(r.alive + r.removed, r.created)
      << "particles are conserved except kill-plane removals, " << label;
  EXPECT_GT(r.ccd_impacts + r.obstacle_stops, 0u) << label;
  EXPECT_LE(1000 * r.failsafe, r.ccd_impacts) << "fail-safe at most 0.1% of impacts, " << label;
  EXPECT_LT(r.fastest_particle, speed_limit) << label;
  EXPECT_LT(r.fastest_node, speed_limit) << label;
  ::testing::Test::RecordProperty("fastest_particle_mps_" + label, std::to_string(r.fastest_particle));
  ::testing::Test::RecordProperty("fastest_node_mps_" + label, std::to_string(r.fastest_node));
  ::testing::Test::RecordProperty("ccd_impacts_" + label, static_cast<int>(r.ccd_impacts));
}

// On this light cloth (node mass 4.1e-5 kg, a third of a particle's) the paper's scheme (impulses to both
// sides after both solvers, CouplingScheme::IMPULSES) is unstable: with it this test throws particles and
// nodes at hundreds of m/s or more, with leaks. CouplingScheme::CARRIED_WATER (the default) holds it.
// The cloth takes 4 sub-steps: a position-based cloth under load stretches less.
TEST(JetOnCloth, NeverLeaksWithContinuousHandling) {
  for (auto solver : {PressureSolverKind::WCSPH, PressureSolverKind::PCISPH, PressureSolverKind::DFSPH}) {
    SceneConfig config = reduced_jet_on_cloth(0.001, true);
    config.cloth->substeps = 4;
    config.fluid.pressure_solver = solver;
    expect_sound_jet(run(config), pressure_solver_name(solver));
  }
}

// At dt 4 ms the fluid sub-steps (CFL) inside each step; cloth and coupling do not. The coupling's
// corrections compress the water next to the cloth, and PCISPH as published undoes that inside one CFL
// sub-step, too fast for the next one: PCISPH's max_compression_per_iteration and max_relief_per_substep
// keep this run within its speed bound (bench_jet_on_cloth leaks_continuous_dt_4ms).
TEST(JetOnCloth, NeverLeaksWithContinuousHandlingAtALargeStep) {
  SceneConfig config = reduced_jet_on_cloth(0.004, true);
  config.cloth->substeps = 4;
  expect_sound_jet(run(config), "dt_4ms");
}

// DFSPH as published undoes the coupling's compression inside one CFL sub-step as PCISPH does (the full jet
// scene at dt 4 ms threw particles at 168 m/s); its max_relief_per_substep holds it as PCISPH's does.
TEST(JetOnCloth, NeverLeaksWithContinuousHandlingAtALargeStepDfsph) {
  SceneConfig config = reduced_jet_on_cloth(0.004, true);
  config.cloth->substeps = 4;
  config.fluid.pressure_solver = PressureSolverKind::DFSPH;
  expect_sound_jet(run(config), "dfsph_dt_4ms");
}

// A game's step (issue 41): PBF at 1/60 s in its fixed sub-steps, the cloth in 16 of its own (about 1 ms,
// its stable step under this jet); the exact CCD (eq. 5-6) holds the water at any step.
TEST(JetOnCloth, NeverLeaksAtAGamesStepPbf) {
  SceneConfig config = reduced_jet_on_cloth(1.0 / 60.0, true);
  config.cloth->substeps = 16;
  config.fluid.pressure_solver = PressureSolverKind::PBF;
  expect_sound_jet(run(config), "pbf_dt_60hz");
}

// WCSPH turns the coupling's compression into pressure through the Tait equation's seventh power; its
// max_compression bounds that push; without it this run exceeds its speed bound (docs/accuracy.md, the
// largest step that holds, for the full scene).
TEST(JetOnCloth, NeverLeaksWithContinuousHandlingAtTwiceTheStepWcsph) {
  SceneConfig config = reduced_jet_on_cloth(0.002, true);
  config.cloth->substeps = 4;
  config.fluid.pressure_solver = PressureSolverKind::WCSPH;
  expect_sound_jet(run(config), "wcsph_dt_2ms");
}

// The paper's Tables 1-2 go to a 5 mm thickness, one particle spacing, where the coupling moves the water
// near the cloth the most: without PCISPH's max_compression_per_iteration this run exceeds its speed bound
// and the full scene blows up (bench_jet_on_cloth table_thickness_5mm).
TEST(JetOnCloth, NeverLeaksWithAThickCloth) {
  SceneConfig config = reduced_jet_on_cloth(0.001, true);
  config.cloth->substeps = 4;
  config.coupling.cloth_thickness = 0.005;
  expect_sound_jet(run(config), "thickness_5mm");
}

// Stress (issue 4): a 20 m/s jet at dt 5 ms, the fluid sub-stepping under its CFL limit, cloth and coupling
// not (as the issue sets it: one cloth step per step): the jet crosses 10 cm, 20 disc layers, per step, and
// the whole jet (0.25 kg) lands on the 18 g cloth within two steps; the cloth, this soft at one 5 ms step,
// sinks far under the jet. Not 4 cloth sub-steps: the cloth would rebound from its pins at tens of m/s, and
// the coupler, which keeps the water on its side of the cloth's end positions, would give the water it
// sweeps that speed for a step before the cloth takes the reaction, past the bound.
TEST(JetOnCloth, AFastJetAtALargeStepNeverLeaks) {
  SceneConfig config = reduced_jet_on_cloth(0.005, true);
  config.emitters[0].nozzle.speed = 20.0;
  config.cloth->substeps = 1;
  // This jet tears the cloth numerically (an edge reaches 30 times its length): the default cloth.max_strain
  // stops the run as CLOTH_OVERSTRETCHED, as it should. The test asks that no particle leaks all the same,
  // through a cloth torn that far, so it runs without the strain limit.
  {
    Simulation sim(config, bullet::cloth_engine_factory());
    StepStatus status;
    while (!sim.finished() && status.ok())
      status |= sim.step();
    EXPECT_NE(status.flags & StepStatus::CLOTH_OVERSTRETCHED, 0u) << status.describe();
  }
  config.cloth->max_strain.reset();
  const RunFigures r = run(config);
  // Twice (jet speed + a free fall over the scene's height, nozzle to kill plane).
  const double speed_limit = 2.0 * (20.0 + std::sqrt(2.0 * 9.81 * 0.65));
  EXPECT_EQ(r.leaks, 0u);
  EXPECT_EQ(r.created, 2000u);
  EXPECT_EQ(r.alive + r.removed, r.created);
  EXPECT_GT(r.ccd_impacts + r.obstacle_stops, 0u);
  EXPECT_LT(r.fastest_particle, speed_limit);
  EXPECT_LT(r.fastest_node, speed_limit);
  ::testing::Test::RecordProperty("fastest_particle_mps", std::to_string(r.fastest_particle));
  ::testing::Test::RecordProperty("fastest_node_mps", std::to_string(r.fastest_node));
  ::testing::Test::RecordProperty("removed", static_cast<int>(r.removed));
}

/// The largest strain of a cloth edge over a reduced jet run of 0.4 s at step dt (unit: s) with the cloth in
/// `substeps` steps of its own; expects the run to end ok with 0 leaks.
double max_strain_of_reduced_jet(double dt, int substeps, const std::string& label) {
  SceneConfig config = reduced_jet_on_cloth(dt, true);
  config.cloth->substeps = substeps;
  config.time.duration = 0.4;  // the water piles on the cloth and its stretch grows until then
  Simulation sim(config, bullet::cloth_engine_factory());
  while (!sim.finished())
    EXPECT_TRUE(sim.step().ok()) << label;
  EXPECT_EQ(sim.leak_stats().leaks, 0u) << label;
  ::testing::Test::RecordProperty("max_cloth_strain_" + label, std::to_string(sim.max_cloth_strain()));
  return sim.max_cloth_strain();
}

// Bullet's position-based cloth, at its 4 position iterations, gives under the water's weight by an amount
// set by the length of its own sub-step, not the scene's step: that is why the full jet at dt 8 ms in 4
// cloth sub-steps stretches the edges at its pins past cloth.max_strain and stops as CLOTH_OVERSTRETCHED,
// and holds in 8 (docs/accuracy.md, the largest step that holds). The coupling must add nothing of its own
// that grows with the step: the same cloth sub-step gives the same stretch at dt 4 and 8 ms.
TEST(JetOnCloth, ClothStretchFollowsTheClothSubStepNotTheStep) {
  const double at_4ms_in_4 = max_strain_of_reduced_jet(0.004, 4, "dt_4ms_4_substeps");
  const double at_8ms_in_8 = max_strain_of_reduced_jet(0.008, 8, "dt_8ms_8_substeps");
  const double at_8ms_in_4 = max_strain_of_reduced_jet(0.008, 4, "dt_8ms_4_substeps");
  EXPECT_GT(at_4ms_in_4, 0.1) << "the water loads the cloth";
  EXPECT_NEAR(at_8ms_in_8, at_4ms_in_4, 0.25 * at_4ms_in_4) << "the same 1 ms cloth sub-step";
  EXPECT_GT(at_8ms_in_4, 2.0 * at_4ms_in_4) << "a 2 ms cloth sub-step gives far more";
}

/// Mean relative tangential speed at contact (unit: m/s) of the reduced jet with the given tangential
/// condition (sec. 3.4).
double mean_contact_slip(SlipCondition slip) {
  SceneConfig config = reduced_jet_on_cloth(0.001, true);
  config.cloth->substeps = 4;
  config.coupling.slip = slip;
  config.coupling.friction_coefficient = 0.0;
  config.effects = {"viscosity", "coupling", "friction", "leak_audit"};
  Simulation sim(config, bullet::cloth_engine_factory());
  while (!sim.finished())
    EXPECT_TRUE(sim.step().ok());
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  const CouplingStepStats& c = sim.coupling_stats();
  EXPECT_GT(c.contacts, 1000u);
  return c.slip_sum_mps / static_cast<double>(c.contacts);
}

// The paper's Fig. 5 (demos/scenes/no_slip.json, free_slip.json), reduced: under no-slip (eq. 7) the water at
// contact moves with the cloth; under free slip it keeps sliding.
TEST(JetOnCloth, NoSlipHoldsTheWaterAtContactToTheCloth) {
  const double free_slip = mean_contact_slip(SlipCondition::FRICTION);
  const double no_slip = mean_contact_slip(SlipCondition::NO_SLIP);
  EXPECT_GT(free_slip, 0.1) << "m/s: the jet spreads over the cloth";
  EXPECT_LE(no_slip, 0.01 * free_slip);
  ::testing::Test::RecordProperty("mean_contact_slip_mps_free", std::to_string(free_slip));
  ::testing::Test::RecordProperty("mean_contact_slip_mps_no_slip", std::to_string(no_slip));
}

/// Total linear momentum of particles, cloth nodes (their own masses) and the impulses owed to the cloth.
Vec3 total_momentum(const Simulation& sim) {
  Vec3 total = Vec3::Zero();
  const ParticleSet& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i)
    total += p.masses[i] * p.velocities[i];
  const ClothMesh& mesh = sim.cloth()->mesh();
  const Vec3Array v = sim.cloth()->velocities();
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    total += v[i] / mesh.inverse_masses[i];
  for (const Vec3& j : sim.pending_cloth_impulses())
    total += j;
  return total;
}

// CouplingScheme::CARRIED_WATER exchanges momentum exactly: on a free cloth (nothing pinned, nothing killed,
// no viscosity) the total changes only by what the jet brings in and by gravity on fluid and cloth.
TEST(JetOnCloth, CarriedWaterConservesLinearMomentum) {
  for (double g : {0.0, -9.81}) {
    SceneConfig config = reduced_jet_on_cloth(0.001, true);
    config.cloth->pinned = "none";
    config.cloth->substeps = 4;
    config.fluid.pressure_solver = PressureSolverKind::WCSPH;
    config.kill_regions.clear();
    config.effects = {"coupling"};
    config.gravity = Vec3(0, g, 0);
    config.time.duration = 0.12;  // the jet reaches the cloth at 0.05 s
    Simulation sim(config, bullet::cloth_engine_factory());
    const double particle_mass = sim.fluid().particle_mass();
    const double cloth_mass = sim.cloth()->total_mass();
    Vec3 expected = total_momentum(sim);
    double largest_error = 0.0;
    while (!sim.finished()) {
      const auto before = sim.created();
      ASSERT_TRUE(sim.step().ok());
      const auto emitted = static_cast<double>(sim.created() - before);
      expected += emitted * particle_mass * Vec3(0, -3.0, 0);
      expected += (static_cast<double>(sim.particles().size()) * particle_mass + cloth_mass) *
                  config.time.dt * config.gravity;
      largest_error = std::max(largest_error, (total_momentum(sim) - expected).norm());
    }
    ASSERT_GT(sim.coupling_stats().ccd_impacts + sim.coupling_stats().obstacle_stops, 0u);
    ASSERT_EQ(sim.coupling_stats().failsafe_activations, 0u) << "the fail-safe moves particles without a "
                                                                "counter-impulse";
    // Issue 4: 1e-12 of the jet's momentum (2,000 x 1.25e-4 kg x 3 m/s = 0.75 N s) without gravity. With it,
    // Bullet steps the cloth by float(dt) (1 + 4.7e-8 at 1 ms), so gravity's share differs by about 1e-9 N s,
    // hence the looser tolerance. With single-precision Bullet every cloth velocity also rounds to float at
    // each of the 120 steps.
    const double steps = config.time.duration / config.time.dt;
    const double tolerance = bullet_tolerance(g == 0.0 ? 1e-12 * 0.75 : 1e-8 * 0.75, steps * 0.75);
    EXPECT_LT(largest_error, tolerance) << "g " << g;
    char figure[32];
    std::snprintf(figure, sizeof figure, "%.3e", largest_error);
    ::testing::Test::RecordProperty(g == 0.0 ? "momentum_error_Ns_no_gravity" : "momentum_error_Ns", figure);
  }
}

// CouplingScheme::IMPULSES (the paper's, both sides corrected within the step) exchanges momentum exactly
// too where the fail-safe moves a particle with its triangle: what that gives the particle is owed to the
// triangle's nodes at the cloth's next step (Coupler::owed_impulses). A cloth 50 times heavier than the
// default (10 kg/m^2: nodes of 2 g against particles of 0.125 g) keeps the paper's scheme stable; a step
// of 4 ms and one CCD round before the fail-safe make it act.
TEST(JetOnCloth, ImpulsesConserveLinearMomentumThroughTheFailSafe) {
  SceneConfig config = reduced_jet_on_cloth(0.004, true);
  config.coupling.scheme = CouplingScheme::IMPULSES;
  config.coupling.max_ccd_iterations = 1;
  config.cloth->pinned = "none";
  config.cloth->area_density = 10.0;
  config.cloth->substeps = 4;
  config.fluid.pressure_solver = PressureSolverKind::WCSPH;
  config.kill_regions.clear();
  config.effects = {"coupling"};
  config.gravity = Vec3::Zero();
  config.time.duration = 0.12;  // the jet reaches the cloth at 0.05 s
  Simulation sim(config, bullet::cloth_engine_factory());
  const double particle_mass = sim.fluid().particle_mass();
  Vec3 expected = total_momentum(sim);
  double largest_error = 0.0;
  while (!sim.finished()) {
    const auto before = sim.created();
    ASSERT_TRUE(sim.step().ok());
    expected += static_cast<double>(sim.created() - before) * particle_mass * Vec3(0, -3.0, 0);
    largest_error = std::max(largest_error, (total_momentum(sim) - expected).norm());
  }
  EXPECT_GT(sim.coupling_stats().failsafe_activations, 0u) << "the test must exercise the fail-safe";
  // As CarriedWaterConservesLinearMomentum without gravity: 1e-12 of the jet's momentum (0.75 N s). One
  // fail-safe placement not paid for is about 1e-4 N s.
  const double steps = config.time.duration / config.time.dt;
  EXPECT_LT(largest_error, bullet_tolerance(1e-12 * 0.75, steps * 0.75));
  char figure[32];
  std::snprintf(figure, sizeof figure, "%.3e", largest_error);
  ::testing::Test::RecordProperty("momentum_error_Ns", figure);
  ::testing::Test::RecordProperty("failsafe_activations",
                                  static_cast<int>(sim.coupling_stats().failsafe_activations));
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
  ::testing::Test::RecordProperty("impulse_per_step_over_m_g_dt",
                                  std::to_string(-per_step / (mass * 9.81 * dt)));
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
  ::testing::Test::RecordProperty("median_distance_over_thickness", std::to_string(median / 0.001));
  EXPECT_GE(median, 0.5 * 0.001);
  EXPECT_LE(median, 1.5 * 0.001);
}

// Stress (issue 4): a layer of water laid on the cloth so that its particles sit above the cloth's
// vertices and edges (the lattice of 5 mm spacing meets the 15 mm node grid on every third particle, and
// every particle on a grid line is above an edge, to rounding), one thickness up, or within the thickness:
// the closest points are the degenerate barycentric cases. It must settle without a leak, non-finite value or
// a fast particle.
TEST(JetOnCloth, WaterRestingOnVerticesAndEdgesStaysPut) {
  for (double height : {0.001, 0.0005}) {
    SceneConfig c = puddle(false);
    EmitterSettings layer;
    layer.kind = EmitterSettings::Kind::BOX;
    // Points at min + 5 mm (i + 1/2): x, z = -75 mm + 5 mm i, on the nodes' -150 mm + 15 mm n every third.
    layer.box.min = Vec3(-0.0775, height - 0.0025, -0.0775);
    layer.box.max = Vec3(0.0775, height + 0.0025, 0.0775);
    c.emitters.push_back(layer);
    c.cloth->damping = 0.0;
    c.cloth->substeps = 4;
    c.time.duration = 0.3;
    c.effects = {"viscosity", "coupling", "leak_audit"};
    Simulation sim(c, bullet::cloth_engine_factory());
    ASSERT_EQ(sim.particles().size(), 31u * 31u);
    // Twice the speed of a free fall over the cloth's half width (0.15 m), which bounds its sag.
    const double speed_limit = 2.0 * std::sqrt(2.0 * 9.81 * 0.15);
    Fastest fastest;
    while (!sim.finished()) {
      ASSERT_TRUE(sim.step().ok()) << "t " << sim.time();
      fastest.update(sim);
    }
    EXPECT_EQ(sim.leak_stats().leaks, 0u) << "height " << height;
    EXPECT_EQ(sim.particles().size(), 31u * 31u);
    EXPECT_LT(fastest.particle, speed_limit) << "height " << height;
    EXPECT_LT(fastest.node, speed_limit) << "height " << height;
    ::testing::Test::RecordProperty("fastest_particle_mps_h" + std::to_string(height),
                                    std::to_string(fastest.particle));
    ::testing::Test::RecordProperty("fastest_node_mps_h" + std::to_string(height),
                                    std::to_string(fastest.node));
  }
}

/// A 0.2 m square cloth folded on itself along x = 0.1 m: two 11 x 11 layers `gap` apart (top at y = 0,
/// written first, so that "corners" pins its corners), joined by one row of quads at the fold. Written as an
/// OBJ file at `path`.
void write_folded_cloth(const std::string& path, double gap) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr) << path;
  const int n = 11;
  const double size = 0.2;
  for (int layer = 0; layer < 2; ++layer) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i)
        std::fprintf(f, "v %.17g %.17g %.17g\n", -0.1 + size * i / (n - 1), -gap * layer,
                     -0.1 + size * j / (n - 1));
    }
  }
  const auto node = [&](int layer, int i, int j) { return 1 + layer * n * n + j * n + i; };
  for (int layer = 0; layer < 2; ++layer) {
    for (int j = 0; j + 1 < n; ++j) {
      for (int i = 0; i + 1 < n; ++i) {
        std::fprintf(f, "f %d %d %d\n", node(layer, i, j), node(layer, i + 1, j), node(layer, i + 1, j + 1));
        std::fprintf(f, "f %d %d %d\n", node(layer, i, j), node(layer, i + 1, j + 1), node(layer, i, j + 1));
      }
    }
  }
  for (int j = 0; j + 1 < n; ++j) {  // the fold: the two layers' x = 0.1 edges
    std::fprintf(f, "f %d %d %d\n", node(0, n - 1, j), node(1, n - 1, j), node(1, n - 1, j + 1));
    std::fprintf(f, "f %d %d %d\n", node(0, n - 1, j), node(1, n - 1, j + 1), node(0, n - 1, j + 1));
  }
  std::fclose(f);
}

// Stress (issue 4): a cloth folded on itself, its layers 3 cloth thicknesses apart, with a layer of water
// between them. The top layer hangs from its corners; the bottom layer, held only by the fold, swings down
// under the water. No particle may cross either layer.
TEST(JetOnCloth, WaterBetweenTheLayersOfAFoldedClothStaysBetweenThem) {
  const double thickness = 0.001;
  const drench::test::TempDir dir;  // its own folder: the double and single Bullet builds run side by side
  const std::string path = (dir.path() / "folded_cloth.obj").string();
  write_folded_cloth(path, 3.0 * thickness);
  SceneConfig c;
  c.fluid.particle_spacing = 0.005;
  EmitterSettings water;  // one layer of particles half way between the layers
  water.kind = EmitterSettings::Kind::BOX;
  water.box.min = Vec3(-0.095, -1.5 * thickness - 0.0025, -0.095);
  water.box.max = Vec3(0.085, -1.5 * thickness + 0.0025, 0.095);
  c.emitters.push_back(water);
  KillRegionSettings kill;
  kill.point = Vec3(0, -0.5, 0);
  c.kill_regions.push_back(kill);
  ClothSettings cloth;
  cloth.mesh = path;
  cloth.substeps = 4;
  c.cloth = cloth;
  c.coupling.cloth_thickness = thickness;
  c.time.dt = 0.001;
  c.time.duration = 0.3;
  c.effects = {"viscosity", "coupling", "leak_audit"};
  Simulation sim(c, bullet::cloth_engine_factory());
  const std::size_t count = sim.particles().size();
  ASSERT_EQ(count, 36u * 38u);
  // Issue 4's bound with H the scene's height, cloth to kill plane (0.5 m), as for the jets. A first bound
  // over the bottom layer's swing alone (0.2 m: 3.96 m/s) did not hold for the cloth itself: its free edge
  // whips, and the folded cloth without water reached 3.59 m/s (with the water 4.92).
  const double speed_limit = 2.0 * std::sqrt(2.0 * 9.81 * 0.5);
  Fastest fastest;
  while (!sim.finished()) {
    ASSERT_TRUE(sim.step().ok()) << "t " << sim.time();
    fastest.update(sim);
  }
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  EXPECT_EQ(sim.particles().size() + static_cast<std::size_t>(sim.removed()), count);
  EXPECT_LT(fastest.particle, speed_limit);
  EXPECT_LT(fastest.node, speed_limit);
  ::testing::Test::RecordProperty("fastest_particle_mps", std::to_string(fastest.particle));
  ::testing::Test::RecordProperty("fastest_node_mps", std::to_string(fastest.node));
  ::testing::Test::RecordProperty("removed", static_cast<int>(sim.removed()));
  ::testing::Test::RecordProperty("ccd_impacts", static_cast<int>(sim.coupling_stats().ccd_impacts));
  std::remove(path.c_str());
}

// Stress (issue 4): a 0.1 m cloth of 11 x 11 nodes (node mass 1.7e-5 kg, each particle weighs 60 of them)
// pinned at one corner swings down through a pool of water (1 cm spacing) in an open box. No leak, nothing
// non-finite, nothing faster than twice the free-fall speed over the scene's height (0.25 m). It is why only
// the water in contact is carried: carrying all water near the cloth, a node moving through water carries it
// at its own speed, not the water's, and is thrown past the bound (coupling/carried_water.hpp).
TEST(JetOnCloth, ClothSwingingThroughAPool) {
  SceneConfig c;
  c.fluid.particle_spacing = 0.01;
  BoundarySettings box;
  box.kind = BoundarySettings::Kind::BOX;
  box.min = Vec3(-0.1, -0.2, -0.1);
  box.max = Vec3(0.1, 0.05, 0.1);
  box.open_top = true;
  c.boundaries.push_back(box);
  EmitterSettings pool;
  pool.kind = EmitterSettings::Kind::BOX;
  pool.box.min = Vec3(-0.1, -0.2, -0.1);
  pool.box.max = Vec3(0.1, -0.08, 0.1);
  c.emitters.push_back(pool);
  ClothSettings cloth;
  cloth.size_x = cloth.size_z = 0.1;
  cloth.nodes_x = cloth.nodes_z = 11;
  cloth.pinned = "corner";
  cloth.substeps = 4;
  c.cloth = cloth;
  c.time.dt = 0.001;
  c.time.duration = 0.5;
  c.effects = {"viscosity", "coupling", "leak_audit"};
  Simulation sim(c, bullet::cloth_engine_factory());
  const std::size_t particles = sim.particles().size();
  const double speed_limit = 2.0 * std::sqrt(2.0 * 9.81 * 0.25);
  Fastest fastest;
  double lowest_node = 0.0;
  while (!sim.finished()) {
    ASSERT_TRUE(sim.step().ok()) << "t " << sim.time();
    fastest.update(sim);
    for (const Vec3& x : sim.cloth()->mesh().positions_t1)
      lowest_node = std::min(lowest_node, x.y());
  }
  EXPECT_LT(lowest_node, -0.08) << "the cloth reached into the pool";
  EXPECT_EQ(sim.leak_stats().leaks, 0u);
  EXPECT_EQ(sim.particles().size(), particles);
  EXPECT_LT(fastest.particle, speed_limit);
  EXPECT_LT(fastest.node, speed_limit);
  ::testing::Test::RecordProperty("fastest_particle_mps", std::to_string(fastest.particle));
  ::testing::Test::RecordProperty("fastest_node_mps", std::to_string(fastest.node));
  ::testing::Test::RecordProperty("lowest_node_m", std::to_string(lowest_node));
}

// Two runs of the coupled jet with the same thread count are bit-identical (the carried water, the deferred
// impulses and the coupler reduce in a fixed order).
TEST(JetOnCloth, TwoRunsAreBitIdentical) {
  SceneConfig config = reduced_jet_on_cloth(0.001, true);
  config.cloth->substeps = 4;
  config.time.duration = 0.1;  // contact from 0.04 s
  Simulation a(config, bullet::cloth_engine_factory());
  Simulation b(config, bullet::cloth_engine_factory());
  while (!a.finished()) {
    ASSERT_TRUE(a.step().ok());
    ASSERT_TRUE(b.step().ok());
  }
  ASSERT_GT(a.coupling_stats().obstacle_stops + a.coupling_stats().ccd_impacts, 0u);
  ASSERT_EQ(a.particles().size(), b.particles().size());
  for (std::size_t i = 0; i < a.particles().size(); ++i) {
    ASSERT_EQ(a.particles().positions[i], b.particles().positions[i]) << "particle " << i;
    ASSERT_EQ(a.particles().velocities[i], b.particles().velocities[i]) << "particle " << i;
  }
  const Vec3Array va = a.cloth()->velocities(), vb = b.cloth()->velocities();
  for (std::size_t i = 0; i < va.size(); ++i) {
    ASSERT_EQ(a.cloth()->mesh().positions_t1[i], b.cloth()->mesh().positions_t1[i]) << "node " << i;
    ASSERT_EQ(va[i], vb[i]) << "node " << i;
    ASSERT_EQ(a.pending_cloth_impulses()[i], b.pending_cloth_impulses()[i]) << "node " << i;
  }
}

}  // namespace
}  // namespace drench
