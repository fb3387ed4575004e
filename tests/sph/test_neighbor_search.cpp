#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <drench/sph/candidate_scan.hpp>
#include <drench/sph/neighbor_search.hpp>
#include "neighbor_test_helpers.hpp"

namespace drench {
namespace {

using testing::brute_force;
using testing::expect_same_sets;
using testing::random_points;
using testing::z_ordered;

/// search.find() with every scan this CPU runs (NeighborSearch::set_candidate_scan): they must give the same
/// lists in the same order (the order fixes the bits of every pair sum). `list` gets the four-lane scan's,
/// which every CPU runs.
void find_with_every_scan(NeighborSearch& search, const Vec3Array& queries, NeighborList& list,
                          bool exclude_self) {
  const CandidateScan fastest = search.candidate_scan();
  ASSERT_TRUE(search.set_candidate_scan(CandidateScan::kFourLanes));
  search.find(queries, list, exclude_self);
  for (const CandidateScan scan : {CandidateScan::kAvx2Permute, CandidateScan::kAvx512Compress}) {
    if (!search.set_candidate_scan(scan)) continue;
    NeighborList other;
    search.find(queries, other, exclude_self);
    EXPECT_EQ(other.offsets, list.offsets) << "scan " << static_cast<int>(scan) << " found other counts";
    EXPECT_EQ(other.indices, list.indices) << "scan " << static_cast<int>(scan) << " found other lists";
  }
  ASSERT_TRUE(search.set_candidate_scan(fastest));
}

TEST(NeighborSearch, SelfQueryMatchesBruteForceOnRandomSets) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Vec3Array points = random_points(1500, Vec3(-0.3, -0.2, -0.1), Vec3(0.2, 0.3, 0.4), seed);
    const Scalar radius = 0.05;
    NeighborSearch search(radius);
    search.build(points);
    NeighborList list;
    find_with_every_scan(search, points, list, /*exclude_self=*/true);
    expect_same_sets(list, brute_force(points, points, radius, true));
  }
}

TEST(NeighborSearch, CrossQueryMatchesBruteForceIncludingNegativeAndFarCoordinates) {
  // Sources around a point far from the origin: cells there have large Morton keys.
  const Vec3Array sources = random_points(800, Vec3(990, -1010, 5), Vec3(990.5, -1009.5, 5.5), 11);
  const Vec3Array queries = random_points(600, Vec3(989.9, -1010.1, 4.9), Vec3(990.6, -1009.4, 5.6), 12);
  const Scalar radius = 0.08;
  NeighborSearch search(radius);
  search.build(sources);
  NeighborList list;
  find_with_every_scan(search, queries, list, /*exclude_self=*/false);
  expect_same_sets(list, brute_force(queries, sources, radius, false));
}

// find() looks a cell's runs of candidates up once for a run of queries in that cell: z-ordered queries come
// in such runs, random ones (above) almost never do, so this set is z-ordered first.
TEST(NeighborSearch, ZOrderedQueriesInRunsPerCellMatchBruteForce) {
  const Scalar radius = 0.05;
  NeighborSearch search(radius);
  const Vec3Array points = z_ordered(search, random_points(4000, Vec3(0, 0, 0), Vec3(0.4, 0.3, 0.3), 21));
  std::size_t runs = 1;
  for (std::size_t k = 1; k < points.size(); ++k)
    runs += search.cell_key(points[k]) != search.cell_key(points[k - 1]) ? 1 : 0;
  ASSERT_LT(runs, points.size() / 4) << "the queries should share cells in runs";
  search.build(points);
  NeighborList list;
  find_with_every_scan(search, points, list, /*exclude_self=*/true);
  expect_same_sets(list, brute_force(points, points, radius, true));
}

/// Builds `search` over `points` in z-order and checks find() against brute force twice: the sorted points
/// querying themselves (self excluded), and the points in their given order querying the sorted ones.
/// Returns the built layout (NeighborSearch::dense()).
bool expect_sorted_and_unsorted_queries_match_brute_force(NeighborSearch& search, const Vec3Array& points) {
  const Scalar radius = search.support_radius();
  const Vec3Array sorted = z_ordered(search, points);
  search.build(sorted);
  NeighborList list;
  find_with_every_scan(search, sorted, list, /*exclude_self=*/true);
  expect_same_sets(list, brute_force(sorted, sorted, radius, true));
  find_with_every_scan(search, points, list, /*exclude_self=*/false);
  expect_same_sets(list, brute_force(points, sorted, radius, false));
  return search.dense();
}

