// Exact predicates (ccd/exact_predicates.hpp): signs where doubles cannot tell, closed contact at edges and
// corners, and the coplanar cases the surface intersection count relies on.

#include <drench/ccd/exact_predicates.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace drench::ccd {
namespace {

TEST(ExactPredicates, Orient3dSignsAndAntisymmetry) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(orient3d_exact(a, b, c, Vec3(0.2, 0.2, 1)), 1);
  EXPECT_EQ(orient3d_exact(a, b, c, Vec3(0.2, 0.2, -1)), -1);
  EXPECT_EQ(orient3d_exact(a, b, c, Vec3(5, -7, 0)), 0);
  EXPECT_EQ(orient3d_exact(b, a, c, Vec3(0.2, 0.2, 1)), -1);
}

TEST(ExactPredicates, Orient3dDecidesWhereDoublesCannot) {
  // d lies 2^-60 off a plane through points of large coordinates: the double determinant is all rounding.
  const Vec3 a(1e3, 1e3, 0), b(1e3 + 0.1, 1e3 + 0.3, 0), c(1e3 - 0.7, 1e3 + 0.1, 0);
  const Vec3 on(1e3 + 0.25, 1e3 + 0.125, 0);
  EXPECT_EQ(orient3d_exact(a, b, c, on), 0);
  const int up = orient3d_exact(a, b, c, Vec3(on.x(), on.y(), 0x1p-60));
  const int down = orient3d_exact(a, b, c, Vec3(on.x(), on.y(), -0x1p-60));
  EXPECT_NE(up, 0);
  EXPECT_EQ(up, -down);
  EXPECT_EQ(up, orient3d_exact(a, b, c, Vec3(on.x(), on.y(), 1.0)));
}

TEST(ExactPredicates, SegmentThroughASharedEdgeMeetsBothTriangles) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(1, 1, 0);
  const Vec3 p(0.5, 0.5, 1), q(0.5, 0.5, -1);  // through the diagonal b-c
  EXPECT_TRUE(segment_meets_triangle_exact(p, q, a, b, c));
  EXPECT_TRUE(segment_meets_triangle_exact(p, q, b, d, c));
}

TEST(ExactPredicates, SegmentTouchingOrStoppingShortIsDecidedExactly) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_meets_triangle_exact(Vec3(0.1, 0.1, 1), Vec3(0.1, 0.1, 0), a, b, c));
  EXPECT_FALSE(segment_meets_triangle_exact(Vec3(0.1, 0.1, 1), Vec3(0.1, 0.1, 0x1p-1000), a, b, c));
  EXPECT_TRUE(segment_meets_triangle_exact(Vec3(0, 0, 1), Vec3(0, 0, -1), a, b, c)) << "through a corner";
  EXPECT_FALSE(
      segment_meets_triangle_exact(Vec3(0.5 + 0x1p-52, 0.5, 1), Vec3(0.5 + 0x1p-52, 0.5, -1), a, b, c))
      << "just beside the hypotenuse";
}

TEST(ExactPredicates, CoplanarSegmentsAndTriangles) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_meets_triangle_exact(Vec3(-1, 0.2, 0), Vec3(2, 0.2, 0), a, b, c)) << "across";
  EXPECT_TRUE(segment_meets_triangle_exact(Vec3(0.1, 0.1, 0), Vec3(0.2, 0.1, 0), a, b, c)) << "inside";
  EXPECT_FALSE(segment_meets_triangle_exact(Vec3(0.6, 0.6, 0), Vec3(2, 2, 0), a, b, c)) << "beside";
  // Containment: the small triangle's edges lie inside the large one.
  EXPECT_TRUE(triangles_meet_exact(a, b, c, Vec3(0.1, 0.1, 0), Vec3(0.2, 0.1, 0), Vec3(0.1, 0.2, 0)));
  EXPECT_FALSE(triangles_meet_exact(a, b, c, Vec3(0, 0, 1e-9), Vec3(1, 0, 1e-9), Vec3(0, 1, 1e-9)))
      << "parallel, 1 nm apart";
  EXPECT_TRUE(triangles_meet_exact(a, b, c, Vec3(0.2, 0.2, -1), Vec3(0.3, 0.2, 1), Vec3(0.2, 0.3, 1)))
      << "piercing";
}

}  // namespace
}  // namespace drench::ccd
