// CarriedWater (CouplingScheme::CARRIED_WATER): which particles a cloth carries through its step, as how
// much mass on which node, and the exact momentum hand-back afterwards.

#include <gtest/gtest.h>

#include "common/triangle_geometry.hpp"
#include "coupling/carried_water.hpp"
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

constexpr double kThickness = 0.001;        // m
constexpr double kSpacing = 0.005;          // m
constexpr double kParticleMass = 1.25e-4;   // kg
constexpr double kNodeInverseMass = 1.0e4;  // 1/kg
constexpr double kDt = 0.001;               // s

/// A 3 x 3 grid, 0.2 m wide, in the plane y = 0, node 0 (at x = z = 0) pinned, and four particles: two within
/// thickness + half a spacing of the cloth, one above that, one whose closest cloth point is the pinned node.
struct Scene {
  ClothMesh cloth = test::grid_mesh(3, 0.2, 0.0, kNodeInverseMass);
  Vec3Array x{Vec3(0.13, 0.001, 0.07), Vec3(0.13, 0.01, 0.07), Vec3(-0.001, 0.001, -0.001),
              Vec3(0.07, -0.002, 0.16)};
  ScalarArray m{kParticleMass, kParticleMass, kParticleMass, 2.0 * kParticleMass};
  Scene() { cloth.inverse_masses[0] = 0.0; }
};

TEST(CarriedWater, CarriesTheParticlesNearTheCloth) {
  Scene s;
  CarriedWater water(kThickness + 0.5 * kSpacing, BroadPhaseKind::GRID);
  water.attach(s.cloth, s.x, s.m);
  EXPECT_EQ(water.carried_count(), 2u);  // the first and the last
  const ScalarArray& carried = water.carried_masses();
  ASSERT_EQ(carried.size(), s.cloth.node_count());
  EXPECT_EQ(carried[0], 0.0) << "a pinned node carries nothing";
  double total = 0.0;
  Vec3 moment = Vec3::Zero();
  for (std::size_t i = 0; i < carried.size(); ++i) {
    total += carried[i];
    moment += carried[i] * s.cloth.positions_t0[i];
  }
  // All of both particles' mass, on the nodes around their closest points: the carried mass's centre is the
  // mass-weighted mean of the two closest points (their projections onto y = 0).
  EXPECT_NEAR(total, s.m[0] + s.m[3], 1e-18);
  const Vec3 expected = s.m[0] * Vec3(0.13, 0.0, 0.07) + s.m[3] * Vec3(0.07, 0.0, 0.16);
  EXPECT_LT((moment - expected).norm(), 1e-18);
}

TEST(CarriedWater, HandsBackExactlyTheWatersShareOfTheClothsMomentumChange) {
  Scene s;
  CarriedWater water(kThickness + 0.5 * kSpacing, BroadPhaseKind::FCL);
  water.attach(s.cloth, s.x, s.m);
  const std::size_t nodes = s.cloth.node_count();
  Vec3Array before(nodes), end(nodes);
  for (std::size_t i = 0; i < nodes; ++i) {
    before[i] = Vec3(0.1 * i, -0.2, 0.05);
    end[i] = before[i] + Vec3(0.01 * i, 0.3 - 0.02 * i, -0.01);
  }
  end[0] = before[0] = Vec3::Zero();  // pinned
  Vec3Array x = s.x;
  Vec3Array v(s.x.size(), Vec3(0.0, -1.0, 0.0));
  const Vec3 given = water.hand_back(before, end, s.cloth, kDt, x, v, s.m);
  // The engine moved node i as m_i + carried_i; the water's part of that momentum change is what the
  // particles receive, no more and no less.
  Vec3 held = Vec3::Zero();
  for (std::size_t i = 0; i < nodes; ++i)
    held += water.carried_masses()[i] * (end[i] - before[i]);
  EXPECT_LT((given - held).norm(), 1e-18);
  Vec3 received = Vec3::Zero();
  for (std::size_t p = 0; p < x.size(); ++p) {
    received += s.m[p] * (v[p] - Vec3(0.0, -1.0, 0.0));
    EXPECT_LT((x[p] - s.x[p] - kDt * (v[p] - Vec3(0.0, -1.0, 0.0))).norm(), 1e-15)
        << "particle " << p << " moves by its velocity change over the step";
  }
  EXPECT_LT((received - held).norm(), 1e-18);
  // Each carried particle gets the velocity change of its own closest point on the cloth.
  for (std::size_t p : {std::size_t{0}, std::size_t{3}}) {
    Vec3 expected = Vec3::Zero();
    double closest = 1e300;
    for (const Triangle& tri : s.cloth.triangles) {
      const Vec3Array& c = s.cloth.positions_t0;
      const Vec3 w = closest_point_barycentric(s.x[p], c[tri[0]], c[tri[1]], c[tri[2]]);
      const double d = (s.x[p] - (w[0] * c[tri[0]] + w[1] * c[tri[1]] + w[2] * c[tri[2]])).norm();
      if (d < closest) {
        closest = d;
        expected = Vec3::Zero();
        for (int i = 0; i < 3; ++i)
          expected += w[i] * (end[tri[i]] - before[tri[i]]);
      }
    }
    EXPECT_LT((v[p] - Vec3(0.0, -1.0, 0.0) - expected).norm(), 1e-15) << "particle " << p;
  }
  EXPECT_EQ(v[1], Vec3(0.0, -1.0, 0.0)) << "not carried: untouched";
  EXPECT_EQ(v[2], Vec3(0.0, -1.0, 0.0)) << "at the pinned node: untouched";
  EXPECT_NE(v[0], Vec3(0.0, -1.0, 0.0));
}

}  // namespace
}  // namespace drench
