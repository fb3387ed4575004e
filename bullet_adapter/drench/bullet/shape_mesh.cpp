#include <drench/bullet/shape_mesh.hpp>

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btConeShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btConvexPointCloudShape.h>
#include <BulletCollision/CollisionShapes/btConvexTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btMultiSphereShape.h>
#include <BulletCollision/CollisionShapes/btScaledBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/CollisionShapes/btTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btUniformScalingShape.h>
#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <drench/common/error.hpp>

namespace drench::bullet {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = kPi / 2.0;

const char* const kSupported =
    "btStaticPlaneShape, btBoxShape, btSphereShape, btCapsuleShape, btCylinderShape, btConeShape, "
    "btConvexHullShape, btConvexPointCloudShape, btConvexTriangleMeshShape, btMultiSphereShape, "
    "btUniformScalingShape, btCompoundShape, btBvhTriangleMeshShape, btMultimaterialTriangleMeshShape, "
    "btScaledBvhTriangleMeshShape, btHeightfieldTerrainShape, btEmptyShape";

/// `path` is where a compound holds the shape ("btCompoundShape child 2: "), empty at the top.
[[noreturn]] void fail(const std::string& path, const btCollisionShape& shape, const std::string& problem) {
  throw SceneError(path + shape.getName() + ": " + problem);
}

bool positive_finite(double x) {
  return x > 0.0 && std::isfinite(x);
}

void check_dimension(double value, const char* what, const std::string& path, const btCollisionShape& shape) {
  if (!positive_finite(value)) {
    fail(path, shape, std::string(what) + " must be > 0 and finite, got " + format_number(value));
  }
}

void check_margin(double margin, const std::string& path, const btCollisionShape& shape) {
  if (!(margin >= 0.0) || !std::isfinite(margin)) {
    fail(path, shape, "collision margin must be >= 0 and finite, got " + format_number(margin));
  }
}

void check_triangle_count(double triangles, const std::string& path, const btCollisionShape& shape,
                          const std::string& fineness) {
  if (triangles > static_cast<double>(kMaxShapeMeshTriangles)) {
    fail(path, shape,
         "its mesh would have " + format_number(std::ceil(triangles)) + " triangles at " + fineness +
             ", more than kMaxShapeMeshTriangles = " + std::to_string(kMaxShapeMeshTriangles) +
             "; choose a coarser ShapeMeshOptions");
  }
}

std::string max_edge_text(double max_edge) {
  return "ShapeMeshOptions::max_edge " + format_number(max_edge);
}

/// Appends `part` to `mesh`, its vertices through `transform` (rotation and translation, in double).
void append(TriangleMesh& mesh, const TriangleMesh& part, const btTransform& transform) {
  const Eigen::Matrix3d rotation = to_matrix3(transform.getBasis());
  const Vec3 origin = to_vec3(transform.getOrigin());
  const auto first = static_cast<Index>(mesh.positions.size());
  for (const Vec3& p : part.positions)
    mesh.positions.push_back(rotation * p + origin);
  for (const Triangle& t : part.triangles)
    mesh.triangles.push_back({first + t[0], first + t[1], first + t[2]});
}

// ---- box: its 8 corners, exact -----------------------------------------------------------------------

/// btBoxShape::localGetSupportingVertex is the sharp box of getHalfExtentsWithMargin() (local scaling
/// included, the margin inside): its 8 corners and 12 triangles are that surface exactly.
TriangleMesh box_mesh(const btBoxShape& box, const std::string& path) {
  const Vec3 half = to_vec3(box.getHalfExtentsWithMargin()).cwiseAbs();
  for (int k = 0; k < 3; ++k)
    check_dimension(half[k], "half extent with margin", path, box);
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                (i & 4) ? half.z() : -half.z());
  }
  // Face of outward normal sign * e_a: with b, c the next axes (e_b x e_c = e_a), the corners (-,-), (+,-),
  // (+,+), (-,+) in (b, c) run counter-clockwise seen from +e_a.
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int sign : {-1, 1}) {
      auto corner = [&](int sb, int sc) {
        return static_cast<Index>(((sign > 0) << a) | ((sb > 0) << b) | ((sc > 0) << c));
      };
      Index q[4] = {corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)};
      if (sign < 0) std::swap(q[1], q[3]);
      mesh.triangles.push_back({q[0], q[1], q[2]});
      mesh.triangles.push_back({q[0], q[2], q[3]});
    }
  }
  return mesh;
}

// ---- surfaces of revolution: sphere, capsule, cylinder, cone ------------------------------------------
//
// Why a revolved profile for these four, and not Bullet's support mapping sampled and hulled (as for
// hulls and multi-spheres below): both put every vertex on Bullet's surface and enclose the same volume to
// within 0.3 points (sphere of 0.1 m at max_edge 0.02 / 0.01 / 0.005: -0.79 / -0.20 / -0.05 % revolved,
// -0.51 / -0.14 / -0.04 % sampled), but the sampled hull lays a cylinder's or a cone's side as facets from
// rim to rim (longest edge 0.38 m on a cylinder of half height 0.2 m, where the profile's longest is the
// cap's radius, 0.09 m), which max_edge is meant to prevent, and costs 10-420 ms per shape against
// 0.03-2.4 ms (btConvexHullComputer over thousands of points; measured on this 2-core machine, double).

/// (cos, sin) of `angle`, exact at 0 and +-pi/2 so that profile points meet the axis and the equator exactly.
Eigen::Vector2d direction(double angle) {
  if (angle == kHalfPi) return {0.0, 1.0};
  if (angle == -kHalfPi) return {0.0, -1.0};
  if (angle == 0.0) return {1.0, 0.0};
  return {std::cos(angle), std::sin(angle)};
}

