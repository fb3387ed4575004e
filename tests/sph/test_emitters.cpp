#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include <drench/scene/simulation.hpp>
#include <drench/sph/emitters.hpp>

namespace drench {
namespace {

TEST(BoxEmitter, FillsTheBoxWithALatticeWhoseVolumesTileIt) {
  BoxEmitterSettings box;
  box.min = Vec3(-0.1, 0.0, 0.2);
  box.max = Vec3(0.85, 0.95, 1.15);
  ParticleSet particles;
  std::uint32_t next_id = 5;
  EXPECT_EQ(emit_box(box, 0.05, 0.125, particles, next_id), 19u * 19u * 19u);
  EXPECT_EQ(next_id, 5u + 19u * 19u * 19u);
  for (const Vec3& x : particles.positions) {
    EXPECT_TRUE((x.array() > box.min.array()).all() && (x.array() < box.max.array()).all());
  }
  EXPECT_NEAR(particles.positions.front().x(), -0.075, 1e-12);
}

/// Fig. 3's nozzle (radius 2 cm, 3 m/s, spacing 5 mm, no budget to speak of) at `center` along `direction`,
/// and the particles it released.
struct Jet {
  static constexpr Scalar kSpacing = 0.005;  // m
  NozzleEmitterSettings settings;
  NozzleEmitter nozzle;
  ParticleSet particles;
  std::uint32_t next_id = 0;

  Jet(const Vec3& center, const Vec3& direction)
      : settings(fig3(center, direction)), nozzle(settings, kSpacing) {}

  static NozzleEmitterSettings fig3(const Vec3& center, const Vec3& direction) {
    NozzleEmitterSettings s;
    s.center = center;
    s.direction = direction;
    s.radius = 0.02;
    s.speed = 3.0;
    s.max_particles = 1000000;
    return s;
  }

  /// Steps `first_step` to `first_step + steps` of `dt` (unit: s): the nozzle emits, then every particle
  /// moves `flow` times its velocity for dt, as the fluid step would move it (1: free flight at the jet's
  /// speed; 0: a blocked outlet). Returns the particles each step released.
  std::vector<std::size_t> run(Scalar dt, int first_step, int steps, Scalar flow) {
    std::vector<std::size_t> released;
    for (int step = first_step; step < first_step + steps; ++step) {
      released.push_back(nozzle.emit(step * dt, dt, 1e-3, particles, next_id));
      for (std::size_t i = 0; i < particles.size(); ++i)
        particles.positions[i] += dt * flow * particles.velocities[i];
    }
    return released;
  }
};

TEST(NozzleEmitter, ReleasesDiscsOneSpacingApartAtTheJetSpeed) {
  Jet jet(Vec3(0.1, 0.3, -0.2), Vec3(0, -1, 0));
  const NozzleEmitterSettings& settings = jet.settings;
  const Scalar spacing = Jet::kSpacing;
  // dt is not a multiple of the layer period (spacing / speed = 1/600 s): layers must still end one spacing
  // apart once each step's motion (here free flight, as the fluid step would do) is applied. 11 steps of 1
  // ms, 6.6 layer periods: no release falls on a step boundary.
  jet.run(0.001, 0, 11, 1.0);
  const ParticleSet& particles = jet.particles;
  const NozzleEmitter& nozzle = jet.nozzle;
  std::set<long long> depths_nm;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    EXPECT_TRUE(particles.velocities[i].isApprox(Vec3(0, -3, 0)));
    const Vec3 offset = particles.positions[i] - settings.center;
    EXPECT_LE(std::hypot(offset.x(), offset.z()), settings.radius + 1e-12);
    depths_nm.insert(std::llround(-offset.y() * 1e9));
  }
  const std::vector<long long> depth(depths_nm.begin(), depths_nm.end());
  ASSERT_EQ(depth.size(), 7u);  // releases at 0, 1/600, ..., 6/600 s
  EXPECT_EQ(particles.size(), 7 * nozzle.disc_size());
  for (std::size_t k = 1; k < depth.size(); ++k)
    EXPECT_NEAR((depth[k] - depth[k - 1]) * 1e-9, spacing, 2e-9);
  // The last layer left at 6/600 s and has flown until 0.011 s.
  EXPECT_NEAR(depth.front() * 1e-9, (0.011 - 0.01) * settings.speed, 2e-9);
}

// A disc carries the jet's mass flux rho pi r^2 v to half a particle, with no two particles closer than a
// spacing (which would start the jet compressed) and none outside the nozzle by more than a tenth of a
// spacing (the count comes from the area, not from the lattice points inside the circle: at r = 0.0537 m the
// last one sits 0.03 mm out; each particle stands for s^2 of area around its centre anyway).
TEST(NozzleEmitter, DiscsCarryTheJetsMassFluxWithoutCompression) {
  const Scalar spacing = 0.005;
  for (Scalar radius : {0.001, 0.0075, 0.02, 0.0537}) {
    NozzleEmitterSettings settings;
    settings.center = Vec3(0.1, 0.3, -0.2);
    settings.direction = Vec3(1, -2, 0.5).normalized();
    settings.radius = radius;
    settings.max_particles = 1000000;
    NozzleEmitter nozzle(settings, spacing);
    ParticleSet particles;
    std::uint32_t next_id = 0;
    nozzle.emit(0.0, 1e-6, 1e-3, particles, next_id);  // the first disc only
    ASSERT_EQ(particles.size(), nozzle.disc_size());
    const double per_layer = M_PI * radius * radius / (spacing * spacing);
    EXPECT_LE(std::abs(static_cast<double>(particles.size()) - std::max(per_layer, 1.0)), 0.5)
        << "radius " << radius;
    for (std::size_t i = 0; i < particles.size(); ++i) {
      const Vec3 offset = particles.positions[i] - settings.center;
      EXPECT_NEAR(offset.dot(settings.direction), 0.0, 1e-9) << "radius " << radius;
      EXPECT_LE(offset.norm(), radius + 0.1 * spacing) << "radius " << radius;
      for (std::size_t j = i + 1; j < particles.size(); ++j)
        EXPECT_GE((particles.positions[i] - particles.positions[j]).norm(), spacing) << "radius " << radius;
    }
  }
}

/// The axial coordinates (unit: m, downstream positive) of each disc's rearmost particle, in id order.
std::vector<Scalar> disc_rears(const NozzleEmitter& nozzle, const NozzleEmitterSettings& settings,
                               const ParticleSet& particles) {
  std::vector<Scalar> rears;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const std::size_t disc = particles.ids[i] / nozzle.disc_size();
    if (rears.size() <= disc) rears.resize(disc + 1, std::numeric_limits<Scalar>::infinity());
    rears[disc] = std::min(rears[disc], (particles.positions[i] - settings.center).dot(settings.direction));
  }
  return rears;
}

