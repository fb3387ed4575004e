// The fast point-triangle CCD (eq. 5-6): analytic cases with a known answer, then random and adversarial
// families checked against the exact rational reference.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <utility>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/ccd/point_triangle_ccd.hpp>
#include "ccd_query_builders.hpp"

namespace drench::ccd {
namespace {

using test::QueryGenerator;
using test::static_triangle;
using test::transformed;

constexpr double kWeightTolerance = 1e-12;  // barycentric weights: >= -this, sum within this of 1

/// Output invariants that hold for every query: finite numbers, toi in [0, 1], weights on the triangle.
void expect_well_formed(const CcdResult& r) {
  EXPECT_TRUE(std::isfinite(r.toi));
  EXPECT_GE(r.toi, 0.0);
  EXPECT_LE(r.toi, 1.0);
  EXPECT_TRUE(r.barycentric.allFinite());
  if (r.hit) {
    EXPECT_GE(r.barycentric.minCoeff(), -kWeightTolerance);
    EXPECT_NEAR(r.barycentric.sum(), 1.0, kWeightTolerance);
  }
}

TEST(PointTriangleCcd, ReportsHeadOnCrossingAtItsTime) {
  // Straight down through (0.25, 0.25) from z = 1 to z = -3: crosses z = 0 at t = 1/4.
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -3)));
  ASSERT_TRUE(r.hit);
  const CcdSettings defaults;
  EXPECT_LE(r.toi, 0.25);
  EXPECT_GE(r.toi, 0.25 - defaults.toi_tolerance);
  EXPECT_NEAR(r.barycentric[0], 0.5, 1e-5);
  EXPECT_NEAR(r.barycentric[1], 0.25, 1e-5);
  EXPECT_NEAR(r.barycentric[2], 0.25, 1e-5);
}

TEST(PointTriangleCcd, ReportsNoContactBesideTheTriangle) {
  EXPECT_FALSE(point_triangle_ccd(static_triangle(Vec3(0.6, 0.6, 1), Vec3(0.6, 0.6, -1))).hit);
  EXPECT_FALSE(point_triangle_ccd(static_triangle(Vec3(-1e-9, 0.5, 1), Vec3(-1e-9, 0.5, -1))).hit);
}

TEST(PointTriangleCcd, ReportsNoContactWhenStoppingShortOfThePlane) {
  EXPECT_FALSE(point_triangle_ccd(static_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 1e-300))).hit);
}

TEST(PointTriangleCcd, CountsTouchingAtTheEndOfTheStep) {
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0)));
  ASSERT_TRUE(r.hit);
  EXPECT_GE(r.toi, 1.0 - CcdSettings{}.toi_tolerance);
}

TEST(PointTriangleCcd, CountsTouchingAtTheStartOfTheStep) {
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1)));
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.toi, 0.0);
}

TEST(PointTriangleCcd, ReportsContactForHeadOnApproachThroughEdge) {
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(0.5, 0.5, 1), Vec3(0.5, 0.5, -1)));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.barycentric[0], 0.0, 1e-6);
  EXPECT_NEAR(r.toi, 0.5, 1e-5);
}

TEST(PointTriangleCcd, ReportsContactThroughAVertex) {
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(1, 0, 1), Vec3(1, 0, -1)));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.barycentric[1], 1.0, 1e-6);
}

TEST(PointTriangleCcd, ReportsGrazingTouchOfAnEdgeLine) {
  // Slides along z = 0 on the line y = 0 from x = -1 to x = 2: on the closed edge ab for x in [0, 1].
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(-1, 0, 0), Vec3(2, 0, 0)));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.toi, 1.0 / 3.0, 1e-5);
}

TEST(PointTriangleCcd, ReportsPointSlidingIntoTheTriangleInItsPlane) {
  const CcdResult r = point_triangle_ccd(static_triangle(Vec3(-1, 0.25, 0), Vec3(1, 0.25, 0)));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.toi, 0.5, 1e-5);
}

TEST(PointTriangleCcd, ReportsNoContactForPointSlidingPastInThePlane) {
  EXPECT_FALSE(point_triangle_ccd(static_triangle(Vec3(-1, -0.25, 0), Vec3(1, -0.25, 0))).hit);
}

