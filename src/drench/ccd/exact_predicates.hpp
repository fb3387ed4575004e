#pragma once
/// Exact geometric predicates on double coordinates: a floating-point filter answers when the rounding error
/// bound leaves the sign certain, and rational arithmetic (GMP) decides the rest. They judge the claim of
/// Huber et al. 2013 sec. 4 (no surface triangle crosses the cloth) without trusting any tolerance.

#include <drench/common/types.hpp>

namespace drench::ccd {

/// Sign of det[b - a, c - a, d - a]: +1 when d lies on the side of the plane abc that (b - a) x (c - a)
/// points to, -1 on the other, 0 exactly on the plane (unit-free; any finite doubles).
int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// True when the closed segment pq and the closed triangle abc share a point, decided exactly; a segment in
/// the triangle's plane counts when it meets the triangle there. A degenerate triangle (collinear corners)
/// is treated as its segments. Coordinates finite.
bool segment_meets_triangle_exact(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

/// True when the closed triangles abc and def share a point, decided exactly: an edge of one meets the
/// other (which covers the coplanar case, containment included).
bool triangles_meet_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                          const Vec3& f);

}  // namespace drench::ccd