// A jet spread far: more cells than the dense grid allows, so cells are hashed.
TEST(NeighborSearch, SparsePointsInHashedCellsMatchBruteForce) {
  Vec3Array points = random_points(1500, Vec3(0, 0, 0), Vec3(0.2, 0.2, 0.2), 31);
  const Vec3Array far = random_points(500, Vec3(-40, -5, 0), Vec3(60, 5, 0.1), 32);
  points.insert(points.end(), far.begin(), far.end());
  NeighborSearch search(0.04);
  EXPECT_FALSE(expect_sorted_and_unsorted_queries_match_brute_force(search, points))
      << "the test is about hashed cells";
}

// Hashed rows about the origin and the clamp: a cluster straddling the origin on every axis (cell 2^20 - 1
// beside 2^20) and one at the clamp of the outermost cells (about 42 km at 4 cm), where a row's key packs
// the largest coordinates (NeighborSearch::candidate_runs).
TEST(NeighborSearch, HashedNeighborKeysAcrossTheOriginAndTheClampMatchBruteForce) {
  Vec3Array points = random_points(1500, Vec3(-0.1, -0.1, -0.1), Vec3(0.1, 0.1, 0.1), 41);
  const Vec3Array far = random_points(500, Vec3(-40, -5, 0), Vec3(60, 5, 0.1), 42);
  points.insert(points.end(), far.begin(), far.end());
  const Vec3Array clamped = random_points(300, Vec3(41943.0, -0.1, 0.0), Vec3(41943.3, 0.1, 0.1), 43);
  points.insert(points.end(), clamped.begin(), clamped.end());
  NeighborSearch search(0.04);
  EXPECT_FALSE(expect_sorted_and_unsorted_queries_match_brute_force(search, points))
      << "the test is about hashed cells";
}

// A jet over a cloth: two clusters and a thin stream between them, about 30 cells of the bounding box per
// point, mostly empty; the grid stays dense (up to 128 per point; it was hashed beyond 4 per point).
TEST(NeighborSearch, SpreadPointsInADenseGridOfMostlyEmptyCellsMatchBruteForce) {
  Vec3Array points = random_points(800, Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 41);
  const Vec3Array stream = random_points(200, Vec3(0.1, 0.1, 0.1), Vec3(0.5, 0.12, 0.12), 42);
  const Vec3Array pool = random_points(500, Vec3(0.4, 0.0, 0.3), Vec3(0.5, 0.1, 0.4), 43);
  points.insert(points.end(), stream.begin(), stream.end());
  points.insert(points.end(), pool.begin(), pool.end());
  const Scalar radius = 0.008;
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& x : points) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const Eigen::Array3d cells = (hi / radius).array().floor() - (lo / radius).array().floor() + 1.0;
  ASSERT_GT(cells.prod(), 4.0 * points.size() + 4096.0) << "the test needs more cells than 4 per point";
  NeighborSearch search(radius);
  EXPECT_TRUE(expect_sorted_and_unsorted_queries_match_brute_force(search, points))
      << "the test is about a dense grid of more than 4 cells per point";
}

// find_self() takes the built points in the grid's order, a cell at a time: it must give find()'s lists of
// the points querying themselves exactly, counts and order (the order fixes the bits of every pair sum), in
// the hashed layout (sparse points spread far) and the dense one, for points in any order.
TEST(NeighborSearch, FindSelfGivesFindsListsInTheSameOrderInEitherLayout) {
  Vec3Array sparse = random_points(1500, Vec3(0, 0, 0), Vec3(0.2, 0.2, 0.2), 51);
  const Vec3Array far = random_points(500, Vec3(-40, -5, 0), Vec3(60, 5, 0.1), 52);
  sparse.insert(sparse.end(), far.begin(), far.end());
  const Vec3Array block = random_points(2000, Vec3(-0.1, 0, 0), Vec3(0.2, 0.1, 0.3), 53);
  for (const bool dense : {false, true}) {
    NeighborSearch search(0.04);
    const Vec3Array& points = dense ? block : sparse;
    for (const Vec3Array& order : {points, z_ordered(search, points)}) {
      search.build(order);
      ASSERT_EQ(search.dense(), dense);
      NeighborList expected, got;
      search.find(order, expected, /*exclude_self=*/true);
      search.find_self(got);
      EXPECT_EQ(got.offsets, expected.offsets) << (dense ? "dense" : "hashed");
      EXPECT_EQ(got.indices, expected.indices) << (dense ? "dense" : "hashed");
      expect_same_sets(got, brute_force(order, order, 0.04, true));
    }
  }
}

