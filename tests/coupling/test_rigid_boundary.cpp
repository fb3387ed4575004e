// Boundary particles of moving rigid bodies (coupling/rigid_boundary.hpp): which bodies have them, and that a
// body at rest keeps the very samples a fresh placing would give.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <drench/coupling/rigid_boundary.hpp>

#include "coupling_fixtures.hpp"

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // the fluid's particle spacing (unit: m)

RigidSurface cube(std::uint64_t key, RigidMotion motion, const Vec3& corner, double side) {
  return test::cube_surface(key, motion, corner, side);
}

/// The surface moved by `offset` (unit: m).
RigidSurface moved(RigidSurface s, const Vec3& offset) {
  for (Vec3& x : s.positions_t0)
    x += offset;
  s.positions_t1 = s.positions_t0;
  return s;
}

TEST(RigidBoundary, OnlyDynamicBodiesHaveSamplesAndEachLiesInsideItsBody) {
  RigidBoundary boundary(kSpacing);
  const std::vector<RigidSurface> surfaces = {
      cube(1, RigidMotion::STATIC, Vec3(-1, -1, -1), 0.5),  // a table: held by the coupling alone
      cube(2, RigidMotion::DYNAMIC, Vec3(0, 0, 0), 0.05),
      cube(3, RigidMotion::KINEMATIC, Vec3(1, 1, 1), 0.05),
  };
  ASSERT_TRUE(boundary.place(surfaces));
  // 12 faces whose longest edge, the diagonal, is 7.07 spacings: 8^2 sub-triangles each.
  ASSERT_EQ(boundary.positions().size(), 12u * 64u);
  ASSERT_EQ(boundary.volumes().size(), boundary.positions().size());
  ASSERT_EQ(boundary.normals().size(), boundary.positions().size());
  for (std::size_t b = 0; b < boundary.positions().size(); ++b) {
    const Vec3& x = boundary.positions()[b];
    const Vec3& n = boundary.normals()[b];
    // Inside the dynamic cube, inset() behind the face its normal names, to rounding.
    EXPECT_GT(x.minCoeff(), 0.0);
    EXPECT_LT(x.maxCoeff(), 0.05);
    int axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    ASSERT_NEAR(std::abs(n[axis]), 1.0, 1e-12);
    const double behind = n[axis] > 0.0 ? 0.05 - x[axis] : x[axis];
    EXPECT_NEAR(behind, boundary.inset(), 1e-12);
    EXPECT_GT(boundary.volumes()[b], 0.0);
  }
}

// A 2 mm plank's samples sat inset() = 6 mm behind their faces, 4 mm outside the opposite face, and pushed
// the water as the plank came near (a 14 g plank dropped into a tank was thrown up at 18 m/s). Where a body
// is thinner than twice inset(), its samples sit half way through it.
TEST(RigidBoundary, EverySampleLiesInsideAThinBody) {
  for (const Vec3& extents : {Vec3(0.12, 0.002, 0.12), Vec3(0.003, 0.003, 0.003), Vec3(0.2, 0.05, 0.009)}) {
    SCOPED_TRACE(extents.transpose());
    RigidSurface body = cube(1, RigidMotion::DYNAMIC, Vec3::Zero(), 1.0);
    for (Vec3& x : body.positions_t0)
      x = x.cwiseProduct(extents);
    body.positions_t1 = body.positions_t0;
    RigidBoundary boundary(kSpacing);
    ASSERT_TRUE(boundary.place({body}));
    ASSERT_FALSE(boundary.positions().empty());
    for (std::size_t b = 0; b < boundary.positions().size(); ++b) {
      const Vec3& x = boundary.positions()[b];
      const Vec3& n = boundary.normals()[b];
      int axis = 0;
      n.cwiseAbs().maxCoeff(&axis);
      // Behind its face by inset(), or by half the body where that is thinner, to rounding; inside the body.
      const double behind = n[axis] > 0.0 ? extents[axis] - x[axis] : x[axis];
      EXPECT_NEAR(behind, std::min(boundary.inset(), 0.5 * extents[axis]), 1e-12) << "sample " << b;
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(x[k], -1e-12) << "sample " << b;
        EXPECT_LE(x[k], extents[k] + 1e-12) << "sample " << b;
      }
    }
  }
}

