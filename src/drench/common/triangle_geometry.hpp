#pragma once
/// Closest points on triangles, shared by the CCD (barycentric weights at the time of impact) and the
/// coupling's proximity test (Huber et al. 2013 sec. 3.1); segment-triangle crossings for the surface's
/// visibility criterion (sec. 4, Fig. 2a) and its intersection count.

#include <utility>
#include <vector>

#include <drench/common/types.hpp>

namespace drench {

/// Barycentric weights (of a, b, c) of the point of the closed triangle abc closest to p: all >= 0, sum 1.
/// Works for zero-area triangles (then the closest point of the longest covering edge or vertex). When two
/// points are equally close, the face wins over edges, and edge ab over bc over ca.
/// Ericson, "Real-Time Collision Detection" (2005) sec. 5.1.5, restated without divisions by a possibly zero
/// area: the face projection is used only when it lies inside, else the best of the three edge segments.
Vec3 closest_point_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// True when the closed segment pq meets the closed triangle abc (unit: m), decided in double precision
/// with a tolerance of 1e-12 relative to the sizes involved counted as meeting, so that a segment through an
/// edge shared by two triangles is never missed by both. A segment in the triangle's plane counts as not
/// crossing it (it passes along, not through), as does a degenerate triangle. Möller & Trumbore 1997.
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

/// True when the closed triangle abc meets the axis-aligned cube of centre `centre` and half-width `half`
/// (unit: m, > 0): the separating-axis test of Akenine-Möller 2001 (the box's 3 axes, the triangle's normal
/// and the 9 edge cross products), in double precision.
bool triangle_overlaps_cube(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& centre, double half);

/// Each edge of `triangles` once, as (lower, higher node index), ascending: a cloth's links for its strain
/// limit and its wetting's diffusion.
std::vector<std::pair<Index, Index>> unique_edges(const std::vector<Triangle>& triangles);

}  // namespace drench