/// The half cross-section of a solid of revolution, as (rho, y) points from its top pole (rho = 0) down to
/// its bottom pole: curved pieces in steps of at most `step`, flat caps as one piece.
class Profile {
 public:
  /// `path`, `shape` and `max_edge` name the shape when its profile alone would outgrow
  /// kMaxShapeMeshTriangles (each profile piece is a ring of at least 3 quads).
  Profile(double step, Eigen::Vector2d top_pole, const std::string& path, const btCollisionShape& shape,
          double max_edge)
      : m_step(step), m_points{top_pole}, m_path(path), m_shape(shape), m_max_edge(max_edge) {}

  /// A straight piece to `end`: in steps of at most the step on a curved surface (a cylinder's or cone's
  /// side, revolved), else one piece (a flat cap, whose fan keeps its length).
  void line_to(const Eigen::Vector2d& end, bool curved) {
    const Eigen::Vector2d start = m_points.back();
    const double length = (end - start).norm();
    if (!(length > 0.0)) return;
    const int n = curved ? pieces(std::ceil(length / m_step)) : 1;
    for (int k = 1; k < n; ++k)
      m_points.push_back(start + (end - start) * (static_cast<double>(k) / n));
    m_points.push_back(end);
  }

  /// A circular arc about `center` of `radius` from angle `from` to `to` (radians in the (rho, y) plane),
  /// starting at the last point; nothing for a zero radius (a margin of 0). At least one piece per eighth
  /// of a turn: a sphere smaller than the step was one piece from pole to pole, no ring, and its pole fans
  /// named vertices that did not exist.
  void arc(const Eigen::Vector2d& center, double radius, double from, double to) {
    const double length = radius * std::abs(to - from);
    if (!(length > 0.0)) return;
    const int n = pieces(std::max(std::ceil(length / m_step), std::ceil(std::abs(to - from) / (0.25 * kPi))));
    for (int k = 1; k < n; ++k)
      m_points.push_back(center + radius * direction(from + (to - from) * (static_cast<double>(k) / n)));
    m_points.push_back(center + radius * direction(to));
  }

  const std::vector<Eigen::Vector2d>& points() const { return m_points; }

 private:
  /// `wanted` pieces as an int, once the profile's pieces so far fit kMaxShapeMeshTriangles: a sphere of
  /// 1e7 m overflowed the int before its mesh was counted.
  int pieces(double wanted) {
    m_total += wanted;
    check_triangle_count(6.0 * m_total, m_path, m_shape, max_edge_text(m_max_edge));
    return std::max(1, static_cast<int>(wanted));
  }

  double m_step;
  std::vector<Eigen::Vector2d> m_points;
  const std::string& m_path;
  const btCollisionShape& m_shape;
  double m_max_edge;
  double m_total = 0.0;  ///< pieces so far
};

/// The profile revolved about local axis `up_axis` (a cyclic frame: e_b x e_c = e_up with b, c the next
/// axes), N segments per ring with a chord of at most `step` on the widest ring. Rings are quads split
/// into two triangles, poles are fans. With `step` = max_edge / sqrt(2) every edge on the curved part is at
/// most max_edge: ring chords and profile steps are at most `step`, a quad's diagonal at most sqrt(2) step.
TriangleMesh revolve(const Profile& profile, int up_axis, double step, const std::string& path,
                     const btCollisionShape& shape, double max_edge) {
  const std::vector<Eigen::Vector2d>& p = profile.points();
  const int rings = static_cast<int>(p.size()) - 2;
  // Every profile has a curved piece between its poles (Profile::arc's least pieces, a side's line).
  if (rings < 1) fail(path, shape, "its profile has no ring between the poles (drench bug)");
  double widest = 0.0;
  for (const Eigen::Vector2d& q : p)
    widest = std::max(widest, q.x());
  // At least an eighth of a turn a segment, as Profile::arc's pieces: a shape far smaller than the step
  // (a pebble) is still round enough to hold water off.
  const double segments_wanted = std::max(8.0, std::ceil(2.0 * kPi * widest / step));
  check_triangle_count(2.0 * segments_wanted * std::max(rings, 1), path, shape, max_edge_text(max_edge));
  const int n = static_cast<int>(segments_wanted);

  Vec3 up = Vec3::Zero(), b = Vec3::Zero(), c = Vec3::Zero();
  up[up_axis] = 1.0;
  b[(up_axis + 1) % 3] = 1.0;
  c[(up_axis + 2) % 3] = 1.0;
  std::vector<Eigen::Vector2d> around(n);
  for (int j = 0; j < n; ++j)
    around[j] = j == 0 ? Eigen::Vector2d(1.0, 0.0) : direction(2.0 * kPi * j / n);

  TriangleMesh mesh;
  mesh.positions.reserve(2 + static_cast<std::size_t>(rings) * n);
  mesh.positions.push_back(p.front().y() * up);
  for (int k = 1; k <= rings; ++k) {
    for (int j = 0; j < n; ++j)
      mesh.positions.push_back(p[k].y() * up + p[k].x() * (around[j].x() * b + around[j].y() * c));
  }
  mesh.positions.push_back(p.back().y() * up);

  const Index top = 0;
  const auto bottom = static_cast<Index>(mesh.positions.size() - 1);
  auto ring = [n](int k, int j) { return static_cast<Index>(1 + (k - 1) * n + j % n); };
  mesh.triangles.reserve(2 * static_cast<std::size_t>(n) * rings);
  // With e_r x e_theta = e_up, a ring quad A = (k, j), B = (k, j + 1), C = (k + 1, j + 1), D = (k + 1, j)
  // (k + 1 lower) is counter-clockwise seen from outside as A, D, C, B.
  for (int j = 0; j < n; ++j)
    mesh.triangles.push_back({top, ring(1, j), ring(1, j + 1)});
  for (int k = 1; k < rings; ++k) {
    for (int j = 0; j < n; ++j) {
      const Index a = ring(k, j), bb = ring(k, j + 1), cc = ring(k + 1, j + 1), d = ring(k + 1, j);
      mesh.triangles.push_back({a, cc, bb});
      mesh.triangles.push_back({a, d, cc});
    }
  }
  for (int j = 0; j < n; ++j)
    mesh.triangles.push_back({bottom, ring(rings, j + 1), ring(rings, j)});
  return mesh;
}