// One grid rebuilt in turn hashed, dense and hashed again over other points, as the fluid's grid is every
// sub-step: the hashed layout's table of rows is built by the first find() after a build, so each find()
// must see the rows of the last build, never a former one's.
TEST(NeighborSearch, RebuildsAlternatingLayoutsFindTheLastBuildsPoints) {
  Vec3Array sparse_a = random_points(1200, Vec3(0, 0, 0), Vec3(0.2, 0.2, 0.2), 61);
  const Vec3Array far_a = random_points(400, Vec3(-40, -5, 0), Vec3(60, 5, 0.1), 62);
  sparse_a.insert(sparse_a.end(), far_a.begin(), far_a.end());
  Vec3Array sparse_b = random_points(1000, Vec3(0.1, -0.1, 0), Vec3(0.3, 0.1, 0.2), 63);
  const Vec3Array far_b = random_points(300, Vec3(-5, -40, 0), Vec3(5, 60, 0.1), 64);
  sparse_b.insert(sparse_b.end(), far_b.begin(), far_b.end());
  const Vec3Array block = random_points(1500, Vec3(-0.1, 0, 0), Vec3(0.2, 0.1, 0.3), 65);
  const Vec3Array queries = random_points(800, Vec3(-0.1, -0.1, -0.1), Vec3(0.3, 0.2, 0.3), 66);
  NeighborSearch search(0.04);
  const std::pair<const Vec3Array*, bool> builds[] = {
      {&sparse_a, false}, {&block, true}, {&sparse_b, false}, {&sparse_a, false}};
  for (const auto& [points, dense] : builds) {
    search.build(*points);
    ASSERT_EQ(search.dense(), dense);
    NeighborList self, cross;
    search.find_self(self);
    expect_same_sets(self, brute_force(*points, *points, 0.04, true));
    search.find(queries, cross, /*exclude_self=*/false);
    expect_same_sets(cross, brute_force(queries, *points, 0.04, false));
  }
}

// A NaN point (a particle the solver will name after the sub-step) sits in the grid's lowest cell: it is
// nobody's neighbor and has none, with every scan, and the other points keep exactly their neighbors.
TEST(NeighborSearch, ANaNPointIsNoNeighborAndHasNone) {
  Vec3Array points = random_points(600, Vec3(-0.1, -0.1, -0.1), Vec3(0.1, 0.1, 0.1), 51);
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  points[17] = Vec3(nan, 0.0, 0.0);
  points[300] = Vec3(nan, nan, nan);
  NeighborSearch search(0.04);
  search.build(points);
  NeighborList list;
  find_with_every_scan(search, points, list, /*exclude_self=*/true);
  EXPECT_EQ(list.count(17), 0u);
  EXPECT_EQ(list.count(300), 0u);
  expect_same_sets(list, brute_force(points, points, 0.04, true));
}

TEST(NeighborSearch, PointsExactlyAtTheRadiusAreNotNeighbors) {
  const Vec3Array points = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.0999999, 0)};
  NeighborSearch search(0.1);
  search.build(points);
  NeighborList list;
  find_with_every_scan(search, points, list, true);
  EXPECT_EQ(list.count(0), 1u);
  EXPECT_EQ(*list.begin(0), 2u);
}

/// Candidate runs for the scans: random points around the query (about a quarter inside the radius), some at
/// the radius up to rounding, some NaN, the query's own index somewhere, and padding that would be kept if a
/// scan read past the end (points at the query, indices that are not the query's).
struct CandidateRun {
  ScalarArray xs, ys, zs;
  IndexArray indices;
  std::uint32_t size = 0;
  Index self = 0;
};