TEST(PointTriangleCcd, ReportsTriangleMovingOntoAStillPoint) {
  VertexFaceQuery q = static_triangle(Vec3(0.2, 0.3, 0.5), Vec3(0.2, 0.3, 0.5));
  q.a_t1 = q.a_t0 + Vec3(0, 0, 1);
  q.b_t1 = q.b_t0 + Vec3(0, 0, 1);
  q.c_t1 = q.c_t0 + Vec3(0, 0, 1);
  const CcdResult r = point_triangle_ccd(q);
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.toi, 0.5, 1e-5);
}

/// Triangle (0,0,0), (1,0,0), (0,1,z) with z: 1 -> -1 tilting about the x axis, and a point whose path makes
/// eq. 6 equal to 2 (t - 1/2)^2 + gap: for gap = 0 a double root, the point touching the plane at t = 1/2
/// without crossing it, at (0.1, 0.75, 0), inside the triangle.
VertexFaceQuery tangential_touch(double gap) {
  VertexFaceQuery q;
  q.a_t0 = q.a_t1 = Vec3(0, 0, 0);
  q.b_t0 = q.b_t1 = Vec3(1, 0, 0);
  q.c_t0 = Vec3(0, 1, 1);
  q.c_t1 = Vec3(0, 1, -1);
  q.p_t0 = Vec3(0.1, 0.25, 0.75 + gap);
  q.p_t1 = Vec3(0.1, 1.25, -0.75 + gap);
  return q;
}

TEST(PointTriangleCcd, ReportsTangentialTouchAtADoubleRoot) {
  const CcdResult r = point_triangle_ccd(tangential_touch(0.0));
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.toi, 0.5, 1e-5);
  EXPECT_LE(r.toi, 0.5);
}

TEST(PointTriangleCcd, ReportsNoContactForANearMissAtADoubleRoot) {
  EXPECT_FALSE(point_triangle_ccd(tangential_touch(0x1p-40)).hit);
}

TEST(PointTriangleCcd, ReportsZeroAreaTriangleOnlyWhereThePointMeetsIt) {
  // A degenerate triangle (all vertices on the x axis): the point crosses the segment [0, 2] at x = 1.
  VertexFaceQuery q;
  q.a_t0 = q.a_t1 = Vec3(0, 0, 0);
  q.b_t0 = q.b_t1 = Vec3(2, 0, 0);
  q.c_t0 = q.c_t1 = Vec3(1, 0, 0);
  q.p_t0 = Vec3(1, 1, 1);
  q.p_t1 = Vec3(1, -1, -1);
  EXPECT_TRUE(point_triangle_ccd(q).hit);
  q.p_t0 = Vec3(3, 1, 1);
  q.p_t1 = Vec3(3, -1, -1);
  EXPECT_FALSE(point_triangle_ccd(q).hit);
}

TEST(PointTriangleCcd, RejectsNonFiniteCoordinatesNamingThem) {
  VertexFaceQuery q = static_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1));
  q.b_t1[1] = std::numeric_limits<double>::quiet_NaN();
  try {
    point_triangle_ccd(q);
    FAIL() << "expected InvalidQueryError";
  } catch (const InvalidQueryError& e) {
    EXPECT_NE(std::string(e.what()).find("b_t1.y"), std::string::npos) << e.what();
  }
  q.b_t1[1] = 0.0;
  q.p_t0[2] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(point_triangle_ccd(q), InvalidQueryError);
  EXPECT_THROW(point_triangle_ccd_exact(q), InvalidQueryError);
}

/// Runs `count` queries of a family through both solvers and asserts the same decision and a consistent toi.
void expect_agreement_with_exact(const std::string& family, int count,
                                 const std::function<VertexFaceQuery()>& make) {
  int hits = 0;
  int exact_path = 0;
  const CcdSettings settings;
  for (int i = 0; i < count; ++i) {
    const VertexFaceQuery q = make();
    const CcdResult fast = point_triangle_ccd(q, settings);
    const ExactCcdResult exact = point_triangle_ccd_exact(q, 0.0, settings.toi_tolerance);
    expect_well_formed(fast);
    ASSERT_EQ(fast.hit, exact.hit) << family << " query " << i;
    if (fast.hit) {
      ++hits;
      // The true first contact lies in [exact.toi_lower, exact.toi_upper] and in [fast.toi, fast.toi + tol].
      EXPECT_LE(fast.toi, exact.toi_upper) << family << " query " << i;
      EXPECT_GE(fast.toi + settings.toi_tolerance, exact.toi_lower) << family << " query " << i;
    }
    exact_path += fast.path == CcdPath::EXACT;
  }
  // Each family must exercise both answers, or it tests less than it claims.
  EXPECT_GT(hits, 0) << family;
  EXPECT_LT(hits, count) << family;
  ::testing::Test::RecordProperty(family + "_hits", hits);
  ::testing::Test::RecordProperty(family + "_exact_path", exact_path);
}

