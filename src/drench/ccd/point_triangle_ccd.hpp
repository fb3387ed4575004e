#pragma once
/// Continuous collision detection of a moving point against a moving triangle over one step (Huber et al.
/// 2013 sec. 3.3, eq. 5-6; Provot 1997). Decisions are exact for the double inputs as given: a certified
/// floating-point filter decides almost every query, and the exact rational reference
/// (ccd_exact_reference.hpp) decides the rest. See point_triangle_ccd.cpp for the method and its sources.

#include <cstdint>

#include <drench/common/error.hpp>
#include <drench/common/types.hpp>

namespace drench::ccd {

/// A point and a triangle moving linearly over one step: x(t) = (1 - t) x_t0 + t x_t1 for t in [0, 1] (eq. 5,
/// with t the fraction of the step). Any length unit works; drench passes metres.
struct VertexFaceQuery {
  Vec3 p_t0, a_t0, b_t0, c_t0;  ///< point and triangle vertices at the start of the step
  Vec3 p_t1, a_t1, b_t1, c_t1;  ///< the same at the end of the step
};

/// A query holds a NaN or an infinite coordinate. The message names the vertex and the coordinate.
class InvalidQueryError : public Error {
 public:
  using Error::Error;
};

/// Tunables of the solver. The defaults are what the coupler uses.
struct CcdSettings {
  /// Width of the bracket that the reported time of impact lies in (unit: fraction of the step), > 0. The
  /// contact decision itself has no tolerance: it is exact with separation 0 (touching counts).
  double toi_tolerance = 1e-6;
  /// Intervals of [0, 1] the floating-point filter may examine before it hands the query to the exact
  /// reference (from the first undecided time on). Larger values trade exact calls for filter work.
  int max_filter_intervals = 64;
};

/// How a query was decided; for statistics and tests.
enum class CcdPath : std::uint8_t {
  FILTER = 0,  ///< the certified floating-point filter decided alone
  EXACT = 1,   ///< the exact rational reference decided (degenerate or near-degenerate query)
};

/// Result of one query.
struct CcdResult {
  bool hit = false;  ///< the point lies in the closed triangle at some t in [0, 1]
  /// Earliest time of contact, as a lower bound: the true first contact lies in [toi, toi + toi_tolerance]
  /// (unit: fraction of the step). 1 when there is no hit.
  double toi = 1.0;
  /// Barycentric weights (a, b, c) of the point on the triangle at toi: the closest point of the closed
  /// triangle, so weights are >= 0 and sum to 1. Zero when there is no hit.
  Vec3 barycentric = Vec3::Zero();
  CcdPath path = CcdPath::FILTER;
};

/// Earliest contact of a moving point with a moving triangle during one step (eq. 5-6): the roots of the
/// coplanarity cubic on [0, 1] at which the point lies in the closed triangle.
/// Handles every degenerate case exactly: vanishing leading coefficients, a cubic identically zero (motion in
/// the triangle's plane), double roots and grazing, roots at t = 0 and t = 1, contact on an edge or a vertex,
/// zero-area triangles.
/// @param query  point and triangle at both ends of the step; every coordinate finite
/// @throws InvalidQueryError when a coordinate is NaN or infinite
/// @return the decision, never NaN: toi in [0, 1], barycentric weights in [0, 1]
CcdResult point_triangle_ccd(const VertexFaceQuery& query, const CcdSettings& settings = {});

/// point_triangle_ccd for a triangle that does not move during the step (a_t1 = a_t0, ...): the same result,
/// bit for bit except where the general filter would bracket the time of impact by another route (a root
/// within rounding of a bracket boundary, or a near-degenerate query; then both are still correct to within
/// toi_tolerance). The plane is fixed, so eq. 6 is linear in t: the sides of the two ends, then three
/// orientations of the segment against the edges (Shewchuk 1997's orient3d with a certified error bound)
/// decide a crossing, and the crossing time is the root of a line. Queries within rounding of an edge, a
/// vertex or the plane go to the general filter. Used by the fluid's sub-step against the cloth at rest
/// (coupling/cloth_obstacle.hpp), where most hits are particles crossing a face's interior.
/// @param p_t0, p_t1  point at the start and the end of the step (unit: m); finite
/// @param a, b, c  triangle vertices during the whole step (unit: m); finite
/// @throws InvalidQueryError when a coordinate is NaN or infinite
CcdResult point_static_triangle_ccd(const Vec3& p_t0, const Vec3& p_t1, const Vec3& a, const Vec3& b,
                                    const Vec3& c, const CcdSettings& settings = {});

/// Whether the point crosses the triangle transversally during the step, decided exactly: the same answer as
/// transversal_crossing_exact (ccd_exact_reference.hpp, which defines the question), from the certified
/// filter of point_triangle_ccd where it can decide (a sign change of eq. 6 where every inside test is
/// certainly positive: a crossing; no such time: none) and from the exact reference otherwise. The leak
/// audit asks this of every pair it cannot clear cheaply (coupling/leak_audit.hpp).
/// @param query  point and triangle at both ends of the step; every coordinate finite
/// @param path  when not null, receives how the answer was reached (EXACT: the rational reference ran)
/// @throws InvalidQueryError when a coordinate is NaN or infinite
bool transversal_crossing(const VertexFaceQuery& query, CcdPath* path = nullptr);

/// Throws InvalidQueryError naming the first NaN or infinite coordinate of the query.
void check_query_finite(const VertexFaceQuery& query);

}  // namespace drench::ccd