/// btSphereShape: the margin is the radius, getRadius() (local scaling's x), about the origin.
TriangleMesh sphere_mesh(const btSphereShape& sphere, double max_edge, const std::string& path) {
  const double r = sphere.getRadius();
  check_dimension(r, "radius", path, sphere);
  const double step = max_edge / std::sqrt(2.0);
  Profile profile(step, {0.0, r}, path, sphere, max_edge);
  profile.arc({0.0, 0.0}, r, kHalfPi, -kHalfPi);
  return revolve(profile, 1, step, path, sphere, max_edge);
}

/// btCapsuleShape: the segment of half length getHalfHeight() along getUpAxis() grown by getRadius() (the
/// margin is the radius), both with local scaling.
TriangleMesh capsule_mesh(const btCapsuleShape& capsule, double max_edge, const std::string& path) {
  const double r = capsule.getRadius(), h = capsule.getHalfHeight();
  check_dimension(r, "radius", path, capsule);
  if (!(h >= 0.0) || !std::isfinite(h)) {
    fail(path, capsule, "half height must be >= 0 and finite, got " + format_number(h));
  }
  const double step = max_edge / std::sqrt(2.0);
  Profile profile(step, {0.0, h + r}, path, capsule, max_edge);
  profile.arc({0.0, h}, r, kHalfPi, 0.0);
  profile.line_to({r, -h}, true);
  profile.arc({0.0, -h}, r, 0.0, -kHalfPi);
  return revolve(profile, capsule.getUpAxis(), step, path, capsule, max_edge);
}

/// btCylinderShape: Bullet's support is the core cylinder getHalfExtentsWithoutMargin() (the given extents
/// shrunk by the margin; radius along x, or y for btCylinderShapeX) plus the margin along the direction:
/// the given extents with edges rounded to the margin's radius.
TriangleMesh cylinder_mesh(const btCylinderShape& cylinder, double max_edge, const std::string& path) {
  const int up = cylinder.getUpAxis();
  const Vec3 core = to_vec3(cylinder.getHalfExtentsWithoutMargin());
  const double m = cylinder.getMargin();
  const double r = core[up == 0 ? 1 : 0], h = core[up];
  check_margin(m, path, cylinder);
  if (!(r >= 0.0) || !(h >= 0.0) || !std::isfinite(r) || !std::isfinite(h)) {
    fail(path, cylinder,
         "radius and half height without margin must be >= 0 and finite (the margin " + format_number(m) +
             " is inside the half extents), got " + format_number(r) + " and " + format_number(h));
  }
  check_dimension(r + m, "radius", path, cylinder);
  check_dimension(h + m, "half height", path, cylinder);
  const double step = max_edge / std::sqrt(2.0);
  Profile profile(step, {0.0, h + m}, path, cylinder, max_edge);
  profile.line_to({r, h + m}, false);
  profile.arc({r, h}, m, kHalfPi, 0.0);
  profile.line_to({r + m, -h}, true);
  profile.arc({r, -h}, m, 0.0, -kHalfPi);
  profile.line_to({0.0, -h - m}, false);
  return revolve(profile, up, step, path, cylinder, max_edge);
}

/// btConeShape: apex at +getHeight()/2 along getConeUpIndex(), base of getRadius() at -getHeight()/2 (both
/// with local scaling), grown outward by the margin: a rounded apex, a rounded rim, a base moved down.
TriangleMesh cone_mesh(const btConeShape& cone, double max_edge, const std::string& path) {
  const double radius = cone.getRadius(), height = cone.getHeight(), m = cone.getMargin();
  check_dimension(radius, "radius", path, cone);
  check_dimension(height, "height", path, cone);
  check_margin(m, path, cone);
  const double h = 0.5 * height;
  // The side's outward normal in (rho, y) is (height, radius) / slant: Bullet's apex threshold sin = radius
  // / slant in btConeShape::coneLocalSupport.
  const double side = std::atan2(radius, height);
  const Eigen::Vector2d offset = m * direction(side);
  const double step = max_edge / std::sqrt(2.0);
  Profile profile(step, {0.0, h + m}, path, cone, max_edge);
  profile.arc({0.0, h}, m, kHalfPi, side);
  profile.line_to(Eigen::Vector2d(radius, -h) + offset, true);
  profile.arc({radius, -h}, m, side, -kHalfPi);
  profile.line_to({0.0, -h - m}, false);
  return revolve(profile, cone.getConeUpIndex(), step, path, cone, max_edge);
}

// ---- convex hulls: polyhedra, rounded by the margin, and Bullet's support mapping ---------------------

/// The convex hull of `points` by Bullet's btConvexHullComputer (exact integer arithmetic on quantized
/// coordinates): its faces are planar polygons, counter-clockwise seen from outside, fanned into triangles
/// from their first vertex; vertices are the input points themselves (original_vertex_index), unrounded.
/// Empty when the points span no volume.
TriangleMesh convex_hull_mesh(const Vec3Array& points) {
  TriangleMesh mesh;
  if (points.size() < 4) return mesh;
  btConvexHullComputer hull;
  hull.compute(coordinates(points), static_cast<int>(sizeof(Vec3)), static_cast<int>(points.size()), 0, 0);
  for (int i = 0; i < hull.vertices.size(); ++i)
    mesh.positions.push_back(points[hull.original_vertex_index[i]]);
  std::vector<Index> polygon;
  for (int f = 0; f < hull.faces.size(); ++f) {
    polygon.clear();
    const btConvexHullComputer::Edge* first = &hull.edges[hull.faces[f]];
    const btConvexHullComputer::Edge* edge = first;
    do {
      polygon.push_back(static_cast<Index>(edge->getSourceVertex()));
      edge = edge->getNextEdgeOfFace();
    } while (edge != first);
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
      mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
  }
  // Coplanar points give a flat hull of two faces: no solid.
  double volume6 = 0.0;
  for (const Triangle& t : mesh.triangles)
    volume6 += mesh.positions[t[0]].dot(mesh.positions[t[1]].cross(mesh.positions[t[2]]));
  if (!(volume6 > 0.0)) return {};
  return mesh;
}