TEST(PointTriangleCcdProperty, AgreesWithExactOnAimedQueries) {
  QueryGenerator gen(1);
  expect_agreement_with_exact("aimed", 3000, [&] { return gen.aimed(); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactWhenScaledBy1em3And1e3) {
  QueryGenerator gen(2);
  expect_agreement_with_exact("scaled_1e-3", 1000,
                              [&] { return transformed(gen.aimed(), 1e-3, Vec3::Zero()); });
  expect_agreement_with_exact("scaled_1e3", 1000,
                              [&] { return transformed(gen.aimed(), 1e3, Vec3::Zero()); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactTranslated1e3MetresFromTheOrigin) {
  QueryGenerator gen(3);
  expect_agreement_with_exact("translated_1e3", 1000,
                              [&] { return transformed(gen.aimed(), 1.0, Vec3(1e3, -1e3, 1e3)); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactForMotionsDownTo1em12) {
  QueryGenerator gen(4);
  expect_agreement_with_exact("tiny_motion", 1000, [&] { return gen.tiny_motion(); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactOnGridQueriesWithExactContacts) {
  QueryGenerator gen(5);
  expect_agreement_with_exact("grid", 3000, [&] { return gen.grid(); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactForZeroAreaTriangles) {
  QueryGenerator gen(6);
  expect_agreement_with_exact("zero_area", 1000, [&] { return gen.zero_area(); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactForMotionInsideTheTrianglesPlane) {
  QueryGenerator gen(7);
  expect_agreement_with_exact("coplanar", 1000, [&] { return gen.coplanar(); });
  expect_agreement_with_exact("sliding_in_tilted_plane", 1000, [&] { return gen.sliding_in_plane(); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactWhereTheFilterOverflows) {
  // Coordinates near 1e100: products of five differences overflow double, so the filter must hand the query
  // to the exact reference instead of deciding on infinities (the fuzzer does not reach this range: too
  // slow).
  QueryGenerator gen(9);
  expect_agreement_with_exact("scaled_1e100", 200,
                              [&] { return transformed(gen.aimed(), 1e100, Vec3::Zero()); });
  expect_agreement_with_exact("scaled_1e-100", 200,
                              [&] { return transformed(gen.aimed(), 1e-100, Vec3::Zero()); });
}

TEST(PointTriangleCcdProperty, AgreesWithExactThroughEdgesAndVertices) {
  QueryGenerator gen(8);
  int hits = 0;
  for (int i = 0; i < 500; ++i) {
    const VertexFaceQuery q = gen.through_edge_or_vertex();
    const CcdResult fast = point_triangle_ccd(q);
    expect_well_formed(fast);
    ASSERT_TRUE(fast.hit) << "query " << i;  // every one passes exactly through the closed triangle
    ASSERT_TRUE(point_triangle_ccd_exact(q).hit) << "query " << i;
    hits += fast.hit;
  }
  EXPECT_EQ(hits, 500);
}

/// The query with its triangle held where it starts.
VertexFaceQuery held_still(VertexFaceQuery q) {
  q.a_t1 = q.a_t0;
  q.b_t1 = q.b_t0;
  q.c_t1 = q.c_t0;
  return q;
}

CcdResult static_ccd(const VertexFaceQuery& q) {
  return point_static_triangle_ccd(q.p_t0, q.p_t1, q.a_t0, q.b_t0, q.c_t0);
}

/// Runs `count` queries with a still triangle through point_static_triangle_ccd, the general solver and the
/// exact reference: the same decision from all three, the general solver's toi and weights bit for bit from
/// the static path on all but `allowed_differences` hits (there, within the toi tolerance of it and
/// bracketing the exact time).
void expect_static_agreement(const std::string& family, int count, int allowed_differences,
                             const std::function<VertexFaceQuery()>& make) {
  int hits = 0;
  int differences = 0;
  const CcdSettings settings;
  for (int i = 0; i < count; ++i) {
    const VertexFaceQuery q = held_still(make());
    const CcdResult fast = static_ccd(q);
    const CcdResult general = point_triangle_ccd(q, settings);
    const ExactCcdResult exact = point_triangle_ccd_exact(q, 0.0, settings.toi_tolerance);
    expect_well_formed(fast);
    ASSERT_EQ(fast.hit, exact.hit) << family << " query " << i;
    ASSERT_EQ(fast.hit, general.hit) << family << " query " << i;
    if (!fast.hit) continue;
    ++hits;
    EXPECT_LE(fast.toi, exact.toi_upper) << family << " query " << i;
    EXPECT_GE(fast.toi + settings.toi_tolerance, exact.toi_lower) << family << " query " << i;
    if (fast.toi != general.toi || fast.barycentric != general.barycentric) {
      ++differences;
      EXPECT_NEAR(fast.toi, general.toi, settings.toi_tolerance) << family << " query " << i;
    }
  }
  EXPECT_GT(hits, 0) << family;
  EXPECT_LT(hits, count) << family;
  EXPECT_LE(differences, allowed_differences) << family;
  ::testing::Test::RecordProperty(family + "_hits", hits);
  ::testing::Test::RecordProperty(family + "_differences", differences);
}

TEST(PointStaticTriangleCcd, MatchesTheGeneralSolverOnAimedQueries) {
  QueryGenerator gen(21);
  expect_static_agreement("aimed_at_static", 3000, 0, [&] { return gen.aimed_at_static(); });
  expect_static_agreement("aimed_at_static_1e3_away", 1000, 0,
                          [&] { return transformed(gen.aimed_at_static(), 1e-2, Vec3(1e3, 1, -1e3)); });
}

TEST(PointStaticTriangleCcd, MatchesTheGeneralSolverWhereItsDeterminantsOverflowOrUnderflow) {
  // Near 1e100 the determinants overflow, near 1e-100 they fall below the bounds' absolute term: the static
  // path must hand these on rather than decide on infinities or zeros.
  QueryGenerator gen(24);
  expect_static_agreement("aimed_at_static_1e100", 200, 0,
                          [&] { return transformed(gen.aimed_at_static(), 1e100, Vec3::Zero()); });
  expect_static_agreement("aimed_at_static_1e-100", 200, 0,
                          [&] { return transformed(gen.aimed_at_static(), 1e-100, Vec3::Zero()); });
  // Just inside the range where the static path answers itself.
  expect_static_agreement("aimed_at_static_1e55", 300, 0,
                          [&] { return transformed(gen.aimed_at_static(), 1e55, Vec3::Zero()); });
  expect_static_agreement("aimed_at_static_1e-26", 300, 0,
                          [&] { return transformed(gen.aimed_at_static(), 1e-26, Vec3::Zero()); });
}

TEST(PointStaticTriangleCcd, MatchesTheGeneralSolverForParticlesNearACloth) {
  QueryGenerator gen(22);
  expect_static_agreement("near_static_face", 5000, 0, [&] { return gen.near_static_face(); });
}

TEST(PointStaticTriangleCcd, AgreesOnGridQueriesThroughEdgesVerticesAndThePlane) {
  // On the k / 4 grid, crossings pass exactly through edges and vertices, and points start, end or move in
  // the plane: the static path must hand all of those on, and decide as the exact reference does.
  QueryGenerator gen(23);
  expect_static_agreement("grid_static", 3000, 0, [&] { return gen.grid(); });
  expect_static_agreement("coplanar_static", 1000, 0, [&] { return gen.coplanar(); });
  expect_static_agreement("zero_area_static", 1000, 0, [&] { return gen.zero_area(); });
  for (int i = 0; i < 300; ++i) {
    const VertexFaceQuery q = gen.through_edge_or_vertex();
    const CcdResult fast = static_ccd(q);
    ASSERT_TRUE(fast.hit) << "query " << i;
    EXPECT_EQ(fast.toi, point_triangle_ccd(q).toi) << "query " << i;
  }
}

TEST(PointStaticTriangleCcd, DecidesTouchingAnEdgeAVertexAndThePlaneAsTheGeneralSolver) {
  // Analytic cases of static_triangle: through the middle of the hypotenuse, through a vertex, stopping on
  // the plane, starting on it, sliding in it, and passing just beside an edge (1e-15 m).
  const std::pair<Vec3, Vec3> paths[] = {
      {Vec3(0.5, 0.5, 1), Vec3(0.5, 0.5, -1)},     {Vec3(1, 0, 1), Vec3(1, 0, -3)},
      {Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0)},      {Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1)},
      {Vec3(-1, 0.5, 0), Vec3(0.5, 0.25, 0)},      {Vec3(0.5 + 1e-15, 0.5, 1), Vec3(0.5 + 1e-15, 0.5, -1)},
      {Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -2)}, {Vec3(-1e-15, 0.5, 1), Vec3(-1e-15, 0.5, -1)}};
  const bool hit[] = {true, true, true, true, true, false, true, false};
  for (std::size_t k = 0; k < std::size(paths); ++k) {
    const VertexFaceQuery q = static_triangle(paths[k].first, paths[k].second);
    const CcdResult fast = static_ccd(q);
    const CcdResult general = point_triangle_ccd(q);
    EXPECT_EQ(fast.hit, hit[k]) << "path " << k;
    EXPECT_EQ(fast.hit, general.hit) << "path " << k;
    EXPECT_EQ(fast.toi, general.toi) << "path " << k;
    EXPECT_EQ(fast.barycentric, general.barycentric) << "path " << k;
  }
}

TEST(PointStaticTriangleCcd, RejectsNonFiniteCoordinates) {
  const Vec3 nan(std::numeric_limits<double>::quiet_NaN(), 0, 0);
  EXPECT_THROW(point_static_triangle_ccd(Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3::Zero(), Vec3(1, 0, 0), nan),
               InvalidQueryError);
}

/// Runs `count` queries through transversal_crossing and transversal_crossing_exact: the same answer, both
/// answers present.
void expect_crossing_agreement(const std::string& family, int count,
                               const std::function<VertexFaceQuery()>& make, bool both_answers = true) {
  int crossings = 0;
  int exact_path = 0;
  for (int i = 0; i < count; ++i) {
    const VertexFaceQuery q = make();
    CcdPath path = CcdPath::FILTER;
    const bool crossing = transversal_crossing(q, &path);
    ASSERT_EQ(crossing, transversal_crossing_exact(q)) << family << " query " << i;
    crossings += crossing;
    exact_path += path == CcdPath::EXACT;
  }
  if (both_answers) {
    EXPECT_GT(crossings, 0) << family;
    EXPECT_LT(crossings, count) << family;
  }
  ::testing::Test::RecordProperty(family + "_crossings", crossings);
  ::testing::Test::RecordProperty(family + "_exact_path", exact_path);
}

TEST(TransversalCrossing, AgreesWithExactOnGenericQueries) {
  QueryGenerator gen(31);
  expect_crossing_agreement("aimed", 2000, [&] { return gen.aimed(); });
  expect_crossing_agreement("tiny_motion", 500, [&] { return gen.tiny_motion(); });
  expect_crossing_agreement("scaled_1e-3_translated", 500,
                            [&] { return transformed(gen.aimed(), 1e-3, Vec3(10, -10, 10)); });
}

TEST(TransversalCrossing, AgreesWithExactOnDegenerateQueries) {
  // Grid queries cross exactly through edges and vertices, touch and turn back, start or end in the plane;
  // coplanar and zero-area ones never cross (the plane's side never changes, or there is no face).
  QueryGenerator gen(32);
  expect_crossing_agreement("grid", 2000, [&] { return gen.grid(); });
  expect_crossing_agreement(
      "coplanar", 300, [&] { return gen.coplanar(); }, false);
  expect_crossing_agreement("zero_area", 500, [&] { return gen.zero_area(); });
  expect_crossing_agreement(
      "through_edge_or_vertex", 300, [&] { return gen.through_edge_or_vertex(); }, false);
  expect_crossing_agreement(
      "tangential_touch", 2, [n = 0]() mutable { return tangential_touch(n++ * 1e-3); }, false);
}

TEST(TransversalCrossing, AgreesWithExactWhereTheFilterOverflows) {
  QueryGenerator gen(33);
  expect_crossing_agreement("scaled_1e100", 100,
                            [&] { return transformed(gen.aimed(), 1e100, Vec3::Zero()); });
}

TEST(TransversalCrossing, DecidesAGenericCrossingAndMissWithoutTheExactReference) {
  // Through a triangle that tilts during the step, and past its edge: both decided by the filter.
  VertexFaceQuery q = static_triangle(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -1));
  q.c_t1.z() = 0.1;
  CcdPath path = CcdPath::EXACT;
  EXPECT_TRUE(transversal_crossing(q, &path));
  EXPECT_EQ(path, CcdPath::FILTER);
  q.p_t0 = Vec3(0.8, 0.8, 1);
  q.p_t1 = Vec3(-0.1, 0.9, -1);
  EXPECT_FALSE(transversal_crossing(q, &path));
  EXPECT_EQ(path, CcdPath::FILTER);
}

}  // namespace
}  // namespace drench::ccd
