#include <drench/ccd/exact_predicates.hpp>

#include <gmpxx.h>

#include <algorithm>
#include <cmath>

namespace drench::ccd {

namespace {

constexpr double kUnitRoundoff = 0x1p-53;

int sign_of(double x) {
  return (x > 0.0) - (x < 0.0);
}

int sign_of(const mpq_class& x) {
  return sgn(x);
}

/// Sign of det[(b - a)_ij, (c - a)_ij], the orientation of a, b, c projected on the axes i and j.
int orient2d_exact(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j) {
  const double t1 = (b[i] - a[i]) * (c[j] - a[j]);
  const double t2 = (b[j] - a[j]) * (c[i] - a[i]);
  const double value = t1 - t2;
  // Two rounded differences and a product per term, one subtraction: 8 u covers them with a margin.
  const double bound = 8.0 * kUnitRoundoff * (std::abs(t1) + std::abs(t2));
  if (std::abs(value) > bound) return sign_of(value);
  const mpq_class ax(a[i]), ay(a[j]), bx(b[i]), by(b[j]), cx(c[i]), cy(c[j]);
  return sign_of(mpq_class((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)));
}

/// The closed 2D segments pq and rs (projected on the axes i, j) share a point.
bool segments_meet_2d(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int i, int j) {
  const int o1 = orient2d_exact(p, q, r, i, j), o2 = orient2d_exact(p, q, s, i, j);
  const int o3 = orient2d_exact(r, s, p, i, j), o4 = orient2d_exact(r, s, q, i, j);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  // A point on the other segment's line: it meets the segment when it lies within its extent (exact, as
  // comparisons of input coordinates).
  const auto within = [&](const Vec3& x, const Vec3& u, const Vec3& v) {
    return std::min(u[i], v[i]) <= x[i] && x[i] <= std::max(u[i], v[i]) && std::min(u[j], v[j]) <= x[j] &&
           x[j] <= std::max(u[j], v[j]);
  };
  return (o1 == 0 && within(r, p, q)) || (o2 == 0 && within(s, p, q)) || (o3 == 0 && within(p, r, s)) ||
         (o4 == 0 && within(q, r, s));
}

/// The closed point x lies in the closed 2D triangle abc of orientation `turn` (+1 or -1).
bool point_in_triangle_2d(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, int turn, int i,
                          int j) {
  return orient2d_exact(a, b, x, i, j) * turn >= 0 && orient2d_exact(b, c, x, i, j) * turn >= 0 &&
         orient2d_exact(c, a, x, i, j) * turn >= 0;
}

}  // namespace

int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double t[6] = {u.x() * v.y() * w.z(), u.y() * v.z() * w.x(), u.z() * v.x() * w.y(),
                       u.z() * v.y() * w.x(), u.x() * v.z() * w.y(), u.y() * v.x() * w.z()};
  const double value = ((t[0] + t[1]) + t[2]) - ((t[3] + t[4]) + t[5]);
  double magnitude = 0.0;
  for (double x : t)
    magnitude += std::abs(x);
  // Three rounded differences and two products per term, five additions: 16 u covers them with a margin
  // (Shewchuk 1997's bound for this form is 7 u); the constant keeps underflowed terms honest.
  if (std::abs(value) > 16.0 * kUnitRoundoff * magnitude + 0x1p-1000) return sign_of(value);
  const mpq_class ax(a.x()), ay(a.y()), az(a.z());
  const mpq_class ux = mpq_class(b.x()) - ax, uy = mpq_class(b.y()) - ay, uz = mpq_class(b.z()) - az;
  const mpq_class vx = mpq_class(c.x()) - ax, vy = mpq_class(c.y()) - ay, vz = mpq_class(c.z()) - az;
  const mpq_class wx = mpq_class(d.x()) - ax, wy = mpq_class(d.y()) - ay, wz = mpq_class(d.z()) - az;
  return sign_of(mpq_class(ux * (vy * wz - vz * wy) - uy * (vx * wz - vz * wx) + uz * (vx * wy - vy * wx)));
}

bool segment_meets_triangle_exact(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int sp = orient3d_exact(a, b, c, p), sq = orient3d_exact(a, b, c, q);
  if (sp * sq > 0) return false;
  if (sp != 0 || sq != 0) {
    // The segment meets the plane in one point; the line through it passes the triangle (closed) exactly
    // when it turns the same way around all three edges.
    const int e0 = orient3d_exact(p, q, a, b), e1 = orient3d_exact(p, q, b, c),
              e2 = orient3d_exact(p, q, c, a);
    return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
  }
  // In the triangle's plane (or the triangle is degenerate): decide in a projection on two axes that keeps
  // the triangle's area, so that the projection is one-to-one on the plane.
  for (int drop = 0; drop < 3; ++drop) {
    const int i = (drop + 1) % 3, j = (drop + 2) % 3;
    const int turn = orient2d_exact(a, b, c, i, j);
    if (turn == 0) continue;
    return point_in_triangle_2d(p, a, b, c, turn, i, j) || point_in_triangle_2d(q, a, b, c, turn, i, j) ||
           segments_meet_2d(p, q, a, b, i, j) || segments_meet_2d(p, q, b, c, i, j) ||
           segments_meet_2d(p, q, c, a, i, j);
  }
  return false;  // a degenerate triangle: it is met through its edges (triangles_meet_exact)
}

bool triangles_meet_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                          const Vec3& f) {
  return segment_meets_triangle_exact(a, b, d, e, f) || segment_meets_triangle_exact(b, c, d, e, f) ||
         segment_meets_triangle_exact(c, a, d, e, f) || segment_meets_triangle_exact(d, e, a, b, c) ||
         segment_meets_triangle_exact(e, f, a, b, c) || segment_meets_triangle_exact(f, d, a, b, c);
}

}  // namespace drench::ccd