/// Unit directions of a cube-sphere grid with `n` cells along each cube edge: neighbours (diagonals
/// included) are at most 2 sqrt(2) / n radians apart, since a face at distance >= 1 from the centre turns
/// a step s of its grid by at most s radians.
Vec3Array cube_sphere_directions(int n) {
  Vec3Array directions;
  directions.reserve(6 * static_cast<std::size_t>(n + 1) * (n + 1));
  for (int a = 0; a < 3; ++a) {
    for (int sign : {-1, 1}) {
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          Vec3 d;
          d[a] = sign;
          d[(a + 1) % 3] = -1.0 + 2.0 * i / n;
          d[(a + 2) % 3] = -1.0 + 2.0 * j / n;
          directions.push_back(d.normalized());
        }
      }
    }
  }
  return directions;
}

/// Cells per cube edge so that support points of a surface whose radius of curvature is at most `radius`
/// are at most `max_edge` apart (diagonals included); at least 4 (30-degree steps) to round small margins.
/// @throws SceneError when the cube-sphere would have more than kMaxShapeMeshTriangles triangles (counted
/// before the int, which a sphere of 1e7 m overflowed)
int cube_sphere_cells(double radius, double max_edge, const std::string& path,
                      const btCollisionShape& shape) {
  const double cells = std::max(4.0, std::ceil(2.0 * std::sqrt(2.0) * radius / max_edge));
  check_triangle_count(12.0 * (cells + 1.0) * (cells + 1.0), path, shape, max_edge_text(max_edge));
  return static_cast<int>(cells);
}

/// `points` without the ones closer than `radius` to an earlier one (a spatial hash of cells `radius`
/// wide): support points of nearly equal directions would otherwise make needle faces.
Vec3Array without_near_duplicates(const Vec3Array& points, double radius) {
  struct CellHash {
    std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
      return static_cast<std::size_t>(k[0] * 73856093 ^ k[1] * 19349663 ^ k[2] * 83492791);
    }
  };
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<Index>, CellHash> cells;
  Vec3Array kept;
  for (const Vec3& p : points) {
    const std::array<std::int64_t, 3> key = {static_cast<std::int64_t>(std::floor(p.x() / radius)),
                                             static_cast<std::int64_t>(std::floor(p.y() / radius)),
                                             static_cast<std::int64_t>(std::floor(p.z() / radius))};
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx) {
      for (int dy = -1; dy <= 1 && !near; ++dy) {
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          const auto it = cells.find({key[0] + dx, key[1] + dy, key[2] + dz});
          if (it == cells.end()) continue;
          for (Index i : it->second) {
            if ((kept[i] - p).squaredNorm() < radius * radius) {
              near = true;
              break;
            }
          }
        }
      }
    }
    if (near) continue;
    cells[key].push_back(static_cast<Index>(kept.size()));
    kept.push_back(p);
  }
  return kept;
}

/// The normals of a flat point set that the cube-sphere grid may miss: +-n of a planar polygon (so its two
/// faces, moved out by the margin, are exact), or a ring of directions perpendicular to a segment (its
/// rounded side), as fine as the grid of `cells`.
void add_flat_normals(const Vec3Array& points, int cells, Vec3Array& directions) {
  if (points.empty()) return;
  const Vec3& p0 = points.front();
  Vec3 axis = Vec3::Zero();
  for (const Vec3& p : points)
    if ((p - p0).squaredNorm() > axis.squaredNorm()) axis = p - p0;
  if (!(axis.squaredNorm() > 0.0)) return;  // one point: a ball, which the grid samples
  Vec3 normal = Vec3::Zero();
  for (const Vec3& p : points) {
    const Vec3 w = (p - p0).cross(axis);
    if (w.squaredNorm() > normal.squaredNorm()) normal = w;
  }
  if (normal.norm() > 1e-12 * axis.squaredNorm()) {
    directions.push_back(normal.normalized());
    directions.push_back(-normal.normalized());
    return;
  }
  const Vec3 u = axis.normalized(), v1 = u.unitOrthogonal(), v2 = u.cross(v1);
  const int ring = 4 * cells;
  for (int k = 0; k < ring; ++k) {
    const double angle = 2.0 * kPi * k / ring;
    directions.push_back(std::cos(angle) * v1 + std::sin(angle) * v2);
  }
}

