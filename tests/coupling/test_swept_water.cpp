// A dynamic body and the water it would sweep in a step meet before either moves
// (coupling/swept_water.hpp): one inelastic collision of the two masses, momentum kept.

#include <gtest/gtest.h>

#include <vector>

#include <drench/coupling/swept_water.hpp>

#include "coupling_fixtures.hpp"

namespace drench {
namespace {

/// A cube of side `side` (unit: m) centred at `centre`, moving at `velocity` (unit: m/s), of `mass` (kg).
RigidSurface moving_cube(const Vec3& centre, double side, const Vec3& velocity, double mass) {
  RigidSurface s = test::cube_surface(1, RigidMotion::DYNAMIC, centre - Vec3::Constant(0.5 * side), side);
  s.velocities_t0.assign(8, velocity);
  s.inverse_mass = 1.0 / mass;
  s.centre = centre;
  s.velocity = velocity;
  return s;
}

TEST(SweptWater, ABodyAndTheWaterAheadOfItEndAtTheirCommonVelocity) {
  // A 4 cm cube falling at 1.2 m/s over a layer of 1 cm particles of 1 g at rest: in 1/60 s it sweeps 2 cm,
  // the two layers under it (4 x 4 particles each), and those beside it, or more than 2 cm below, stay.
  const double dt = 1.0 / 60.0, m = 0.001;
  Vec3Array x;
  for (int layer = 0; layer < 4; ++layer)
    for (int i = -3; i <= 3; ++i)
      for (int k = -3; k <= 3; ++k)
        x.emplace_back(0.005 + 0.01 * i, -0.005 - 0.01 * layer, 0.005 + 0.01 * k);
  const ScalarArray masses(x.size(), m);
  // 6.4 g (a 4 cm cube of 100 kg/m^3), 0.2 kg (3,125 kg/m^3, six times the water it sweeps), and 0.4 kg,
  // ten times more than its faces can sweep (1000 kg/m^3 x 16 cm^2 x 2 cm = 32 g), which is left to the
  // coupler: it would lose to the water 1.2 m/s x 32 / 400 and not 32 / 432, to within a tenth the same.
  for (const double mass : {0.0064, 0.2, 0.4}) {
    SCOPED_TRACE(mass);
    const Vec3 velocity(0, -1.2, 0);
    const Vec3 centre(0.0, 0.0201, 0.0);
    std::vector<RigidSurface> cube = {moving_cube(centre, 0.04, velocity, mass)};
    Vec3Array v(x.size(), Vec3::Zero());
    Vec3Array nodes;
    const std::size_t swept = meet_swept_water(cube, {0}, 8, dt, 1000.0, x, masses, v, nodes);
    if (mass > 0.3) {
      EXPECT_EQ(swept, 0u);
      EXPECT_EQ(v, Vec3Array(x.size(), Vec3::Zero()));
      EXPECT_TRUE(nodes.empty());
      continue;
    }
    ASSERT_EQ(nodes.size(), 8u);
    ASSERT_EQ(swept, 32u) << "two layers of 4 x 4 under the cube's face";
    const Vec3 common = mass * velocity / (mass + swept * m);
    Vec3 water = Vec3::Zero(), body = Vec3::Zero();
    std::size_t moved = 0;
    for (std::size_t p = 0; p < x.size(); ++p) {
      water += m * v[p];
      if (v[p] != Vec3::Zero()) {
        ++moved;
        EXPECT_NEAR((v[p] - common).norm(), 0.0, 1e-12) << "particle " << p;
        // Under the cube, within its sweep.
        EXPECT_LT(std::abs(x[p].x()), 0.02);
        EXPECT_LT(std::abs(x[p].z()), 0.02);
        EXPECT_GT(x[p].y(), -0.0201);
      }
    }
    EXPECT_EQ(moved, swept);
    Vec3 torque = Vec3::Zero();
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      body += nodes[k];
      torque += (cube[0].positions_t0[k] - centre).cross(nodes[k]);
    }
    // The body's impulse brings it to the common velocity, at its centre; the water's is the opposite. The
    // body's velocities for the rest of the step are the common one.
    EXPECT_NEAR((velocity + body / mass - common).norm(), 0.0, 1e-12);
    EXPECT_NEAR((water + body).norm(), 0.0, 1e-15);
    EXPECT_NEAR(torque.norm(), 0.0, 1e-15);
    EXPECT_NEAR((cube[0].velocity - common).norm(), 0.0, 1e-15);
    for (const Vec3& u : cube[0].velocities_t0)
      EXPECT_NEAR((u - common).norm(), 0.0, 1e-15);
    // The 6.4 g cube nearly stops: 32 g of water is five times it.
    if (mass < 0.01) {
      EXPECT_NEAR(common.y(), -0.2, 1e-9);
    }
  }
}

TEST(SweptWater, StaticKinematicAndMasslessBodiesSweepNothing) {
  Vec3Array x = {Vec3(0.005, -0.005, 0.005)};
  const ScalarArray masses = {0.001};
  for (const RigidMotion motion : {RigidMotion::STATIC, RigidMotion::KINEMATIC, RigidMotion::DYNAMIC}) {
    RigidSurface cube = moving_cube(Vec3(0.0, 0.0201, 0.0), 0.04, Vec3(0, -1.2, 0), 1.0);
    cube.motion = motion;
    if (motion == RigidMotion::DYNAMIC) cube.inverse_mass = 0.0;  // a source that gave no mass
    Vec3Array v(1, Vec3::Zero()), nodes;
    std::vector<RigidSurface> surfaces = {cube};
    EXPECT_EQ(meet_swept_water(surfaces, {0}, 8, 1.0 / 60.0, 1000.0, x, masses, v, nodes), 0u);
    EXPECT_EQ(v[0], Vec3::Zero());
  }
}

// Only the water in the body's way counts, and the collision only loses energy: a rod of 4 g moving along
// its length at 1 m/s has 8 g of water at rest ahead of one half of its end face (a lever off its centre)
// and 8 g running ahead of the other half at 3 m/s, which it never reaches. Taken as standing still, the
// running water was met and slowed; handed on at the faces that met the water, the impulses made the rod
// spin with more energy than the collision freed.
TEST(SweptWater, OnlyTheWaterInTheWayIsMetAndNoEnergyIsMade) {
  const double dt = 0.01, m = 0.001, mass = 0.004;
  RigidSurface rod = test::cube_surface(1, RigidMotion::DYNAMIC, Vec3::Zero(), 1.0);
  const Vec3 size(0.04, 0.2, 0.04);  // along y
  for (Vec3& x : rod.positions_t0)
    x = x.cwiseProduct(size);
  rod.positions_t1 = rod.positions_t0;
  const Vec3 velocity(0, 1.0, 0);
  rod.velocities_t0.assign(8, velocity);
  rod.inverse_mass = 1.0 / mass;
  rod.centre = 0.5 * size;
  rod.velocity = velocity;
  Vec3Array x, v;
  for (int running = 0; running < 2; ++running)
    for (int i = 0; i < 2; ++i)
      for (int k = 0; k < 2; ++k)
        for (int layer = 0; layer < 2; ++layer) {
          // Within the 1 cm the rod's end moves in the step, over the half x < 2 cm (at rest) or x > 2 cm.
          x.emplace_back(0.005 + 0.01 * i + 0.02 * running, 0.2 + 0.003 + 0.004 * layer, 0.01 + 0.02 * k);
          v.push_back(running ? Vec3(0, 3.0, 0) : Vec3::Zero());
        }
  const ScalarArray masses(x.size(), m);
  std::vector<RigidSurface> surfaces = {rod};
  Vec3Array nodes;
  const double energy_before = 0.5 * mass * velocity.squaredNorm() + 0.5 * 8 * m * 9.0;
  ASSERT_EQ(meet_swept_water(surfaces, {0}, 8, dt, 1000.0, x, masses, v, nodes), 8u);
  Vec3 body = Vec3::Zero(), torque = Vec3::Zero();
  for (std::size_t k = 0; k < 8; ++k) {
    body += nodes[k];
    torque += (rod.positions_t0[k] - rod.centre).cross(nodes[k]);
  }
  const Vec3 common = mass * velocity / (mass + 8 * m);
  for (int p = 0; p < 8; ++p)
    EXPECT_NEAR((v[p] - common).norm(), 0.0, 1e-12) << "particle " << p;
  for (int p = 8; p < 16; ++p)
    EXPECT_EQ(v[p], Vec3(0, 3.0, 0)) << "particle " << p << " runs ahead";
  EXPECT_NEAR(torque.norm(), 0.0, 1e-15) << "no spin";
  double energy_after = 0.5 * mass * (velocity + body / mass).squaredNorm();
  for (std::size_t p = 0; p < x.size(); ++p)
    energy_after += 0.5 * m * v[p].squaredNorm();
  EXPECT_LT(energy_after, energy_before);
}

}  // namespace
}  // namespace drench
