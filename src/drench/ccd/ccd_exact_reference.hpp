#pragma once
/// Exact reference for point-triangle CCD: rational arithmetic (GMP) and Sturm root isolation. Slow (tens of
/// microseconds per query) but exact for double inputs; used by the tests, the fuzzer, the fast solver's
/// fallback, and the coupling's leak audit.

#include <drench/ccd/point_triangle_ccd.hpp>

namespace drench::ccd {

/// Exact answer to a query on [t_from, 1].
struct ExactCcdResult {
  bool hit = false;  ///< the point lies in the closed triangle at some t in [t_from, 1]
  /// The earliest such t lies in [toi_lower, toi_upper] (doubles rounded outward); both 1 when no hit.
  double toi_lower = 1.0;
  double toi_upper = 1.0;
};

/// Decides exactly whether the point lies in the closed triangle at some t in [t_from, 1] (linear motion,
/// eq. 5), and brackets the earliest such t to within `toi_tolerance`.
/// @param query  finite coordinates (else InvalidQueryError)
/// @param t_from  start of the examined time range, in [0, 1] (any double is exact, so no rounding)
/// @param toi_tolerance  width of the returned bracket, > 0
ExactCcdResult point_triangle_ccd_exact(const VertexFaceQuery& query, double t_from = 0.0,
                                        double toi_tolerance = 1e-6);

}  // namespace drench::ccd

namespace drench::ccd {

/// Exact sign of the coplanarity determinant of eq. 6, (p - a) . ((b - a) x (c - a)), at the start (t = 0) or
/// the end (t = 1) of the step: +1, 0 or -1. The filter of point_triangle_ccd asks for it when rounding hides
/// whether the point starts or ends in the triangle's plane.
int coplanarity_sign_exact(const VertexFaceQuery& query, bool at_end);

}  // namespace drench::ccd

namespace drench::ccd {

/// Exact test for a transversal crossing (the leak of the coupling issue): at some t in the open (0, 1) the
/// point lies in the closed triangle and the sign of eq. 6 (its side of the triangle) changes there. Touching
/// and returning, starting or ending in the triangle, and motion inside its plane are not crossings.
/// @throws InvalidQueryError for non-finite coordinates
bool transversal_crossing_exact(const VertexFaceQuery& query);

}  // namespace drench::ccd