/// A convex polyhedron (the scaled points of a btConvexHullShape and its kin) grown by `margin`, as Bullet's
/// support mapping has it (the vertex farthest along a direction d, plus margin d). The polyhedron is
/// hulled first; then every corner of every face moved out by margin along the face's normal (so the
/// faces, moved out, are exact), and the vertex support plus margin d for the directions of a cube-sphere
/// grid fine enough that the rounded corners and edges (radius margin) are sampled every max_edge. Every
/// point is on Bullet's surface (at distance margin from the polyhedron); their hull is the mesh. The strips
/// rounding the polyhedron's edges keep the edges' length, as the flat faces keep theirs. Points that span no
/// volume (a flat polygon, a segment) grown by a margin are a slab or a capsule: add_flat_normals adds the
/// directions that make their faces and sides. Measured: a hull
/// of 8 / 200 / 1,000 points on a 0.2 m sphere, margin 0.04, max_edge 0.02 gives 502 / 2,656 / 10,580
/// triangles in 1.3 / 3.6 / 24 ms (up to 2.5 times that while the machine's other core was busy).
TriangleMesh polyhedron_mesh(const Vec3Array& points, double margin, double max_edge, const std::string& path,
                             const btCollisionShape& shape) {
  const TriangleMesh core = convex_hull_mesh(points);
  if (margin == 0.0) {
    if (core.triangles.empty()) fail(path, shape, "its points span no volume and its margin is 0");
    return core;
  }
  Vec3Array samples;
  if (!core.triangles.empty()) {
    // Corners of each face moved out along the face's normal, shared by the face's triangles.
    for (const Triangle& t : core.triangles) {
      const Vec3& a = core.positions[t[0]];
      const Vec3 normal = (core.positions[t[1]] - a).cross(core.positions[t[2]] - a).normalized();
      for (Index v : t)
        samples.push_back(core.positions[v] + margin * normal);
    }
  }
  const Vec3Array& corners = core.triangles.empty() ? points : core.positions;
  const int cells = cube_sphere_cells(margin, max_edge, path, shape);
  Vec3Array directions = cube_sphere_directions(cells);
  if (core.triangles.empty()) add_flat_normals(points, cells, directions);
  check_triangle_count(2.0 * static_cast<double>(directions.size() + samples.size()), path, shape,
                       max_edge_text(max_edge));
  double size = 0.0;
  for (const Vec3& c : corners)
    size = std::max(size, c.norm());
  for (const Vec3& d : directions) {
    // Every vertex that ties for farthest: along a face's or a flat set's normal, all of its corners.
    double best = -std::numeric_limits<double>::infinity();
    for (const Vec3& c : corners)
      best = std::max(best, d.dot(c));
    for (const Vec3& c : corners)
      if (d.dot(c) >= best - 1e-12 * size) samples.push_back(c + margin * d);
  }
  return convex_hull_mesh(without_near_duplicates(samples, 0.05 * margin * 2.0 / cells));
}

/// Any other convex shape by its own support mapping (localGetSupportingVertex, margin and scaling
/// included): support points for a cube-sphere grid of directions fine for a surface whose radius of
/// curvature is at most `curvature_radius`, hulled.
TriangleMesh support_mesh(const btConvexShape& shape, double curvature_radius, double max_edge,
                          const std::string& path) {
  const int cells = cube_sphere_cells(curvature_radius, max_edge, path, shape);
  const Vec3Array directions = cube_sphere_directions(cells);
  check_triangle_count(2.0 * static_cast<double>(directions.size()), path, shape, max_edge_text(max_edge));
  Vec3Array samples;
  samples.reserve(directions.size());
  for (const Vec3& d : directions)
    samples.push_back(to_vec3(shape.localGetSupportingVertex(to_bt(d))));
  TriangleMesh mesh =
      convex_hull_mesh(without_near_duplicates(samples, 0.05 * curvature_radius * 2.0 / cells));
  if (mesh.triangles.empty()) fail(path, shape, "its support points span no volume");
  return mesh;
}

// ---- triangle meshes and heightfields ------------------------------------------------------------------

/// Coordinate k of vertex v of a striding mesh's vertex base, stored as float or double.
double vertex_coordinate(const unsigned char* base, int stride, PHY_ScalarType type, int v, int k) {
  const unsigned char* at = base + static_cast<std::ptrdiff_t>(v) * stride;
  if (type == PHY_DOUBLE) {
    double x;
    std::memcpy(&x, at + k * sizeof(double), sizeof x);
    return x;
  }
  float x;
  std::memcpy(&x, at + k * sizeof(float), sizeof x);
  return x;
}

/// Index k of face f of a striding mesh's index base (32-, 16- or 8-bit).
Index face_index(const unsigned char* base, int stride, PHY_ScalarType type, int f, int k) {
  const unsigned char* at = base + static_cast<std::ptrdiff_t>(f) * stride;
  if (type == PHY_SHORT) {
    unsigned short i;
    std::memcpy(&i, at + k * sizeof i, sizeof i);
    return i;
  }
  if (type == PHY_UCHAR) return at[k];
  unsigned int i;
  std::memcpy(&i, at + k * sizeof i, sizeof i);
  return i;
}

/// Every subpart of a striding mesh with its scaling (a triangle mesh shape's local scaling is its mesh
/// interface's), vertices shared by index as the game stored them, every face kept.
TriangleMesh striding_mesh(const btStridingMeshInterface& striding, const std::string& path,
                           const btCollisionShape& shape) {
  const Vec3 scaling = to_vec3(striding.getScaling());
  TriangleMesh mesh;
  for (int part = 0; part < striding.getNumSubParts(); ++part) {
    const unsigned char* vertices = nullptr;
    const unsigned char* indices = nullptr;
    int vertex_count = 0, vertex_stride = 0, index_stride = 0, face_count = 0;
    PHY_ScalarType vertex_type = PHY_FLOAT, index_type = PHY_INTEGER;
    striding.getLockedReadOnlyVertexIndexBase(&vertices, vertex_count, vertex_type, vertex_stride, &indices,
                                              index_stride, face_count, index_type, part);
    const bool vertex_type_ok = vertex_type == PHY_FLOAT || vertex_type == PHY_DOUBLE;
    const bool index_type_ok =
        index_type == PHY_INTEGER || index_type == PHY_SHORT || index_type == PHY_UCHAR;
    if (!vertex_type_ok || !index_type_ok) {
      striding.unLockReadOnlyVertexBase(part);
      fail(path, shape,
           "subpart " + std::to_string(part) + " stores vertices as PHY_ScalarType " +
               std::to_string(vertex_type) + " and indices as " + std::to_string(index_type) +
               "; Bullet reads float or double vertices and 8-, 16- or 32-bit indices");
    }
    const auto first = static_cast<Index>(mesh.positions.size());
    for (int v = 0; v < vertex_count; ++v) {
      const Vec3 local(vertex_coordinate(vertices, vertex_stride, vertex_type, v, 0),
                       vertex_coordinate(vertices, vertex_stride, vertex_type, v, 1),
                       vertex_coordinate(vertices, vertex_stride, vertex_type, v, 2));
      mesh.positions.push_back(local.cwiseProduct(scaling));
    }
    for (int f = 0; f < face_count; ++f) {
      Triangle t;
      for (int k = 0; k < 3; ++k) {
        const Index i = face_index(indices, index_stride, index_type, f, k);
        if (i >= static_cast<Index>(vertex_count)) {
          striding.unLockReadOnlyVertexBase(part);
          fail(path, shape,
               "subpart " + std::to_string(part) + " face " + std::to_string(f) + " has vertex index " +
                   std::to_string(i) + ", but the subpart has " + std::to_string(vertex_count) + " vertices");
        }
        t[k] = first + i;
      }
      mesh.triangles.push_back(t);
    }
    striding.unLockReadOnlyVertexBase(part);
  }
  return mesh;
}