CandidateRun candidate_run(std::uint32_t size, const Vec3& query, Scalar radius, std::mt19937& rng) {
  std::uniform_real_distribution<Scalar> offset(-1.3 * radius, 1.3 * radius);
  CandidateRun run;
  run.size = size;
  const std::size_t stored = size + kScanPadding;
  run.xs.assign(stored, query.x());
  run.ys.assign(stored, query.y());
  run.zs.assign(stored, query.z());
  run.indices.resize(stored);
  for (std::size_t q = 0; q < stored; ++q)
    run.indices[q] = static_cast<Index>(1000 + q);
  for (std::uint32_t q = 0; q < size; ++q) {
    Vec3 p = query + Vec3(offset(rng), offset(rng), offset(rng));
    if (q % 7 == 3) p = query + Vec3(0.0, radius, 0.0);  // at the radius, up to rounding
    if (q % 11 == 5) p.x() = std::numeric_limits<Scalar>::quiet_NaN();
    run.xs[q] = p.x();
    run.ys[q] = p.y();
    run.zs[q] = p.z();
  }
  run.self = size > 0 ? static_cast<Index>(1000 + rng() % size) : 0;
  // The query itself sits at its own position: kept only if the self test failed.
  if (size > 0) {
    const std::uint32_t own = run.self - 1000;
    run.xs[own] = query.x();
    run.ys[own] = query.y();
    run.zs[own] = query.z();
  }
  return run;
}

/// The definition: candidates q < size with |p_q - x|^2 < r2 (NaN never), other than self, in their order.
IndexArray kept_by_definition(const CandidateRun& run, const Vec3& x, Scalar r2) {
  IndexArray kept;
  for (std::uint32_t q = 0; q < run.size; ++q) {
    const Scalar d0 = run.xs[q] - x.x(), d1 = run.ys[q] - x.y(), d2 = run.zs[q] - x.z();
    if (d0 * d0 + d1 * d1 + d2 * d2 < r2 && run.indices[q] != run.self) kept.push_back(run.indices[q]);
  }
  return kept;
}

// The three scans of the grid search (sph/candidate_scan.hpp) against the definition, on runs of every length
// from 0 to 40 (whole groups of four and eight and every tail): the same indices in the same order, nothing
// from the padding, the query's own index and NaN left out, points at the radius up to rounding kept exactly
// when the definition keeps them.
TEST(CandidateScan, EveryScanKeepsExactlyTheCandidatesWithinTheRadiusInOrder) {
  std::mt19937 rng(7);
  const Vec3 query(0.31, -0.72, 1.05);
  const Scalar radius = 0.05, r2 = radius * radius;
  int avx2_runs = 0, avx512_runs = 0;
  for (int repeat = 0; repeat < 20; ++repeat) {
    for (std::uint32_t size = 0; size <= 40; ++size) {
      const CandidateRun run = candidate_run(size, query, radius, rng);
      const IndexArray expected = kept_by_definition(run, query, r2);
      IndexArray dst(size + kScanPadding, 0);
      const std::size_t count =
          scan_candidates_lanes(run.xs.data(), run.ys.data(), run.zs.data(), run.indices.data(), size, query,
                                r2, run.self, dst.data());
      ASSERT_EQ(IndexArray(dst.begin(), dst.begin() + static_cast<std::ptrdiff_t>(count)), expected)
          << "four-lane scan, " << size << " candidates";
#if DRENCH_HAS_AVX2_SCAN
      if (NeighborSearch::candidate_scan_available(CandidateScan::kAvx2Permute)) {
        std::fill(dst.begin(), dst.end(), 0);
        const std::size_t permuted =
            scan_candidates_permute(run.xs.data(), run.ys.data(), run.zs.data(), run.indices.data(), size,
                                    query, r2, run.self, dst.data());
        ASSERT_EQ(IndexArray(dst.begin(), dst.begin() + static_cast<std::ptrdiff_t>(permuted)), expected)
            << "AVX2 scan, " << size << " candidates";
        ++avx2_runs;
      }
#endif
#if DRENCH_HAS_AVX512_SCAN
      if (NeighborSearch::candidate_scan_available(CandidateScan::kAvx512Compress)) {
        std::fill(dst.begin(), dst.end(), 0);
        const std::size_t compressed =
            scan_candidates_compress(run.xs.data(), run.ys.data(), run.zs.data(), run.indices.data(), size,
                                     query, r2, run.self, dst.data());
        ASSERT_EQ(IndexArray(dst.begin(), dst.begin() + static_cast<std::ptrdiff_t>(compressed)), expected)
            << "AVX-512 scan, " << size << " candidates";
        ++avx512_runs;
      }
#endif
    }
  }
  if (avx2_runs == 0 || avx512_runs == 0)
    GTEST_SKIP() << "this CPU or build lacks AVX2 or AVX-512: checked the four-lane scan"
                 << (avx2_runs ? " and AVX2's" : "");
}

