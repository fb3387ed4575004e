// The surface's triangle bins (src/drench/surface/triangle_bins.hpp) against brute force, on a mesh of cloth-
// sized triangles beside a game's ground quad 10^4 cells across.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include <drench/surface/triangle_bins.hpp>

namespace drench {
namespace {

bool boxes_overlap(const Vec3& a_lo, const Vec3& a_hi, const Vec3& b_lo, const Vec3& b_hi) {
  return (a_lo.array() <= b_hi.array()).all() && (b_lo.array() <= a_hi.array()).all();
}

TEST(TriangleBins, FindsWhatBruteForceFindsWithAtMost8EntriesATriangle) {
  constexpr Scalar kCell = 0.02;
  std::mt19937 random(7);
  std::uniform_real_distribution<Scalar> place(-1.0, 1.0), small(0.0, 0.05);
  Vec3Array positions = {Vec3(-100, 0, -100), Vec3(100, 0, -100), Vec3(100, 0, 100), Vec3(-100, 0, 100)};
  std::vector<Triangle> triangles = {{0, 1, 2}, {0, 2, 3}};
  for (int t = 0; t < 500; ++t) {
    const Vec3 a(place(random), place(random), place(random));
    const auto first = static_cast<Index>(positions.size());
    positions.push_back(a);
    positions.push_back(a + Vec3(small(random), small(random), small(random)));
    positions.push_back(a + Vec3(small(random), small(random), small(random)));
    triangles.push_back({first, first + 1, first + 2});
  }
  const std::vector<SurfaceObstacle> obstacles = {{&positions, &triangles}};
  const TriangleBins bins(obstacles, kCell);
  // One level of 2 cm cells held the ground quad in 10^8 entries (109 s and 8.7 GB for five surface frames).
  EXPECT_LE(bins.entry_count(), 8 * triangles.size());

  std::vector<std::pair<Index, Index>> found;
  for (int q = 0; q < 2000; ++q) {
    const Vec3 lo(place(random), place(random), place(random));
    const Vec3 hi = lo + Vec3::Constant(small(random));
    bins.collect_box(lo, hi, found);
    std::vector<std::pair<Index, Index>> expected;
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Triangle& tri = triangles[t];
      const Vec3 t_lo = positions[tri[0]].cwiseMin(positions[tri[1]]).cwiseMin(positions[tri[2]]);
      const Vec3 t_hi = positions[tri[0]].cwiseMax(positions[tri[1]]).cwiseMax(positions[tri[2]]);
      if (boxes_overlap(lo, hi, t_lo, t_hi)) expected.emplace_back(0, static_cast<Index>(t));
    }
    ASSERT_EQ(found, expected) << "query " << q;
  }
  // A query far beyond int cells (1e12 m at 2 cm) finds nothing and does not overflow.
  bins.collect_box(Vec3::Constant(1e12), Vec3::Constant(1e12 + 1), found);
  EXPECT_TRUE(found.empty());
}

}  // namespace
}  // namespace drench