/// Drops faces that repeat a vertex or have no area, which Bullet tolerates in triangle meshes.
void drop_degenerate_faces(TriangleMesh& mesh) {
  const auto degenerate = [&](const Triangle& t) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
    const Vec3& a = mesh.positions[t[0]];
    return !((mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).squaredNorm() > 0.0);
  };
  mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(), degenerate),
                       mesh.triangles.end());
}

/// The vertices a btConvexTriangleMeshShape's support runs over: those of its faces, scaled.
Vec3Array face_vertices(const TriangleMesh& mesh) {
  std::vector<bool> used(mesh.positions.size(), false);
  for (const Triangle& t : mesh.triangles)
    for (Index v : t)
      used[v] = true;
  Vec3Array points;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (used[i]) points.push_back(mesh.positions[i]);
  return points;
}

/// Collects a heightfield's triangles as Bullet's processAllTriangles gives them (its diagonals, winding and
/// local origin), welding grid points by their exact coordinates (getVertex computes each the same way for
/// every triangle that has it) so that neighbouring triangles share vertices.
class HeightfieldCollector final : public btTriangleCallback {
 public:
  void processTriangle(btVector3* triangle, int /*part*/, int /*index*/) override {
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = to_vec3(triangle[k]);
      const auto [it, inserted] = m_index.try_emplace({p.x(), p.y(), p.z()}, 0);
      if (inserted) {
        it->second = static_cast<Index>(mesh.positions.size());
        mesh.positions.push_back(p);
      }
      t[k] = it->second;
    }
    mesh.triangles.push_back(t);
  }

  TriangleMesh mesh;

 private:
  struct KeyHash {
    std::size_t operator()(const std::array<double, 3>& k) const {
      std::size_t h = 0;
      for (double x : k) {
        std::uint64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        h = h * 1000003u ^ std::hash<std::uint64_t>()(bits);
      }
      return h;
    }
  };
  std::unordered_map<std::array<double, 3>, Index, KeyHash> m_index;
};

TriangleMesh heightfield_mesh(const btHeightfieldTerrainShape& terrain) {
  btTransform identity;
  identity.setIdentity();
  btVector3 aabb_min, aabb_max;
  terrain.getAabb(identity, aabb_min, aabb_max);
  HeightfieldCollector collector;
  terrain.processAllTriangles(&collector, aabb_min, aabb_max);
  drop_degenerate_faces(collector.mesh);
  return std::move(collector.mesh);
}

// ---- the unbounded plane ----------------------------------------------------------------------------------

PlaneFrame frame_of(const btStaticPlaneShape& plane, const std::string& path) {
  const Vec3 normal = to_vec3(plane.getPlaneNormal());
  const double constant = plane.getPlaneConstant();
  if (!normal.allFinite() || !(normal.squaredNorm() > 0.0) || !std::isfinite(constant)) {
    fail(path, plane,
         "normal (" + format_number(normal.x()) + ", " + format_number(normal.y()) + ", " +
             format_number(normal.z()) + ") must be finite and non-zero and constant " +
             format_number(constant) + " finite");
  }
  PlaneFrame frame;
  frame.origin = normal * (constant / normal.squaredNorm());
  frame.normal = normal.normalized();
  frame.axis_u = frame.normal.unitOrthogonal();
  frame.axis_v = frame.normal.cross(frame.axis_u);
  return frame;
}

/// The plane n . x = c (Bullet's normal and constant; its plane collisions ignore local scaling and margin)
/// as a square of half side plane_half_size about the point c n / |n|^2, in cells of at most plane_cell,
/// counter-clockwise seen from the side n points to (the solid is the other side).
TriangleMesh plane_mesh(const btStaticPlaneShape& plane, const ShapeMeshOptions& options,
                        const std::string& path) {
  const PlaneFrame frame = frame_of(plane, path);
  const double half = options.plane_half_size;
  const double cells_wanted = std::ceil(2.0 * half / options.plane_cell);
  check_triangle_count(2.0 * cells_wanted * cells_wanted, path, plane,
                       "ShapeMeshOptions::plane_half_size " + format_number(half) + " and plane_cell " +
                           format_number(options.plane_cell));
  const int cells = static_cast<int>(cells_wanted);
  const Vec3& center = frame.origin;
  const Vec3& t1 = frame.axis_u;
  const Vec3& t2 = frame.axis_v;
  TriangleMesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(cells + 1) * (cells + 1));
  auto coordinate = [&](int i) { return i == cells ? half : -half + 2.0 * half * i / cells; };
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      mesh.positions.push_back(center + coordinate(i) * t1 + coordinate(j) * t2);
  auto at = [cells](int i, int j) { return static_cast<Index>(j * (cells + 1) + i); };
  mesh.triangles.reserve(2 * static_cast<std::size_t>(cells) * cells);
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return mesh;
}

// ---- dispatch by Bullet's shape type
// ------------------------------------------------------------------------