// Pressure slows a jet's last disc. The next disc, due on schedule, must still sit a spacing behind that
// disc's rearmost particle, not where free flight would have put it: closer, stiff WCSPH threw particles at
// 65 m/s (the Fig. 3 jet at dt 4 ms, three discs a step). Here the fluid moves at 2/3 of the nozzle's speed.
TEST(NozzleEmitter, ADiscIsNeverCloserThanASpacingToTheSlowedDiscBeforeIt) {
  Jet jet(Vec3::Zero(), Vec3(1, -2, 0.5).normalized());
  jet.run(0.004, 0, 10, 2.0 / 3.0);  // 2.4 layer periods a step
  const NozzleEmitter& nozzle = jet.nozzle;
  const NozzleEmitterSettings& settings = jet.settings;
  const ParticleSet& particles = jet.particles;
  const Scalar spacing = Jet::kSpacing;
  const std::vector<Scalar> rears = disc_rears(nozzle, settings, particles);
  ASSERT_GE(rears.size(), 16u);  // a slowed jet still leaves the nozzle: at least 2/3 of 24 discs
  for (std::size_t k = 1; k < rears.size(); ++k)
    EXPECT_GE(rears[k - 1] - rears[k], spacing - 1e-12) << "disc " << k;
  // Discs of one step are a spacing apart exactly, as the schedule has them.
  EXPECT_NEAR(rears[1] - rears[2], spacing, 1e-12);
}

// A blocked outlet (the fluid in front of it does not move) stops the nozzle once the fluid it released in a
// step and one spacing more stand above the outlet; it stacks nothing further upstream, and when the way is
// clear it releases discs at its usual rate, not the backlog at once.
TEST(NozzleEmitter, ABlockedNozzleWaitsAndThenResumesAtItsRate) {
  Jet jet(Vec3::Zero(), Vec3(0, -1, 0));
  const NozzleEmitter& nozzle = jet.nozzle;
  const NozzleEmitterSettings& settings = jet.settings;
  const ParticleSet& particles = jet.particles;
  const Scalar spacing = Jet::kSpacing;
  const Scalar dt = 0.004;
  jet.run(dt, 0, 20, 0.0);  // blocked: nothing moves
  const std::size_t blocked = particles.size();
  EXPECT_LE(blocked, 4 * nozzle.disc_size());  // at most dt v / s + 1 = 3.4 discs, then nothing
  for (std::size_t i = 0; i < particles.size(); ++i)
    EXPECT_GE((particles.positions[i] - settings.center).dot(settings.direction),
              -(dt * 3.0 + spacing) - 1e-12);
  // Clear: the fluid moves at the nozzle's speed, and no step releases more than ceil(2.4) discs.
  for (std::size_t released : jet.run(dt, 20, 10, 1.0))
    EXPECT_LE(released, 3 * nozzle.disc_size());
  // The first of those steps still finds the column in place; the nine after it release 2.4 discs each.
  EXPECT_GE(particles.size() - blocked, 21 * nozzle.disc_size());
  const std::vector<Scalar> rears = disc_rears(nozzle, settings, particles);
  for (std::size_t k = 1; k < rears.size(); ++k)
    EXPECT_GE(rears[k - 1] - rears[k], spacing - 1e-12) << "disc " << k;
}

