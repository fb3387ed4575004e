#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <drench/sph/verlet_neighbor_lists.hpp>
#include "neighbor_test_helpers.hpp"

namespace drench {
namespace {

using testing::brute_force;
using testing::expect_same_sets;
using testing::random_points;

constexpr Scalar kRadius = 0.05;  // the support: smoothing length 0.025 m
constexpr Scalar kSkin = 0.01;
const CubicSplineKernel kKernel(0.5 * kRadius);

std::vector<std::uint32_t> sequential_ids(std::size_t n) {
  std::vector<std::uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  return ids;
}

/// Every pair's gradient factor is the kernel's at the pair's distance now, rounded to float: within half a
/// float ulp (2^-24 relative) of the double value, plus 1e-12 for the double's own rounding.
void expect_gradient_factors(const NeighborList& list, const GradientFactorArray& factors,
                             const Vec3Array& points, const Vec3Array& sources) {
  ASSERT_EQ(factors.size(), list.indices.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::uint32_t n = list.offsets[i]; n < list.offsets[i + 1]; ++n) {
      const Scalar expected = kKernel.gradient_factor((sources[list.indices[n]] - points[i]).squaredNorm());
      ASSERT_NEAR(factors[n], expected, (0x1p-24 + 1e-12) * std::abs(expected))
          << "pair " << i << ", " << list.indices[n];
    }
  }
}

void expect_exact_lists(const VerletNeighborLists& lists, const Vec3Array& points,
                        const Vec3Array& boundary) {
  expect_same_sets(lists.fluid(), brute_force(points, points, kRadius, true));
  expect_same_sets(lists.boundary(), brute_force(points, boundary, kRadius, false));
  expect_gradient_factors(lists.fluid(), lists.fluid_gradient_factors(), points, points);
  expect_gradient_factors(lists.boundary(), lists.boundary_gradient_factors(), points, boundary);
}

TEST(VerletNeighborLists, GiveExactlyTheNeighborsOfAFreshSearchWhileReusingCandidates) {
  // Points drift by up to 1.5 mm per update; the skin (10 mm) lets the candidates serve while no point has
  // moved 5 mm since the last rebuild. Every update must still report exactly the pairs closer than the
  // support, and rebuild exactly when some point moved beyond half the skin.
  Vec3Array points = random_points(1500, Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.3), 21);
  const Vec3Array boundary = random_points(600, Vec3(-0.05, -0.05, -0.05), Vec3(0.45, 0.0, 0.35), 22);
  const auto ids = sequential_ids(points.size());
  VerletNeighborLists lists(kKernel, kSkin, boundary);
  std::mt19937 rng(23);
  std::uniform_real_distribution<Scalar> step(-0.0015 / std::sqrt(3.0), 0.0015 / std::sqrt(3.0));
  Vec3Array at_rebuild;
  int rebuilds = 0;
  for (int update = 0; update < 40; ++update) {
    Scalar moved = 0.0;
    for (std::size_t i = 0; i < at_rebuild.size(); ++i)
      moved = std::max(moved, (points[i] - at_rebuild[i]).norm());
    const bool expected = at_rebuild.empty() || moved > 0.5 * kSkin;
    ASSERT_EQ(lists.update(points, ids, kSkin), expected) << "update " << update << ", moved " << moved;
    if (expected) {
      at_rebuild = points;
      ++rebuilds;
    }
    expect_exact_lists(lists, points, boundary);
    for (Vec3& p : points)
      p += Vec3(step(rng), step(rng), step(rng));
  }
  // Both paths ran: reuse (at most every fourth update rebuilds at 1.5 mm per update) and rebuilds.
  EXPECT_GT(rebuilds, 2);
  EXPECT_LT(rebuilds, 15);
}

TEST(VerletNeighborLists, OneParticleJumpingFarForcesARebuild) {
  Vec3Array points = random_points(800, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3), 31);
  const Vec3Array boundary = random_points(200, Vec3(0, -0.04, 0), Vec3(0.3, 0.0, 0.3), 32);
  const auto ids = sequential_ids(points.size());
  VerletNeighborLists lists(kKernel, kSkin, boundary);
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  points[17] = points[400] + Vec3(0.001, 0.0, 0.0);  // into another particle's neighborhood
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  expect_exact_lists(lists, points, boundary);
}

TEST(VerletNeighborLists, RebuildWhenParticlesAreReorderedAddedOrRemoved) {
  Vec3Array points = random_points(900, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3), 41);
  const Vec3Array boundary = random_points(200, Vec3(0, -0.04, 0), Vec3(0.3, 0.0, 0.3), 42);
  auto ids = sequential_ids(points.size());
  VerletNeighborLists lists(kKernel, kSkin, boundary);
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  EXPECT_FALSE(lists.update(points, ids, kSkin));  // nothing moved

  // Re-sorted: the same points in another order, with their ids.
  std::reverse(points.begin(), points.end());
  std::reverse(ids.begin(), ids.end());
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  expect_exact_lists(lists, points, boundary);

  // Emitted: one more particle, in the middle of the others.
  points.push_back(Vec3(0.15, 0.15, 0.15));
  ids.push_back(5000);
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  expect_exact_lists(lists, points, boundary);

  // Removed and emitted in one step: same count, another particle.
  points.erase(points.begin() + 3);
  ids.erase(ids.begin() + 3);
  points.push_back(Vec3(0.1, 0.2, 0.1));
  ids.push_back(5001);
  EXPECT_TRUE(lists.update(points, ids, kSkin));
  expect_exact_lists(lists, points, boundary);
}

TEST(VerletNeighborLists, WithoutASkinSearchEveryTime) {
  const Vec3Array points = random_points(700, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3), 51);
  const Vec3Array boundary = random_points(200, Vec3(0, -0.04, 0), Vec3(0.3, 0.0, 0.3), 52);
  const auto ids = sequential_ids(points.size());
  VerletNeighborLists lists(kKernel, kSkin, boundary);
  for (int update = 0; update < 3; ++update) {
    EXPECT_TRUE(lists.update(points, ids, 0.0));
    expect_exact_lists(lists, points, boundary);
  }
}

TEST(VerletNeighborLists, FluidGradientFactorsTurnedOffLeaveTheListsExact) {
  // Off for PBF: the lists and the boundary's factors stay exact on each path (the exact search, a rebuild
  // with a skin, a reuse of its candidates), and the fluid's factors are not taken.
  Vec3Array points = random_points(700, Vec3(0, 0, 0), Vec3(0.3, 0.3, 0.3), 71);
  const Vec3Array boundary = random_points(200, Vec3(0, -0.04, 0), Vec3(0.3, 0.0, 0.3), 72);
  const auto ids = sequential_ids(points.size());
  VerletNeighborLists lists(kKernel, kSkin, boundary);
  lists.set_fluid_gradient_factors(false);
  const bool rebuilds[] = {true, true, false};
  for (int update = 0; update < 3; ++update) {
    EXPECT_EQ(lists.update(points, ids, update == 0 ? 0.0 : kSkin), rebuilds[update]) << "update " << update;
    expect_same_sets(lists.fluid(), brute_force(points, points, kRadius, true));
    expect_same_sets(lists.boundary(), brute_force(points, boundary, kRadius, false));
    expect_gradient_factors(lists.boundary(), lists.boundary_gradient_factors(), points, boundary);
    EXPECT_TRUE(lists.fluid_gradient_factors().empty());
    for (Vec3& p : points)
      p += Vec3(0.0005, 0.0, 0.0);
  }
}

}  // namespace
}  // namespace drench
