// A dynamic body and the water it would sweep in a step meet before either moves
// (coupling/swept_water.hpp): one inelastic collision of the two masses, momentum kept.

#include <gtest/gtest.h>

#include <vector>

#include <drench/coupling/swept_water.hpp>

namespace drench {
namespace {

/// A cube of side `side` (unit: m) centred at `centre`, moving at `velocity` (unit: m/s), of `mass` (kg): 8
/// nodes, 12 faces turned outward.
RigidSurface moving_cube(const Vec3& centre, double side, const Vec3& velocity, double mass) {
  RigidSurface s;
  s.key = 1;
  s.motion = RigidMotion::DYNAMIC;
  for (int i = 0; i < 8; ++i)
    s.positions_t0.push_back(centre + side * (Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1) - Vec3::Constant(0.5)));
  const Index faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
  const Vec3Array& x = s.positions_t0;
  for (const auto& f : faces) {
    for (const Triangle t : {Triangle{f[0], f[1], f[2]}, Triangle{f[0], f[2], f[3]}}) {
      const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
      s.triangles.push_back(n.dot(x[t[0]] - centre) > 0.0 ? t : Triangle{t[0], t[2], t[1]});
    }
  }
  s.positions_t1 = s.positions_t0;
  s.velocities_t0.assign(8, velocity);
  s.inverse_mass = 1.0 / mass;
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
    const std::vector<RigidSurface> cube = {moving_cube(Vec3(0.0, 0.0201, 0.0), 0.04, velocity, mass)};
    Vec3Array v(x.size(), Vec3::Zero());
    Vec3Array nodes(8, Vec3::Zero());
    const std::size_t swept = meet_swept_water(cube, {0}, dt, 1000.0, x, masses, v, nodes);
    if (mass > 0.3) {
      EXPECT_EQ(swept, 0u);
      EXPECT_EQ(v, Vec3Array(x.size(), Vec3::Zero()));
      continue;
    }
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
    for (const Vec3& j : nodes)
      body += j;
    // The body's impulse brings it to the common velocity; the water's is the opposite.
    EXPECT_NEAR((velocity + body / mass - common).norm(), 0.0, 1e-12);
    EXPECT_NEAR((water + body).norm(), 0.0, 1e-15);
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
    Vec3Array v(1, Vec3::Zero()), nodes(8, Vec3::Zero());
    EXPECT_EQ(meet_swept_water({cube}, {0}, 1.0 / 60.0, 1000.0, x, masses, v, nodes), 0u);
    EXPECT_EQ(v[0], Vec3::Zero());
  }
}

}  // namespace
}  // namespace drench