// The Fig. 3 jet under WCSPH at dt 4 ms, with nothing in its way: free fall, so no particle may be faster
// than the nozzle's 3 m/s plus what gravity adds in the 0.04 s (0.39 m/s), give or take 10% for the small
// pressures inside a free jet. With discs placed on schedule, one disc sat 4.2 mm behind the slowed disc
// before it and a particle left at 65 m/s within 0.024 s.
TEST(NozzleEmitter, AWcsphJetWithSeveralDiscsAStepStaysInFreeFall) {
  SceneConfig config;
  config.fluid.particle_spacing = 0.005;
  config.fluid.pressure_solver = PressureSolverKind::WCSPH;
  config.fluid.wcsph.speed_of_sound = 54.26;  // what the Fig. 3 scene's fall to its cloth gives
  config.effects = {"viscosity"};             // XSPH, 0.01, as in demos/scenes/jet_on_cloth.json
  EmitterSettings e;
  e.kind = EmitterSettings::Kind::NOZZLE;
  e.nozzle.center = Vec3(0, 0.3, 0);
  e.nozzle.direction = Vec3(0, -1, 0);
  e.nozzle.radius = 0.02;
  e.nozzle.speed = 3.0;
  config.emitters.push_back(e);
  config.time.dt = 0.004;
  config.time.duration = 0.04;
  Simulation sim(config);
  while (!sim.finished())
    ASSERT_TRUE(sim.step().ok());
  EXPECT_GT(sim.created(), 20 * 50);
  EXPECT_LE(sim.max_particle_speed(), 1.1 * (3.0 + 9.81 * 0.04));
}

TEST(NozzleEmitter, StopsExactlyAtItsParticleBudget) {
  NozzleEmitterSettings settings;
  settings.radius = 0.02;
  settings.speed = 2.0;
  settings.max_particles = 100;
  NozzleEmitter nozzle(settings, 0.005);
  ASSERT_GT(nozzle.disc_size(), 40u);
  ParticleSet particles;
  std::uint32_t next_id = 0;
  for (int step = 0; step < 50; ++step)
    nozzle.emit(step * 0.001, 0.001, 1e-3, particles, next_id);
  EXPECT_EQ(particles.size(), 100u);
  EXPECT_EQ(nozzle.emitted(), 100);
}

TEST(NozzleEmitter, EmitsNothingBeforeItsStartTime) {
  NozzleEmitterSettings settings;
  settings.start_time = 0.5;
  NozzleEmitter nozzle(settings, 0.01);
  ParticleSet particles;
  std::uint32_t next_id = 0;
  EXPECT_EQ(nozzle.emit(0.0, 0.4, 1e-3, particles, next_id), 0u);
  EXPECT_GT(nozzle.emit(0.4, 0.2, 1e-3, particles, next_id), 0u);
}

TEST(KillRegion, RemovesAndCountsEveryParticleThatCrossesThePlane) {
  SceneConfig config;
  config.gravity = Vec3::Zero();
  config.fluid.particle_spacing = 0.02;
  EmitterSettings e;
  e.kind = EmitterSettings::Kind::BOX;
  e.box.min = Vec3(0, 0, 0);
  e.box.max = Vec3(0.1, 0.1, 0.1);
  e.box.velocity = Vec3(0, -2, 0);
  config.emitters.push_back(e);
  KillRegionSettings kill;
  kill.point = Vec3(0, -0.05, 0);
  kill.normal = Vec3(0, 1, 0);
  config.kill_regions.push_back(kill);
  config.time.dt = 0.01;
  config.time.duration = 0.2;
  Simulation sim(config);
  EXPECT_EQ(sim.created(), 125);
  std::int64_t previous_removed = 0;
  while (!sim.finished()) {
    ASSERT_TRUE(sim.step().ok());
    for (const Vec3& x : sim.particles().positions)
      ASSERT_GE(x.y(), -0.05);
    EXPECT_EQ(static_cast<std::int64_t>(sim.particles().size()) + sim.removed(), sim.created());
    EXPECT_GE(sim.removed(), previous_removed);
    previous_removed = sim.removed();
  }
  EXPECT_EQ(sim.removed(), 125);
}

}  // namespace
}  // namespace drench