// A 1 m x 4 cm x 4 cm rod: each long face, sampled as 101^2 sub-triangles similar to it, took 10,000
// samples where its area needs a few hundred (a 1 m convex hull took 12.8 GB). Its slivers are sampled in
// rows across instead: samples in proportion to the area, and none of the face farther than a spacing from
// one.
TEST(RigidBoundary, ASliverFaceTakesSamplesByItsAreaAndIsCoveredByThem) {
  RigidSurface rod = cube(1, RigidMotion::DYNAMIC, Vec3::Zero(), 1.0);
  const Vec3 extents(1.0, 0.04, 0.04);
  for (Vec3& x : rod.positions_t0)
    x = x.cwiseProduct(extents);
  rod.positions_t1 = rod.positions_t0;
  RigidBoundary boundary(kSpacing);
  ASSERT_TRUE(boundary.place({rod}));
  const double area = 2 * (1.0 * 0.04 + 1.0 * 0.04 + 0.04 * 0.04);
  // At most 2 samples per square spacing (the similar sub-triangles gave 50).
  EXPECT_LE(static_cast<double>(boundary.positions().size()), 2.0 * area / (kSpacing * kSpacing));
  const Vec3Array& samples = boundary.positions();
  // Every point of the face y = 0 (a grid of 2 mm) has a sample within a spacing, inset aside.
  for (double x = 0.0; x <= 1.0; x += 0.002) {
    for (double z = 0.0; z <= 0.04; z += 0.002) {
      double nearest = INFINITY;
      for (const Vec3& b : samples)
        if (std::abs(b.y() - boundary.inset()) < 1e-9)
          nearest = std::min(nearest, (b - Vec3(x, b.y(), z)).norm());
      ASSERT_LE(nearest, kSpacing) << "at x " << x << " z " << z;
    }
  }
}

TEST(RigidBoundary, ABodyAtRestKeepsTheBitsAFreshPlacingGives) {
  RigidBoundary boundary(kSpacing);
  const RigidSurface ball = cube(7, RigidMotion::DYNAMIC, Vec3(0.2, 0.3, 0.1), 0.04);
  const RigidSurface crate = cube(8, RigidMotion::DYNAMIC, Vec3(-0.2, 0.1, 0.0), 0.03);
  const Vec3 nudge(1e-3, -2e-4, 3e-5);
  ASSERT_TRUE(boundary.place({ball, crate}));
  // Nothing moved: no change, and the same points.
  const Vec3Array first = boundary.positions();
  const ScalarArray volumes = boundary.volumes();
  EXPECT_FALSE(boundary.place({ball, crate}));
  EXPECT_EQ(boundary.positions(), first);
  // The crate moves, the ball rests: a change, and bit for bit the points a new RigidBoundary places there
  // (the volumes are the bodies' own, from their first sampling: the bodies are rigid).
  const std::vector<RigidSurface> later = {ball, moved(crate, nudge)};
  ASSERT_TRUE(boundary.place(later));
  RigidBoundary fresh(kSpacing);
  ASSERT_TRUE(fresh.place(later));
  EXPECT_EQ(boundary.positions(), fresh.positions());
  EXPECT_EQ(boundary.volumes(), volumes);
  EXPECT_EQ(boundary.normals(), fresh.normals());
  EXPECT_NE(boundary.positions(), first);
  // A body that leaves, or the same bodies in another order, change the points though none moved.
  EXPECT_TRUE(boundary.place({ball}));
  EXPECT_TRUE(boundary.place({later[1], ball}));
  RigidBoundary reordered(kSpacing);
  ASSERT_TRUE(reordered.place({later[1], ball}));
  EXPECT_EQ(boundary.positions(), reordered.positions());
  // A static body coming or going changes nothing: it has no samples.
  EXPECT_FALSE(boundary.place({later[1], cube(9, RigidMotion::STATIC, Vec3(0, 0, 0), 1.0), ball}));
}

/// The surface turned by `angle` (unit: rad) about the z axis through `pivot` (unit: m).
RigidSurface turned(RigidSurface s, double angle, const Vec3& pivot) {
  const double c = std::cos(angle), sn = std::sin(angle);
  for (Vec3& x : s.positions_t0) {
    const Vec3 d = x - pivot;
    x = pivot + Vec3(c * d.x() - sn * d.y(), sn * d.x() + c * d.y(), d.z());
  }
  s.positions_t1 = s.positions_t0;
  return s;
}

