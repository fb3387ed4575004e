#pragma once
/// Closest points on triangles, shared by the CCD (barycentric weights at the time of impact) and the
/// coupling's proximity test (Huber et al. 2013 sec. 3.1).

#include <drench/common/types.hpp>

namespace drench {

/// Barycentric weights (of a, b, c) of the point of the closed triangle abc closest to p: all >= 0, sum 1.
/// Works for zero-area triangles (then the closest point of the longest covering edge or vertex). When two
/// points are equally close, the face wins over edges, and edge ab over bc over ca.
/// Ericson, "Real-Time Collision Detection" (2005) sec. 5.1.5, restated without divisions by a possibly zero
/// area: the face projection is used only when it lies inside, else the best of the three edge segments.
Vec3 closest_point_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace drench
