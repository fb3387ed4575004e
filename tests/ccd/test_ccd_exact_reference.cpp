// The exact rational reference: cases whose answer is known in closed form, including the time of impact.

#include <gtest/gtest.h>

#include <limits>
#include <utility>

#include <drench/ccd/ccd_exact_reference.hpp>
#include "ccd_query_builders.hpp"

namespace drench::ccd {
namespace {

using test::static_triangle;

TEST(CcdExactReference, BracketsTheTimeOfARationalCrossing) {
  // z: 1 -> -2 crosses z = 0 at t = 1/3, which no double equals: the bracket must contain it.
  const ExactCcdResult r =
      point_triangle_ccd_exact(static_triangle(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -2)), 0.0, 1e-9);
  ASSERT_TRUE(r.hit);
  EXPECT_LT(r.toi_lower, 1.0 / 3.0 + 1e-16);
  EXPECT_GT(r.toi_upper, 1.0 / 3.0 - 1e-16);
  EXPECT_LE(r.toi_upper - r.toi_lower, 1e-9 * (1 + 1e-9));
}

TEST(CcdExactReference, ReturnsAnExactRootAsAPoint) {
  const ExactCcdResult r =
      point_triangle_ccd_exact(static_triangle(Vec3(0.25, 0.25, 1), Vec3(0.25, 0.25, -3)));
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.toi_lower, 0.25);
  EXPECT_EQ(r.toi_upper, 0.25);
}

TEST(CcdExactReference, SeparatesAMissByOneUlp) {
  // Passing x = -2^-1074 beside the edge x = 0: a miss by the smallest double there is.
  const double tiny = std::numeric_limits<double>::denorm_min();
  EXPECT_FALSE(point_triangle_ccd_exact(static_triangle(Vec3(-tiny, 0.5, 1), Vec3(-tiny, 0.5, -1))).hit);
  EXPECT_TRUE(point_triangle_ccd_exact(static_triangle(Vec3(0, 0.5, 1), Vec3(0, 0.5, -1))).hit);
}

TEST(CcdExactReference, FindsTheEarliestOfSeveralContacts) {
  // In the plane for the whole step, crossing the triangle: enters through the edge x = 0 at t = 1/4.
  const ExactCcdResult r = point_triangle_ccd_exact(static_triangle(Vec3(-0.5, 0.25, 0), Vec3(1.5, 0.25, 0)));
  ASSERT_TRUE(r.hit);
  EXPECT_LE(r.toi_lower, 0.25);
  EXPECT_GE(r.toi_upper, 0.25);
  EXPECT_LE(r.toi_upper - r.toi_lower, 1e-6);
}

TEST(CcdExactReference, StartsTheSearchAtTFrom) {
  // The point rises at 2 per step, the triangle at 1.5, both from z = 0: they touch at t = 0 only.
  VertexFaceQuery q = static_triangle(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 2));
  for (auto [x0, x1] :
       {std::pair{&q.a_t0, &q.a_t1}, std::pair{&q.b_t0, &q.b_t1}, std::pair{&q.c_t0, &q.c_t1}}) {
    *x1 = *x0 + Vec3(0, 0, 1.5);
  }
  EXPECT_EQ(point_triangle_ccd_exact(q).toi_lower, 0.0);
  EXPECT_FALSE(point_triangle_ccd_exact(q, 0.5).hit);
}

TEST(CcdExactReference, DecidesTheCoplanaritySignAtTheEnds) {
  const VertexFaceQuery q = static_triangle(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, -1e-300));
  EXPECT_EQ(coplanarity_sign_exact(q, false), 0);
  EXPECT_EQ(coplanarity_sign_exact(q, true), -1);
}

}  // namespace
}  // namespace drench::ccd