TEST(NeighborSearch, ZOrderIsAPermutationGroupingEachCell) {
  const Vec3Array points = random_points(3000, Vec3(0, 0, 0), Vec3(1, 1, 1), 3);
  NeighborSearch search(0.1);
  const IndexArray order = search.z_order(points);
  IndexArray sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t k = 0; k < sorted.size(); ++k)
    ASSERT_EQ(sorted[k], k);
  for (std::size_t k = 1; k < order.size(); ++k) {
    ASSERT_LE(search.cell_key(points[order[k - 1]]), search.cell_key(points[order[k]]));
  }
}

/// The lists' order by its definition, as slowly as can be: the sources sorted by cell (z, then y, then x of
/// floor(x / radius)), then by index; each query takes the nine rows (z, y) about its cell, z then y, each
/// row the sources of its cells x - 1 .. x + 1 in that order, and keeps those within the radius (source minus
/// query, summed x, y, z, as the scans). Every pair sum downstream follows this order, so the search must
/// give it exactly, whatever its layout or its tricks.
NeighborList lists_in_grid_order(const Vec3Array& queries, const Vec3Array& sources, Scalar radius,
                                 bool exclude_self) {
  const auto cell = [&](const Vec3& x) {
    return Vec3i(static_cast<int>(std::floor(x.x() * (1.0 / radius))),
                 static_cast<int>(std::floor(x.y() * (1.0 / radius))),
                 static_cast<int>(std::floor(x.z() * (1.0 / radius))));
  };
  const auto before = [](const Vec3i& a, const Vec3i& b) {
    if (a.z() != b.z()) return a.z() < b.z();
    if (a.y() != b.y()) return a.y() < b.y();
    return a.x() < b.x();
  };
  std::vector<Vec3i> cells(sources.size());
  IndexArray sorted(sources.size());
  for (std::size_t j = 0; j < sources.size(); ++j) {
    cells[j] = cell(sources[j]);
    sorted[j] = static_cast<Index>(j);
  }
  std::stable_sort(sorted.begin(), sorted.end(),
                   [&](Index a, Index b) { return before(cells[a], cells[b]); });
  NeighborList list;
  list.offsets.push_back(0);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const Vec3& x = queries[i];
    const Vec3i c = cell(x);
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (const Index j : sorted) {
          const Vec3i& cj = cells[j];
          if (cj.z() != c.z() + dz || cj.y() != c.y() + dy || cj.x() < c.x() - 1 || cj.x() > c.x() + 1)
            continue;
          if (exclude_self && j == i) continue;
          const Scalar d0 = sources[j].x() - x.x(), d1 = sources[j].y() - x.y(), d2 = sources[j].z() - x.z();
          if (d0 * d0 + d1 * d1 + d2 * d2 < radius * radius) list.indices.push_back(j);
        }
      }
    }
    list.offsets.push_back(static_cast<std::uint32_t>(list.indices.size()));
  }
  return list;
}

// find() and find_self() give every list in exactly the order of its definition (lists_in_grid_order), not
// only the same sets: in the dense layout and the hashed one, for points in their given order and z-ordered,
// querying themselves and other points. A change that kept the sets but moved one entry would change the
// bits of the sums that follow.
TEST(NeighborSearch, ListsFollowTheGridOrderOfTheirDefinition) {
  const Scalar radius = 0.04;
  Vec3Array sparse = random_points(700, Vec3(-0.05, 0, -0.1), Vec3(0.15, 0.2, 0.1), 61);
  const Vec3Array far = random_points(300, Vec3(-40, -5, 0), Vec3(60, 5, 0.1), 62);
  sparse.insert(sparse.end(), far.begin(), far.end());
  const Vec3Array block = random_points(1000, Vec3(-0.1, -0.05, 0), Vec3(0.1, 0.1, 0.15), 63);
  const Vec3Array queries = random_points(400, Vec3(-0.15, -0.1, -0.15), Vec3(0.2, 0.25, 0.2), 64);
  for (const bool dense : {false, true}) {
    NeighborSearch search(radius);
    const Vec3Array& points = dense ? block : sparse;
    for (const Vec3Array& order : {points, z_ordered(search, points)}) {
      search.build(order);
      ASSERT_EQ(search.dense(), dense);
      const NeighborList expected = lists_in_grid_order(order, order, radius, true);
      NeighborList got;
      find_with_every_scan(search, order, got, /*exclude_self=*/true);
      EXPECT_EQ(got.offsets, expected.offsets) << (dense ? "dense" : "hashed") << ", find";
      EXPECT_EQ(got.indices, expected.indices) << (dense ? "dense" : "hashed") << ", find";
      search.find_self(got);
      EXPECT_EQ(got.offsets, expected.offsets) << (dense ? "dense" : "hashed") << ", find_self";
      EXPECT_EQ(got.indices, expected.indices) << (dense ? "dense" : "hashed") << ", find_self";
      const NeighborList cross = lists_in_grid_order(queries, order, radius, false);
      find_with_every_scan(search, queries, got, /*exclude_self=*/false);
      EXPECT_EQ(got.offsets, cross.offsets) << (dense ? "dense" : "hashed") << ", other queries";
      EXPECT_EQ(got.indices, cross.indices) << (dense ? "dense" : "hashed") << ", other queries";
      for (const Vec3Array& query_order : {queries, z_ordered(search, queries), points}) {
        NeighborSearch query_grid(radius);
        query_grid.build(query_order);
        search.find_for_points_of(query_grid, got);
        const NeighborList expected_cross = lists_in_grid_order(query_order, order, radius, false);
        EXPECT_EQ(got.offsets, expected_cross.offsets) << (dense ? "dense" : "hashed") << ", another grid's";
        EXPECT_EQ(got.indices, expected_cross.indices) << (dense ? "dense" : "hashed") << ", another grid's";
      }
    }
  }
}