bool supported_type(int type) {
  switch (type) {
    case BOX_SHAPE_PROXYTYPE:
    case SPHERE_SHAPE_PROXYTYPE:
    case CAPSULE_SHAPE_PROXYTYPE:
    case CYLINDER_SHAPE_PROXYTYPE:
    case CONE_SHAPE_PROXYTYPE:
    case CONVEX_HULL_SHAPE_PROXYTYPE:
    case CONVEX_POINT_CLOUD_SHAPE_PROXYTYPE:
    case CONVEX_TRIANGLEMESH_SHAPE_PROXYTYPE:
    case MULTI_SPHERE_SHAPE_PROXYTYPE:
    case UNIFORM_SCALING_SHAPE_PROXYTYPE:
    case STATIC_PLANE_PROXYTYPE:
    case TRIANGLE_MESH_SHAPE_PROXYTYPE:
    case MULTIMATERIAL_TRIANGLE_MESH_PROXYTYPE:
    case SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE:
    case TERRAIN_SHAPE_PROXYTYPE:
    case COMPOUND_SHAPE_PROXYTYPE:
    case EMPTY_SHAPE_PROXYTYPE:
      return true;
    default:
      return false;
  }
}

TriangleMesh build(const btCollisionShape& shape, const ShapeMeshOptions& options, const std::string& path) {
  const double e = options.max_edge;
  switch (shape.getShapeType()) {
    case BOX_SHAPE_PROXYTYPE:
      return box_mesh(static_cast<const btBoxShape&>(shape), path);
    case SPHERE_SHAPE_PROXYTYPE:
      return sphere_mesh(static_cast<const btSphereShape&>(shape), e, path);
    case CAPSULE_SHAPE_PROXYTYPE:
      return capsule_mesh(static_cast<const btCapsuleShape&>(shape), e, path);
    case CYLINDER_SHAPE_PROXYTYPE:
      return cylinder_mesh(static_cast<const btCylinderShape&>(shape), e, path);
    case CONE_SHAPE_PROXYTYPE:
      return cone_mesh(static_cast<const btConeShape&>(shape), e, path);
    case CONVEX_HULL_SHAPE_PROXYTYPE: {
      const auto& hull = static_cast<const btConvexHullShape&>(shape);
      Vec3Array points;
      for (int i = 0; i < hull.getNumPoints(); ++i)
        points.push_back(to_vec3(hull.getScaledPoint(i)));
      check_margin(hull.getMargin(), path, shape);
      return polyhedron_mesh(points, hull.getMargin(), e, path, shape);
    }
    case CONVEX_POINT_CLOUD_SHAPE_PROXYTYPE: {
      const auto& cloud = static_cast<const btConvexPointCloudShape&>(shape);
      Vec3Array points;
      for (int i = 0; i < cloud.getNumPoints(); ++i)
        points.push_back(to_vec3(cloud.getScaledPoint(i)));
      check_margin(cloud.getMargin(), path, shape);
      return polyhedron_mesh(points, cloud.getMargin(), e, path, shape);
    }
    case CONVEX_TRIANGLEMESH_SHAPE_PROXYTYPE: {
      const auto& convex = static_cast<const btConvexTriangleMeshShape&>(shape);
      check_margin(convex.getMargin(), path, shape);
      return polyhedron_mesh(face_vertices(striding_mesh(*convex.getMeshInterface(), path, shape)),
                             convex.getMargin(), e, path, shape);
    }
    case MULTI_SPHERE_SHAPE_PROXYTYPE: {
      // Curved like its largest sphere (local scaling included); between spheres the hull is ruled.
      const auto& spheres = static_cast<const btMultiSphereShape&>(shape);
      const double scale = to_vec3(spheres.getLocalScaling()).cwiseAbs().maxCoeff();
      double radius = 0.0;
      for (int i = 0; i < spheres.getSphereCount(); ++i)
        radius = std::max(radius, std::abs(static_cast<double>(spheres.getSphereRadius(i))) * scale);
      check_dimension(radius, "largest sphere radius", path, shape);
      return support_mesh(spheres, radius, e, path);
    }
    case UNIFORM_SCALING_SHAPE_PROXYTYPE: {
      const auto& scaled = static_cast<const btUniformScalingShape&>(shape);
      const double factor = scaled.getUniformScalingFactor();
      if (!std::isfinite(factor) || factor == 0.0) {
        fail(path, shape, "uniform scaling factor must be finite and non-zero, got " + format_number(factor));
      }
      ShapeMeshOptions child_options = options;
      child_options.max_edge = e / std::abs(factor);
      TriangleMesh mesh =
          build(*scaled.getChildShape(), child_options, path + "btUniformScalingShape child: ");
      for (Vec3& p : mesh.positions)
        p *= factor;
      if (factor < 0.0) {
        for (Triangle& t : mesh.triangles)
          std::swap(t[1], t[2]);  // a point reflection turns the winding inside out
      }
      return mesh;
    }
    case STATIC_PLANE_PROXYTYPE:
      return plane_mesh(static_cast<const btStaticPlaneShape&>(shape), options, path);
    case TRIANGLE_MESH_SHAPE_PROXYTYPE:
    case MULTIMATERIAL_TRIANGLE_MESH_PROXYTYPE: {
      TriangleMesh mesh =
          striding_mesh(*static_cast<const btTriangleMeshShape&>(shape).getMeshInterface(), path, shape);
      drop_degenerate_faces(mesh);
      return mesh;
    }
    case SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE: {
      // Bullet scales the child's triangles (with their own mesh scaling) by this shape's local scaling.
      const auto& scaled = static_cast<const btScaledBvhTriangleMeshShape&>(shape);
      const Vec3 scaling = to_vec3(scaled.getLocalScaling());
      TriangleMesh mesh = striding_mesh(*scaled.getChildShape()->getMeshInterface(), path, shape);
      for (Vec3& p : mesh.positions)
        p = p.cwiseProduct(scaling);
      drop_degenerate_faces(mesh);
      return mesh;
    }
    case TERRAIN_SHAPE_PROXYTYPE:
      return heightfield_mesh(static_cast<const btHeightfieldTerrainShape&>(shape));
    case COMPOUND_SHAPE_PROXYTYPE: {
      const auto& compound = static_cast<const btCompoundShape&>(shape);
      TriangleMesh mesh;
      for (int i = 0; i < compound.getNumChildShapes(); ++i) {
        const TriangleMesh child = build(*compound.getChildShape(i), options,
                                         path + "btCompoundShape child " + std::to_string(i) + ": ");
        append(mesh, child, compound.getChildTransform(i));
      }
      return mesh;
    }
    case EMPTY_SHAPE_PROXYTYPE:
      return {};  // Bullet collides nothing with it
    default:
      fail(path, shape,
           "Bullet shape type " + std::to_string(shape.getShapeType()) +
               " is not supported by drench::bullet::shape_mesh; supported: " + kSupported);
  }
}

}  // namespace

