// Broad phases return exactly the brute-force set of (particle, triangle) pairs whose swept boxes overlap.

#include <gtest/gtest.h>

#include <random>

#include "coupling/broad_phase.hpp"
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

void expect_same_pairs_as_brute_force(BroadPhaseKind kind) {
  ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vec3& x : mesh.positions_t1)
    x += 0.01 * Vec3(u(rng), u(rng), u(rng));
  test::Particles particles;
  for (int k = 0; k < 3000; ++k) {
    const Vec3 x(0.35 * u(rng) + 0.15, 0.02 * u(rng), 0.35 * u(rng) + 0.15);
    particles.add(x, Vec3(u(rng), 3 * u(rng), u(rng)), 0.004, 1e-4);
  }
  particles.add(Vec3(-5, 0, 0), Vec3(1e4, 0, 0), 0.001, 1e-4);  // sweeps across the whole cloth in one step
  std::vector<std::pair<Index, Index>> expected, got;
  for (double margin : {0.0, 0.001, 0.02}) {
    find_pairs_brute_force(particles.x0, particles.x1, mesh, margin, expected);
    make_broad_phase(kind)->find_pairs(particles.x0, particles.x1, mesh, margin, nullptr, got);
    ASSERT_GT(expected.size(), 100u);
    EXPECT_EQ(got, expected) << "margin " << margin;
  }
}

TEST(BroadPhase, GridFindsExactlyTheBruteForcePairs) {
  expect_same_pairs_as_brute_force(BroadPhaseKind::GRID);
}

}  // namespace
}  // namespace drench