// The hashed layout's cursors, which find_self and find_for_points_of move along each row and over the rows'
// keys from cell to cell, moving far in one step: a query row with cells 12 apart beside a row of 21 cells,
// and query rows 14 apart beside a plane of 16 rows (each cursor takes up to four entries per step). The
// lists must still be those of their definition, in order.
TEST(NeighborSearch, HashedCursorsMovingFarGiveTheListsOfTheirDefinition) {
  const Scalar radius = 0.04;
  std::mt19937 random(81);
  std::uniform_real_distribution<Scalar> within(0.1, 0.9);
  Vec3Array points;
  const auto in_cell = [&](int x, int y, int z) {
    points.push_back(radius * Vec3(x + within(random), y + within(random), z + within(random)));
  };
  for (int x = 0; x <= 20; ++x) {
    in_cell(x, 1, 1);
    if (x % 2 == 0) in_cell(x, 1, 1);  // some cells of two points
  }
  in_cell(0, 0, 1);
  in_cell(12, 0, 1);
  for (int y = 0; y <= 15; ++y)
    in_cell(0, y, 0);
  in_cell(0, 14, 1);
  points.push_back(Vec3(50.0, 0.0, 0.0));  // far apart: the cells are hashed
  points.push_back(Vec3(-50.0, 0.0, 0.0));
  NeighborSearch search(radius);
  for (const Vec3Array& order : {points, z_ordered(search, points)}) {
    search.build(order);
    ASSERT_FALSE(search.dense()) << "the test is about hashed cells";
    const NeighborList expected = lists_in_grid_order(order, order, radius, true);
    NeighborList got;
    search.find_self(got);
    EXPECT_EQ(got.offsets, expected.offsets) << "find_self";
    EXPECT_EQ(got.indices, expected.indices) << "find_self";
    search.find(order, got, /*exclude_self=*/true);
    EXPECT_EQ(got.offsets, expected.offsets) << "find";
    EXPECT_EQ(got.indices, expected.indices) << "find";
    NeighborSearch query_grid(radius);
    query_grid.build(order);
    search.find_for_points_of(query_grid, got);
    const NeighborList cross = lists_in_grid_order(order, order, radius, false);
    EXPECT_EQ(got.offsets, cross.offsets) << "find_for_points_of";
    EXPECT_EQ(got.indices, cross.indices) << "find_for_points_of";
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < order.size(); ++i)
      pairs += expected.count(i);
    EXPECT_GT(pairs, order.size()) << "the points should have neighbors";
  }
}

// Another grid's points are its cells' points only if its cells are this grid's: a grid of other cells is
// refused by name.
TEST(NeighborSearch, FindForPointsOfAGridOfOtherCellsThrows) {
  const Vec3Array points = random_points(50, Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 71);
  NeighborSearch search(0.04), other(0.05);
  search.build(points);
  other.build(points);
  NeighborList list;
  EXPECT_THROW(search.find_for_points_of(other, list), std::invalid_argument);
}

TEST(NeighborSearch, EmptySourceSetGivesNoNeighbors) {
  NeighborSearch search(0.1);
  search.build({});
  NeighborList list;
  find_with_every_scan(search, {Vec3::Zero()}, list, false);
  EXPECT_EQ(list.count(0), 0u);
}

}  // namespace
}  // namespace drench
