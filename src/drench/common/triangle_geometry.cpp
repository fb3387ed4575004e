#include <drench/common/triangle_geometry.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace drench {

Vec3 closest_point_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (nn > 0.0 && std::isfinite(nn)) {
    const double wa = n.dot((b - p).cross(c - p)) / nn;
    const double wb = n.dot((c - p).cross(a - p)) / nn;
    const Vec3 weights(wa, wb, 1.0 - wa - wb);
    if (weights.minCoeff() >= 0.0 && weights.allFinite()) return weights;
  }
  const std::array<const Vec3*, 3> v = {&a, &b, &c};
  Vec3 best(1.0, 0.0, 0.0);
  double best_distance = (p - a).squaredNorm();
  for (int i = 0; i < 3; ++i) {
    const Vec3& u = *v[i];
    const Vec3 e = *v[(i + 1) % 3] - u;
    const double ee = e.squaredNorm();
    double s = ee > 0.0 ? (p - u).dot(e) / ee : 0.0;
    s = std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.0;
    const double distance = (p - (u + s * e)).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = Vec3::Zero();
      best[i] = 1.0 - s;
      best[(i + 1) % 3] = s;
    }
  }
  return best;
}

bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p;
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 h = d.cross(e2);
  const double det = e1.dot(h);
  const double scale = d.norm() * e1.norm() * e2.norm();
  if (!(std::abs(det) > 1e-12 * scale)) return false;  // parallel to the plane, or a degenerate triangle
  const double inv = 1.0 / det;
  const Vec3 s = p - a;
  constexpr double tol = 1e-12;
  const double u = s.dot(h) * inv;
  if (u < -tol || u > 1.0 + tol) return false;
  const Vec3 k = s.cross(e1);
  const double v = d.dot(k) * inv;
  if (v < -tol || u + v > 1.0 + tol) return false;
  const double t = e2.dot(k) * inv;
  return t >= -tol && t <= 1.0 + tol;
}

bool triangle_overlaps_cube(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& centre, double half) {
  const Vec3 v[3] = {a - centre, b - centre, c - centre};
  // The box's own axes: the triangle's extent against the box's.
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min({v[0][k], v[1][k], v[2][k]});
    const double hi = std::max({v[0][k], v[1][k], v[2][k]});
    if (lo > half || hi < -half) return false;
  }
  const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  // Each axis: project the triangle and the box (radius = half times the axis's L1 norm) and look for a gap.
  const auto separated = [&](const Vec3& axis) {
    const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
    const double radius = half * axis.cwiseAbs().sum();
    return std::min({p0, p1, p2}) > radius || std::max({p0, p1, p2}) < -radius;
  };
  if (separated(e[0].cross(e[1]))) return false;
  for (const Vec3& edge : e) {
    for (int k = 0; k < 3; ++k) {
      if (separated(Vec3::Unit(k).cross(edge))) return false;
    }
  }
  return true;
}

std::vector<std::pair<Index, Index>> unique_edges(const std::vector<Triangle>& triangles) {
  std::vector<std::pair<Index, Index>> edges;
  edges.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    for (int k = 0; k < 3; ++k)
      edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

}  // namespace drench