TriangleMesh shape_mesh(const btCollisionShape& shape, const ShapeMeshOptions& options) {
  const std::pair<const char*, double> checked[] = {{"max_edge", options.max_edge},
                                                    {"plane_half_size", options.plane_half_size},
                                                    {"plane_cell", options.plane_cell}};
  for (const auto& [name, value] : checked) {
    if (!positive_finite(value)) {
      fail("", shape,
           std::string("ShapeMeshOptions::") + name + " must be > 0 and finite, got " + format_number(value));
    }
  }
  return build(shape, options, "");
}

bool collides_with_nothing(const btCollisionShape& shape) {
  if (shape.getShapeType() == EMPTY_SHAPE_PROXYTYPE) return true;
  if (shape.getShapeType() != COMPOUND_SHAPE_PROXYTYPE) return false;
  const auto& compound = static_cast<const btCompoundShape&>(shape);
  for (int i = 0; i < compound.getNumChildShapes(); ++i)
    if (!collides_with_nothing(*compound.getChildShape(i))) return false;
  return true;
}

namespace {

/// FNV-1a over the bytes of `value`, continuing `hash`.
template <class T>
std::uint64_t mix(std::uint64_t hash, const T& value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (unsigned char b : bytes)
    hash = (hash ^ b) * 1099511628211ull;
  return hash;
}

std::uint64_t mix_transform(std::uint64_t hash, const btTransform& transform) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      hash = mix(hash, transform.getBasis()[r][c]);
  for (int k = 0; k < 3; ++k)
    hash = mix(hash, transform.getOrigin()[k]);
  return hash;
}

std::uint64_t signature(std::uint64_t hash, const btCollisionShape& shape) {
  hash = mix(hash, shape.getShapeType());
  hash = mix(hash, &shape);
  const btVector3 scaling = shape.getLocalScaling();
  for (int k = 0; k < 3; ++k)
    hash = mix(hash, scaling[k]);
  hash = mix(hash, shape.getMargin());
  // The local box catches what the game changes in place without a new address or scaling: a hull's
  // addPoint, a triangle mesh refitted (Bullet caches these boxes, so this costs little).
  btTransform identity;
  identity.setIdentity();
  btVector3 low, high;
  shape.getAabb(identity, low, high);
  for (int k = 0; k < 3; ++k)
    hash = mix(mix(hash, low[k]), high[k]);
  if (shape.getShapeType() == COMPOUND_SHAPE_PROXYTYPE) {
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    hash = mix(hash, compound.getNumChildShapes());
    for (int i = 0; i < compound.getNumChildShapes(); ++i)
      hash = signature(mix_transform(hash, compound.getChildTransform(i)), *compound.getChildShape(i));
  } else if (shape.getShapeType() == UNIFORM_SCALING_SHAPE_PROXYTYPE) {
    const auto& scaled = static_cast<const btUniformScalingShape&>(shape);
    hash = signature(mix(hash, scaled.getUniformScalingFactor()), *scaled.getChildShape());
  }
  return hash;
}

}  // namespace

std::uint64_t shape_signature(const btCollisionShape& shape) {
  return signature(14695981039346656037ull, shape);
}

PlaneFrame plane_frame(const btStaticPlaneShape& plane) {
  return frame_of(plane, "");
}

TriangleMesh plane_cells_mesh(const PlaneFrame& frame, double cell, const std::vector<PlaneCell>& cells) {
  if (!positive_finite(cell))
    throw SceneError("plane grid cell must be > 0 and finite, got " + format_number(cell));
  if (2.0 * static_cast<double>(cells.size()) > static_cast<double>(kMaxShapeMeshTriangles)) {
    throw SceneError("a plane patch of " + std::to_string(cells.size()) +
                     " cells would have more than kMaxShapeMeshTriangles = " +
                     std::to_string(kMaxShapeMeshTriangles) + " triangles");
  }
  TriangleMesh mesh;
  std::unordered_map<PlaneCell, Index, PlaneCellHash> nodes;  // by grid node: neighbouring cells share
  const auto node = [&](std::int64_t i, std::int64_t j) {
    const auto [it, added] = nodes.try_emplace(PlaneCell{i, j}, static_cast<Index>(mesh.positions.size()));
    if (added) {
      mesh.positions.push_back(frame.origin + (static_cast<double>(i) * cell) * frame.axis_u +
                               (static_cast<double>(j) * cell) * frame.axis_v);
    }
    return it->second;
  };
  mesh.triangles.reserve(2 * cells.size());
  for (const auto& [i, j] : cells) {
    const Index a = node(i, j), b = node(i + 1, j), c = node(i + 1, j + 1), d = node(i, j + 1);
    mesh.triangles.push_back({a, b, c});  // axis_u x axis_v = normal: counter-clockwise seen from it
    mesh.triangles.push_back({a, c, d});
  }
  return mesh;
}

bool is_supported_shape(const btCollisionShape& shape) {
  const int type = shape.getShapeType();
  if (!supported_type(type)) return false;
  if (type == COMPOUND_SHAPE_PROXYTYPE) {
    const auto& compound = static_cast<const btCompoundShape&>(shape);
    for (int i = 0; i < compound.getNumChildShapes(); ++i)
      if (!is_supported_shape(*compound.getChildShape(i))) return false;
  }
  if (type == UNIFORM_SCALING_SHAPE_PROXYTYPE) {
    return is_supported_shape(*static_cast<const btUniformScalingShape&>(shape).getChildShape());
  }
  return true;
}

}  // namespace drench::bullet
