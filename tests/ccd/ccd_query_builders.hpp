#pragma once
/// Query builders for the CCD tests: hand-made cases with a known answer, and random families (generic,
/// degenerate, scaled, translated) for comparing the fast solver with the exact reference.

#include <array>
#include <random>

#include <drench/ccd/point_triangle_ccd.hpp>

namespace drench::ccd::test {

/// A static triangle in the plane z = 0 with vertices (0,0), (1,0), (0,1), and a point moving from p_t0 to
/// p_t1.
inline VertexFaceQuery static_triangle(const Vec3& p_t0, const Vec3& p_t1) {
  VertexFaceQuery q;
  q.a_t0 = q.a_t1 = Vec3(0, 0, 0);
  q.b_t0 = q.b_t1 = Vec3(1, 0, 0);
  q.c_t0 = q.c_t1 = Vec3(0, 1, 0);
  q.p_t0 = p_t0;
  q.p_t1 = p_t1;
  return q;
}

/// Applies x -> scale * x + offset to every vertex.
inline VertexFaceQuery transformed(VertexFaceQuery q, double scale, const Vec3& offset) {
  for (Vec3* v : {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1}) {
    *v = scale * *v + offset;
  }
  return q;
}

/// Deterministic random query families.
class QueryGenerator {
 public:
  explicit QueryGenerator(std::uint64_t seed) : m_rng(seed) {}

  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(m_rng); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(m_rng); }
  Vec3 vec(double lo, double hi) { return Vec3(uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)); }
  /// Coordinates on the grid k / 4, so that coplanarity, edges and vertices are hit exactly.
  Vec3 grid_vec(int range) {
    return Vec3(integer(-range, range), integer(-range, range), integer(-range, range)) / 4.0;
  }

  /// A unit-size triangle and a point aimed at a random point of it (inside, or slightly outside when the
  /// barycentric weights drawn are negative) at a random time; about half of these collide.
  VertexFaceQuery aimed() {
    VertexFaceQuery q;
    q.a_t0 = vec(-1, 1);
    q.b_t0 = vec(-1, 1);
    q.c_t0 = vec(-1, 1);
    const double motion = uniform(0.0, 1.0);
    q.a_t1 = q.a_t0 + motion * vec(-1, 1);
    q.b_t1 = q.b_t0 + motion * vec(-1, 1);
    q.c_t1 = q.c_t0 + motion * vec(-1, 1);
    const double t = uniform(0.0, 1.0);
    const double u = uniform(-0.2, 1.0);
    const double v = uniform(-0.2, 1.0 - u);
    const auto at = [t](const Vec3& x0, const Vec3& x1) { return (1 - t) * x0 + t * x1; };
    const Vec3 target = (1 - u - v) * at(q.a_t0, q.a_t1) + u * at(q.b_t0, q.b_t1) + v * at(q.c_t0, q.c_t1);
    q.p_t0 = target + vec(-1, 1);
    q.p_t1 = t > 0.01 ? Vec3(q.p_t0 + (target - q.p_t0) / t) : Vec3(target + vec(-1, 1));
    return q;
  }

  /// aimed() with a triangle that does not move: the point passes the target point (inside the triangle or
  /// slightly outside) at a random time.
  VertexFaceQuery aimed_at_static() {
    VertexFaceQuery q;
    q.a_t0 = q.a_t1 = vec(-1, 1);
    q.b_t0 = q.b_t1 = vec(-1, 1);
    q.c_t0 = q.c_t1 = vec(-1, 1);
    const double t = uniform(0.0, 1.0);
    const double u = uniform(-0.2, 1.0);
    const double v = uniform(-0.2, 1.0 - u);
    const Vec3 target = (1 - u - v) * q.a_t0 + u * q.b_t0 + v * q.c_t0;
    q.p_t0 = target + vec(-1, 1);
    q.p_t1 = t > 0.01 ? Vec3(q.p_t0 + (target - q.p_t0) / t) : Vec3(target + vec(-1, 1));
    return q;
  }

  /// A particle near a still cloth face, as the fluid's sub-steps test them: a face of about 5 cm, the point
  /// within 2 mm of its plane at the start, over or beside the face, moving up to 2 mm in any direction.
  VertexFaceQuery near_static_face() {
    VertexFaceQuery q;
    const Vec3 origin = vec(-1, 1);
    q.a_t0 = q.a_t1 = origin + 0.05 * vec(-1, 1);
    q.b_t0 = q.b_t1 = origin + 0.05 * vec(-1, 1);
    q.c_t0 = q.c_t1 = origin + 0.05 * vec(-1, 1);
    const Vec3 n = (q.b_t0 - q.a_t0).cross(q.c_t0 - q.a_t0).normalized();
    const double u = uniform(-0.3, 1.0);
    const double v = uniform(-0.3, 1.0 - u);
    q.p_t0 = (1 - u - v) * q.a_t0 + u * q.b_t0 + v * q.c_t0 + uniform(-0.002, 0.002) * n;
    q.p_t1 = q.p_t0 + 0.002 * vec(-1, 1);
    return q;
  }

  /// Everything on the k / 4 grid: exact contacts on vertices and edges, coplanar starts and ends.
  VertexFaceQuery grid() {
    VertexFaceQuery q;
    for (Vec3* v : {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1})
      *v = grid_vec(4);
    return q;
  }

  /// Point and triangle in the plane z = 0 for the whole step (eq. 6 identically zero), on the grid.
  VertexFaceQuery coplanar() {
    VertexFaceQuery q = grid();
    for (Vec3* v : {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1})
      (*v)[2] = 0.0;
    return q;
  }

  /// A triangle with collinear or coincident vertices (zero area) at both ends of the step.
  VertexFaceQuery zero_area() {
    VertexFaceQuery q = grid();
    const double s0 = integer(-4, 4) / 4.0;
    const double s1 = integer(-4, 4) / 4.0;
    q.c_t0 = q.a_t0 + s0 * (q.b_t0 - q.a_t0);
    q.c_t1 = q.a_t1 + s1 * (q.b_t1 - q.a_t1);
    return q;
  }

  /// A point crossing a static triangle exactly through a grid point of an edge or a vertex.
  VertexFaceQuery through_edge_or_vertex() {
    VertexFaceQuery q = static_triangle(Vec3::Zero(), Vec3::Zero());
    const std::array<Vec3, 6> targets = {Vec3(0, 0, 0),     Vec3(1, 0, 0),    Vec3(0, 1, 0),
                                         Vec3(0.5, 0.5, 0), Vec3(0.25, 0, 0), Vec3(0, 0.75, 0)};
    const Vec3 target = targets[static_cast<std::size_t>(integer(0, 5))];
    const Vec3 direction = Vec3(integer(-4, 4), integer(-4, 4), integer(1, 4)) / 4.0;
    q.p_t0 = target + direction;
    q.p_t1 = target - direction;
    return q;
  }

  /// The point's motion and the triangle's are tiny (down to 1e-12), near a unit triangle.
  VertexFaceQuery tiny_motion() {
    VertexFaceQuery q = aimed();
    const double scale = std::pow(10.0, -integer(6, 12));
    for (auto [x0, x1] : {std::pair{&q.p_t0, &q.p_t1}, std::pair{&q.a_t0, &q.a_t1},
                          std::pair{&q.b_t0, &q.b_t1}, std::pair{&q.c_t0, &q.c_t1}}) {
      *x1 = *x0 + scale * (*x1 - *x0);
    }
    // Put the point within reach: start it close to the triangle's plane.
    const Vec3 n = (q.b_t0 - q.a_t0).cross(q.c_t0 - q.a_t0).normalized();
    const Vec3 inside = (q.a_t0 + q.b_t0 + q.c_t0) / 3.0;
    q.p_t0 = inside + scale * uniform(-1, 1) * n;
    q.p_t1 = inside - scale * uniform(-1, 1) * n;
    return q;
  }

  /// A point sliding inside the triangle's plane (in 3D, not axis-aligned), entering or leaving it.
  VertexFaceQuery sliding_in_plane() {
    VertexFaceQuery q = coplanar();
    // Rotate the whole configuration by an exact-ish rotation (a Pythagorean 3-4-5 one keeps the grid exact).
    Eigen::Matrix3d rotation;
    rotation << 0.6, -0.8, 0, 0.8, 0.6, 0, 0, 0, 1;
    Eigen::Matrix3d tilt;
    tilt << 1, 0, 0, 0, 0.6, -0.8, 0, 0.8, 0.6;
    const Eigen::Matrix3d m = tilt * rotation;
    for (Vec3* v : {&q.p_t0, &q.a_t0, &q.b_t0, &q.c_t0, &q.p_t1, &q.a_t1, &q.b_t1, &q.c_t1})
      *v = m * *v;
    return q;
  }

 private:
  std::mt19937_64 m_rng;
};

}  // namespace drench::ccd::test
