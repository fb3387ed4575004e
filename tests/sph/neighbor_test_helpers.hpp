#pragma once
/// Oracles shared by the neighbor search tests: brute force over all pairs, and set comparison.

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include <drench/sph/neighbor_search.hpp>

namespace drench::testing {

inline std::vector<IndexArray> brute_force(const Vec3Array& queries, const Vec3Array& sources, Scalar radius,
                                           bool exclude_self) {
  std::vector<IndexArray> result(queries.size());
  for (std::size_t i = 0; i < queries.size(); ++i) {
    for (std::size_t j = 0; j < sources.size(); ++j) {
      if (exclude_self && i == j) continue;
      if ((queries[i] - sources[j]).squaredNorm() < radius * radius)
        result[i].push_back(static_cast<Index>(j));
    }
  }
  return result;
}

inline void expect_same_sets(const NeighborList& list, const std::vector<IndexArray>& expected) {
  ASSERT_EQ(list.offsets.size(), expected.size() + 1);
  for (std::size_t i = 0; i < expected.size(); ++i) {
    IndexArray got(list.begin(i), list.end(i));
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, expected[i]) << "query " << i;
  }
}

inline Vec3Array random_points(std::size_t n, const Vec3& lo, const Vec3& hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Scalar> u(0.0, 1.0);
  Vec3Array points(n);
  for (auto& p : points)
    p = lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
  return points;
}

/// `points` re-ordered along `search`'s z-order curve, as the fluid solver sorts its particles.
inline Vec3Array z_ordered(const NeighborSearch& search, const Vec3Array& points) {
  const IndexArray order = search.z_order(points);
  Vec3Array sorted(points.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    sorted[k] = points[order[k]];
  return sorted;
}

}  // namespace drench::testing