TEST(RigidBoundary, EveryPlacingGivesTheBitsOfAFreshOne) {
  // place() writes each moved body's samples where they were and leaves a resting body's alone; after any
  // sequence of motions, arrivals and departures its points and normals are bit for bit those a new
  // RigidBoundary places for the same bodies (the volumes are the bodies' own from their first sampling).
  RigidBoundary boundary(kSpacing);
  const RigidSurface ball = cube(7, RigidMotion::DYNAMIC, Vec3(0.2, 0.3, 0.1), 0.04);
  const RigidSurface crate = cube(8, RigidMotion::DYNAMIC, Vec3(-0.2, 0.1, 0.0), 0.03);
  const RigidSurface table = cube(9, RigidMotion::STATIC, Vec3(-1, -1, -1), 0.5);
  const Vec3 pivot(0.1, 0.2, 0.0);
  const std::vector<std::vector<RigidSurface>> steps = {
      {ball, table, crate},
      {turned(ball, 0.3, pivot), table, crate},                           // the ball turns, the crate rests
      {turned(ball, 0.3, pivot), table, moved(crate, Vec3(1e-3, 0, 0))},  // the ball rests, the crate slides
      {turned(ball, 0.7, pivot), table, moved(crate, Vec3(2e-3, 0, 0))},  // both move
      {table, moved(crate, Vec3(2e-3, 0, 0))},                            // the ball leaves, the crate rests
      {moved(crate, Vec3(2e-3, 0, 0)), turned(ball, -0.2, pivot)},        // it comes back, after the crate
      {moved(crate, Vec3(3e-3, 1e-4, 0)), turned(ball, -0.2, pivot)},     // the crate alone moves
  };
  for (std::size_t k = 0; k < steps.size(); ++k) {
    EXPECT_TRUE(boundary.place(steps[k])) << "step " << k;  // each step moves a body or changes the list
    RigidBoundary fresh(kSpacing);
    ASSERT_TRUE(fresh.place(steps[k]));
    ASSERT_EQ(boundary.positions().size(), fresh.positions().size()) << "step " << k;
    EXPECT_EQ(boundary.positions(), fresh.positions()) << "step " << k;
    EXPECT_EQ(boundary.normals(), fresh.normals()) << "step " << k;
    EXPECT_EQ(boundary.volumes().size(), fresh.positions().size()) << "step " << k;
    // Nothing moved since: no change, and the same bits.
    const Vec3Array placed = boundary.positions();
    EXPECT_FALSE(boundary.place(steps[k])) << "step " << k;
    EXPECT_EQ(boundary.positions(), placed) << "step " << k;
  }
}

TEST(RigidBoundary, SpreadGivesTheNodesOfEachSampledFaceItsImpulseByWeight) {
  // Most samples of a body get no impulse (no water near them). Those that do pass it to the three nodes of
  // their face by their barycentric weights: the nodes' sum is the samples' (momentum passes whole), and a
  // lone sample's impulse lands on its own face's nodes only.
  RigidBoundary boundary(kSpacing);
  const std::vector<RigidSurface> surfaces = {cube(1, RigidMotion::STATIC, Vec3(-1, -1, -1), 0.5),
                                              cube(2, RigidMotion::DYNAMIC, Vec3(0, 0, 0), 0.03)};
  ASSERT_TRUE(boundary.place(surfaces));
  const std::size_t count = boundary.positions().size();
  const std::vector<std::size_t> first_node = {0, 8};  // the static cube's 8 nodes come first
  Vec3Array impulses(count, Vec3::Zero());
  const std::size_t lone = count / 3;
  impulses[lone] = Vec3(0.25, -1.0, 0.5);  // (unit: N s)
  Vec3Array nodes(16, Vec3::Zero());
  boundary.spread(surfaces, impulses, first_node, nodes);
  Vec3 sum = Vec3::Zero();
  int touched = 0;
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    sum += nodes[n];
    if (nodes[n] != Vec3::Zero()) {
      ++touched;
      EXPECT_GE(n, 8u) << "a static body's node took an impulse";
    }
  }
  EXPECT_NEAR((sum - impulses[lone]).norm(), 0.0, 1e-15);
  EXPECT_EQ(touched, 3);  // a sample inside its face: all three weights > 0
  // Every sample pushed: the sum is still theirs, to rounding.
  Vec3 total = Vec3::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    impulses[k] = Vec3(1e-3 * static_cast<double>(k % 7), -2e-3, 1e-3 * static_cast<double>(k % 5));
    total += impulses[k];
  }
  nodes.assign(16, Vec3::Zero());
  boundary.spread(surfaces, impulses, first_node, nodes);
  sum = Vec3::Zero();
  for (const Vec3& j : nodes)
    sum += j;
  EXPECT_NEAR((sum - total).norm(), 0.0, 1e-12 * total.norm());
}

}  // namespace
}  // namespace drench
