// shape_mesh: every Bullet collision shape as a triangle mesh, checked against the geometry Bullet collides
// with: closed and outward for solids, vertices on the analytic surface (margins and local scaling
// included), enclosed volumes against analytic ones, edges against max_edge, children where the compound
// puts them, the plane's and the heightfield's grids, and the errors for what it cannot build.

#include <drench/bullet/shape_mesh.hpp>

#include <BulletCollision/CollisionShapes/btConvexPointCloudShape.h>
#include <BulletCollision/CollisionShapes/btConvexTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btEmptyShape.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btMultiSphereShape.h>
#include <BulletCollision/CollisionShapes/btMultimaterialTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btScaledBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btUniformScalingShape.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "../assertions.hpp"
#include "bullet_test_helpers.hpp"

namespace drench::bullet {
namespace {

using drench::test::throws_containing;
using test::bullet_tolerance;

constexpr double kPi = 3.14159265358979323846;

// ---- geometric facts of a mesh ---------------------------------------------------------------------------

/// Closed and consistently oriented: every directed edge once, and its reverse once (so each edge has
/// exactly two faces, in opposite directions); no face repeats a vertex.
testing::AssertionResult closed_and_oriented(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return testing::AssertionFailure() << "no triangles";
  std::map<std::pair<Index, Index>, int> directed;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      return testing::AssertionFailure() << "face " << f << " repeats a vertex";
    }
    for (int k = 0; k < 3; ++k)
      ++directed[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    if (count != 1) {
      return testing::AssertionFailure() << "edge " << edge.first << "-" << edge.second << " in " << count
                                         << " faces in the same direction";
    }
    if (directed.find({edge.second, edge.first}) == directed.end()) {
      return testing::AssertionFailure()
             << "edge " << edge.first << "-" << edge.second << " has no face on its other side";
    }
  }
  return testing::AssertionSuccess();
}

/// Enclosed volume by the divergence theorem (positive for an outward mesh).
double volume(const TriangleMesh& mesh) {
  double v6 = 0.0;
  for (const Triangle& t : mesh.triangles)
    v6 += mesh.positions[t[0]].dot(mesh.positions[t[1]].cross(mesh.positions[t[2]]));
  return v6 / 6.0;
}

double area(const TriangleMesh& mesh) {
  double a = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3& p = mesh.positions[t[0]];
    a += 0.5 * (mesh.positions[t[1]] - p).cross(mesh.positions[t[2]] - p).norm();
  }
  return a;
}

/// The longest edge whose two vertices do not both satisfy `on_flat_face` (edges on flat faces may be long).
double longest_curved_edge(const TriangleMesh& mesh, const std::function<bool(const Vec3&)>& on_flat_face) {
  double longest = 0.0;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = mesh.positions[t[k]];
      const Vec3& b = mesh.positions[t[(k + 1) % 3]];
      if (on_flat_face(a) && on_flat_face(b)) continue;
      longest = std::max(longest, (a - b).norm());
    }
  }
  return longest;
}

double longest_edge(const TriangleMesh& mesh) {
  return longest_curved_edge(mesh, [](const Vec3&) { return false; });
}

/// About-uniform unit directions (a Fibonacci sphere).
std::vector<Vec3> directions(int n = 400) {
  std::vector<Vec3> d;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return d;
}

double mesh_support(const TriangleMesh& mesh, const Vec3& u) {
  double best = -std::numeric_limits<double>::infinity();
  for (const Vec3& p : mesh.positions)
    best = std::max(best, u.dot(p));
  return best;
}

/// Bullet's support of the convex shape along u, margin and scaling included: what GJK collides with.
double bullet_support(const btConvexShape& shape, const Vec3& u) {
  return u.dot(to_vec3(shape.localGetSupportingVertex(to_bt(u))));
}

/// No vertex lies beyond Bullet's surface in any direction (to Bullet's rounding), and the mesh reaches to
/// within `gap` of it in every direction.
void expect_within_support(const btConvexShape& shape, const TriangleMesh& mesh, double gap) {
  double size = 0.0;
  for (const Vec3& p : mesh.positions)
    size = std::max(size, p.norm());
  const double rounding = bullet_tolerance(1e-12 * size, size, 16);
  for (const Vec3& u : directions()) {
    const double bullet = bullet_support(shape, u);
    const double ours = mesh_support(mesh, u);
    EXPECT_LE(ours, bullet + rounding) << shape.getName() << " along " << u.transpose();
    EXPECT_GE(ours, bullet - gap) << shape.getName() << " along " << u.transpose();
  }
}

/// Signed distance from a 2D point to a convex polygon given counter-clockwise (negative inside).
double polygon_distance(const Eigen::Vector2d& q, const std::vector<Eigen::Vector2d>& polygon) {
  double outside = -std::numeric_limits<double>::infinity();  // largest signed distance to an edge line
  double to_boundary = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const Eigen::Vector2d edge = b - a;
    const Eigen::Vector2d normal = Eigen::Vector2d(edge.y(), -edge.x()).normalized();
    outside = std::max(outside, normal.dot(q - a));
    const double s = std::clamp((q - a).dot(edge) / edge.squaredNorm(), 0.0, 1.0);
    to_boundary = std::min(to_boundary, (q - (a + s * edge)).norm());
  }
  return outside >= 0.0 ? to_boundary : -to_boundary;  // on an edge's line counts as outside
}

/// (rho, y) of a point about local axis `up`.
Eigen::Vector2d meridian(const Vec3& p, int up) {
  const double along = p[up];
  Vec3 radial = p;
  radial[up] = 0.0;
  return {radial.norm(), along};
}

/// Largest |distance to `polygon` (a full cross-section through the axis) - margin| over the vertices.
double worst_offset(const TriangleMesh& mesh, int up, const std::vector<Eigen::Vector2d>& polygon,
                    double margin) {
  double worst = 0.0;
  for (const Vec3& p : mesh.positions)
    worst = std::max(worst, std::abs(polygon_distance(meridian(p, up), polygon) - margin));
  return worst;
}

std::vector<Eigen::Vector2d> rectangle(double half_width, double half_height) {
  return {{-half_width, -half_height},
          {half_width, -half_height},
          {half_width, half_height},
          {-half_width, half_height}};
}

double relative_error(double value, double reference) {
  return std::abs(value - reference) / std::abs(reference);
}

/// Volume of a cylinder of core radius a and core half height h grown by a ball of radius m (Pappus: core,
/// caps, side shell, and the two quarter-disc tori of the rounded rims).
double rounded_cylinder_volume(double a, double h, double m) {
  return 2 * kPi * a * a * h + 2 * kPi * a * a * m + 2 * h * kPi * (2 * a * m + m * m) +
         kPi * kPi * a * m * m + 4.0 / 3.0 * kPi * m * m * m;
}

/// Volume of a cone (base radius R, height H) grown by a ball of radius m, by Pappus on its half
/// cross-section: the core, the base slab, the strip along the side, the circular sector at the rim, and
/// the spherical sector at the apex.
double rounded_cone_volume(double R, double H, double m) {
  const double L = std::hypot(R, H);
  const Eigen::Vector2d side(H / L, R / L);  // outward normal of the side in (rho, y)
  const double core = kPi * R * R * H / 3.0;
  const double base = kPi * R * R * m;
  const double strip = 2 * kPi * L * m * (R / 2 + m * side.x() / 2);
  const double beta = std::acos(side.dot(Eigen::Vector2d(0, -1)));
  const Eigen::Vector2d bisector = (side + Eigen::Vector2d(0, -1)).normalized();
  const double rim_centroid = R + 4 * m * std::sin(beta / 2) / (3 * beta) * bisector.x();
  const double rim = 2 * kPi * (beta * m * m / 2) * rim_centroid;
  const double gamma = std::acos(side.dot(Eigen::Vector2d(0, 1)));
  const double apex = 2 * kPi / 3 * m * m * m * (1 - std::cos(gamma));
  return core + base + strip + rim + apex;
}

ShapeMeshOptions with_max_edge(double max_edge) {
  ShapeMeshOptions o;
  o.max_edge = max_edge;
  return o;
}

// ---- box ------------------------------------------------------------------------------------------------

TEST(ShapeMesh, BoxIsItsEightCornersWithMarginInsideAndLocalScaling) {
  btBoxShape box(btVector3(0.3, 0.2, 0.1));
  box.setMargin(0.005);  // inside the extents: they stay
  box.setLocalScaling(btVector3(2.0, 1.0, 0.5));
  const TriangleMesh mesh = shape_mesh(box);
  const Vec3 half = to_vec3(box.getHalfExtentsWithMargin());
  EXPECT_NEAR(half.x(), 0.6, bullet_tolerance(1e-15, 0.6));
  EXPECT_NEAR(half.y(), 0.2, bullet_tolerance(1e-15, 0.2));
  EXPECT_NEAR(half.z(), 0.05, bullet_tolerance(1e-15, 0.05));
  ASSERT_EQ(mesh.positions.size(), 8u);
  ASSERT_EQ(mesh.triangles.size(), 12u);
  EXPECT_TRUE(closed_and_oriented(mesh));
  for (const Vec3& p : mesh.positions)
    EXPECT_EQ(p.cwiseAbs(), half) << p.transpose();
  const double exact = 8.0 * half.x() * half.y() * half.z();
  EXPECT_LE(relative_error(volume(mesh), exact), 1e-12);
  expect_within_support(box, mesh, 1e-12);  // the sharp box: its corners are Bullet's support points
}

// ---- sphere, capsule
// ---------------------------------------------------------------------------------------

TEST(ShapeMesh, SphereVerticesAreOnItsScaledRadiusAndItsVolumeConverges) {
  btSphereShape sphere(0.08);
  sphere.setLocalScaling(btVector3(1.25, 1.25, 1.25));
  const double r = sphere.getRadius();
  EXPECT_NEAR(r, 0.1, bullet_tolerance(1e-15, 0.1));
  double previous_error = 0.0;
  for (double max_edge : {r / 5, r / 10, r / 20}) {
    const TriangleMesh mesh = shape_mesh(sphere, with_max_edge(max_edge));
    EXPECT_TRUE(closed_and_oriented(mesh));
    for (const Vec3& p : mesh.positions)
      ASSERT_NEAR(p.norm(), r, 1e-12 * r) << p.transpose();
    EXPECT_LE(longest_edge(mesh), max_edge);
    const double error = relative_error(volume(mesh), 4.0 / 3.0 * kPi * r * r * r);
    EXPECT_LE(error, 0.03) << "max_edge " << max_edge;
    if (previous_error > 0.0) {
      EXPECT_LT(error, previous_error / 2) << "max_edge " << max_edge;
    }
    previous_error = error;
    expect_within_support(sphere, mesh, max_edge * max_edge / (2 * r));
  }
}

// A sphere smaller than the step (a 4 mm pebble at the default max_edge) was one profile piece from pole to
// pole: 2 vertices and pole fans naming vertices that did not exist, which corrupted the heap downstream.
TEST(ShapeMesh, SpheresMuchSmallerThanTheStepAreStillClosedMeshes) {
  for (const auto& [radius, max_edge] : {std::pair{0.001, 0.05}, {0.004, 0.05}, {0.5, 10.0}}) {
    btSphereShape sphere(radius);
    const TriangleMesh mesh = shape_mesh(sphere, with_max_edge(max_edge));
    EXPECT_TRUE(closed_and_oriented(mesh)) << "radius " << radius;
    for (const Triangle& t : mesh.triangles)
      for (const Index v : t)
        ASSERT_LT(v, mesh.positions.size()) << "radius " << radius;
    const double r = sphere.getRadius();
    for (const Vec3& p : mesh.positions)
      ASSERT_NEAR(p.norm(), r, bullet_tolerance(1e-12 * r, r));
    // The coarsest mesh, an eighth of a turn a piece along the profile and around, holds 0.77 of the ball
    // (an octahedron holds 0.32, the 3-segment mesh of the old minimum 0.35).
    EXPECT_GT(volume(mesh), 0.75 * 4.0 / 3.0 * kPi * r * r * r) << "radius " << radius;
  }
  // And one so large that its pieces overflowed an int before the mesh was counted.
  btSphereShape huge(1e7);
  EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(huge); }, {"SPHERE: ", "kMaxShapeMeshTriangles"}));
  btCapsuleShape long_capsule(0.1, 2e9);
  EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(long_capsule); },
                                       {"CapsuleShape: ", "kMaxShapeMeshTriangles"}));
}

TEST(ShapeMesh, CapsulesAlongEachAxisAreTheirSegmentGrownByTheRadius) {
  const double radius = 0.05, height = 0.2;
  std::vector<std::unique_ptr<btCapsuleShape>> capsules;
  capsules.push_back(std::make_unique<btCapsuleShapeX>(radius, height));
  capsules.push_back(std::make_unique<btCapsuleShape>(radius, height));
  capsules.push_back(std::make_unique<btCapsuleShapeZ>(radius, height));
  for (const auto& capsule : capsules) {
    const int up = capsule->getUpAxis();
    const double r = capsule->getRadius(), h = capsule->getHalfHeight();
    EXPECT_NEAR(h, height / 2, bullet_tolerance(1e-15, h));
    double previous_error = 0.0;
    for (double max_edge : {r / 5, r / 10}) {
      const TriangleMesh mesh = shape_mesh(*capsule, with_max_edge(max_edge));
      EXPECT_TRUE(closed_and_oriented(mesh)) << "up axis " << up;
      // Distance to the segment on the up axis is the radius.
      EXPECT_LE(worst_offset(mesh, up, {{0.0, -h}, {0.0, h}}, r), 1e-12 * r) << "up axis " << up;
      double reach = 0.0;
      for (const Vec3& p : mesh.positions)
        reach = std::max(reach, std::abs(p[up]));
      EXPECT_NEAR(reach, h + r, 1e-12 * r);
      EXPECT_LE(longest_edge(mesh), max_edge);
      const double error = relative_error(volume(mesh), kPi * r * r * 2 * h + 4.0 / 3.0 * kPi * r * r * r);
      EXPECT_LE(error, 0.03) << "up axis " << up << ", max_edge " << max_edge;
      if (previous_error > 0.0) {
        EXPECT_LT(error, previous_error / 2) << "up axis " << up;
      }
      previous_error = error;
      expect_within_support(*capsule, mesh, max_edge * max_edge / (2 * r));
    }
  }
}

// ---- cylinder, cone
// ------------------------------------------------------------------------------------------

TEST(ShapeMesh, CylindersKeepTheirExtentsWithEdgesRoundedByTheMargin) {
  const double radius = 0.1, half_height = 0.2, margin = 0.02;
  std::vector<std::unique_ptr<btCylinderShape>> cylinders;
  cylinders.push_back(std::make_unique<btCylinderShapeX>(btVector3(half_height, radius, radius)));
  cylinders.push_back(std::make_unique<btCylinderShape>(btVector3(radius, half_height, radius)));
  cylinders.push_back(std::make_unique<btCylinderShapeZ>(btVector3(radius, radius, half_height)));
  for (const auto& cylinder : cylinders) {
    cylinder->setMargin(margin);
    const int up = cylinder->getUpAxis();
    const Vec3 core = to_vec3(cylinder->getHalfExtentsWithoutMargin());
    const double m = cylinder->getMargin();
    const double a = core[up == 0 ? 1 : 0], h = core[up];
    EXPECT_NEAR(a + m, radius, bullet_tolerance(1e-15, radius));
    EXPECT_NEAR(h + m, half_height, bullet_tolerance(1e-15, half_height));
    double previous_error = 0.0;
    for (double max_edge : {radius / 5, radius / 10}) {
      const TriangleMesh mesh = shape_mesh(*cylinder, with_max_edge(max_edge));
      EXPECT_TRUE(closed_and_oriented(mesh)) << "up axis " << up;
      EXPECT_LE(worst_offset(mesh, up, rectangle(a, h), m), 1e-12 * radius) << "up axis " << up;
      const auto on_cap = [&](const Vec3& p) { return std::abs(std::abs(p[up]) - (h + m)) < 1e-12; };
      EXPECT_LE(longest_curved_edge(mesh, on_cap), max_edge) << "up axis " << up;
      const double error = relative_error(volume(mesh), rounded_cylinder_volume(a, h, m));
      EXPECT_LE(error, 0.03) << "up axis " << up << ", max_edge " << max_edge;
      if (previous_error > 0.0) {
        EXPECT_LT(error, previous_error / 2) << "up axis " << up;
      }
      previous_error = error;
      expect_within_support(*cylinder, mesh, max_edge * max_edge / (2 * m));
    }
  }
}

TEST(ShapeMesh, CylinderWithoutMarginIsSharp) {
  btCylinderShape cylinder(btVector3(0.1, 0.2, 0.1));
  cylinder.setMargin(0.0);
  cylinder.setLocalScaling(btVector3(1.5, 0.5, 1.5));  // radius 0.15, half height 0.1
  const double r = cylinder.getRadius(), h = cylinder.getHalfExtentsWithoutMargin().y();
  EXPECT_NEAR(r, 0.15, bullet_tolerance(1e-15, 0.15));
  EXPECT_NEAR(h, 0.1, bullet_tolerance(1e-15, 0.1));
  const TriangleMesh mesh = shape_mesh(cylinder, with_max_edge(0.01));
  EXPECT_TRUE(closed_and_oriented(mesh));
  EXPECT_LE(worst_offset(mesh, 1, rectangle(r, h), 0.0), 1e-12);
  EXPECT_LE(relative_error(volume(mesh), kPi * r * r * 2 * h), 0.01);
  expect_within_support(cylinder, mesh, 0.01 * 0.01 / (2 * r));
}

TEST(ShapeMesh, ConesAlongEachAxisGrowOutwardByTheMargin) {
  const double radius = 0.1, height = 0.3, margin = 0.02;
  std::vector<std::unique_ptr<btConeShape>> cones;
  cones.push_back(std::make_unique<btConeShapeX>(radius, height));
  cones.push_back(std::make_unique<btConeShape>(radius, height));
  cones.push_back(std::make_unique<btConeShapeZ>(radius, height));
  for (const auto& cone : cones) {
    cone->setMargin(margin);
    const int up = cone->getConeUpIndex();
    const double R = cone->getRadius(), H = cone->getHeight(), m = cone->getMargin();
    const std::vector<Eigen::Vector2d> triangle = {{-R, -H / 2}, {R, -H / 2}, {0.0, H / 2}};
    double previous_error = 0.0;
    for (double max_edge : {radius / 5, radius / 10}) {
      const TriangleMesh mesh = shape_mesh(*cone, with_max_edge(max_edge));
      EXPECT_TRUE(closed_and_oriented(mesh)) << "up axis " << up;
      EXPECT_LE(worst_offset(mesh, up, triangle, m), 1e-12 * radius) << "up axis " << up;
      const auto on_base = [&](const Vec3& p) { return std::abs(p[up] + H / 2 + m) < 1e-12; };
      EXPECT_LE(longest_curved_edge(mesh, on_base), max_edge) << "up axis " << up;
      const double error = relative_error(volume(mesh), rounded_cone_volume(R, H, m));
      EXPECT_LE(error, 0.03) << "up axis " << up << ", max_edge " << max_edge;
      if (previous_error > 0.0) {
        EXPECT_LT(error, previous_error / 2) << "up axis " << up;
      }
      previous_error = error;
      expect_within_support(*cone, mesh, max_edge * max_edge / (2 * m));
    }
  }
}

TEST(ShapeMesh, ConeWithoutMarginHasItsApexAndRimAndScaling) {
  btConeShape cone(0.1, 0.3);
  cone.setMargin(0.0);
  cone.setLocalScaling(btVector3(2.0, 0.5, 2.0));  // radius 0.2, height 0.15
  const double R = cone.getRadius(), H = cone.getHeight();
  EXPECT_NEAR(R, 0.2, bullet_tolerance(1e-15, 0.2));
  EXPECT_NEAR(H, 0.15, bullet_tolerance(1e-15, 0.15));
  const TriangleMesh mesh = shape_mesh(cone, with_max_edge(0.01));
  EXPECT_TRUE(closed_and_oriented(mesh));
  EXPECT_LE(worst_offset(mesh, 1, {{-R, -H / 2}, {R, -H / 2}, {0.0, H / 2}}, 0.0), 1e-12);
  EXPECT_EQ(mesh.positions.front(), Vec3(0.0, H / 2, 0.0));  // the apex
  EXPECT_LE(relative_error(volume(mesh), kPi * R * R * H / 3), 0.01);
}

// ---- convex hulls
// ------------------------------------------------------------------------------------------

/// A box of points with extra points inside it and on its faces and edges (which the hull drops).
btConvexHullShape box_of_points(const Vec3& half) {
  btConvexHullShape hull;
  for (int i = 0; i < 8; ++i) {
    hull.addPoint(btVector3((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                            (i & 4) ? half.z() : -half.z()),
                  false);
  }
  hull.addPoint(btVector3(0.0, 0.0, 0.0), false);
  hull.addPoint(btVector3(half.x(), 0.0, 0.0), false);                  // on a face
  hull.addPoint(btVector3(half.x(), half.y(), 0.3 * half.z()), false);  // on an edge
  hull.addPoint(btVector3(0.2 * half.x(), -0.5 * half.y(), 0.1 * half.z()), true);
  return hull;
}

double distance_to_box(const Vec3& p, const Vec3& half) {
  return (p.cwiseAbs() - half).cwiseMax(0.0).norm();
}

TEST(ShapeMesh, ConvexHullGrowsOutwardByItsDefaultMargin) {
  btConvexHullShape hull = box_of_points(Vec3(0.1, 0.05, 0.2));
  hull.setLocalScaling(btVector3(1.0, 2.0, 0.5));  // the box of half (0.1, 0.1, 0.1)
  const double m = hull.getMargin();
  EXPECT_NEAR(m, 0.04, bullet_tolerance(1e-15, 0.04));  // Bullet's default, outward
  const Vec3 half = to_vec3(hull.getScaledPoint(7));
  double previous_error = 0.0;
  for (double max_edge : {m / 2, m / 4}) {
    const TriangleMesh mesh = shape_mesh(hull, with_max_edge(max_edge));
    EXPECT_TRUE(closed_and_oriented(mesh));
    for (const Vec3& p : mesh.positions)
      ASSERT_NEAR(distance_to_box(p, half), m, 1e-12) << p.transpose();
    // Steiner: V + S m + pi (a + b + c) m^2 + 4/3 pi m^3 for a box of edges a, b, c.
    const Vec3 e = 2.0 * half;
    const double exact = e.prod() + 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x()) * m +
                         kPi * e.sum() * m * m + 4.0 / 3.0 * kPi * m * m * m;
    const double error = relative_error(volume(mesh), exact);
    EXPECT_LE(error, 0.01) << "max_edge " << max_edge;
    if (previous_error > 0.0) {
      EXPECT_LT(error, previous_error / 2);
    }
    previous_error = error;
    expect_within_support(hull, mesh, max_edge * max_edge / (2 * m));
  }
}

TEST(ShapeMesh, ConvexHullWithoutMarginIsTheHullOfItsScaledPoints) {
  btConvexHullShape hull = box_of_points(Vec3(0.1, 0.05, 0.2));
  hull.setMargin(0.0);
  hull.setLocalScaling(btVector3(1.0, 2.0, 0.5));
  const TriangleMesh mesh = shape_mesh(hull);
  EXPECT_TRUE(closed_and_oriented(mesh));
  EXPECT_EQ(mesh.positions.size(), 8u);  // the points inside, on a face and on an edge are dropped
  for (const Vec3& p : mesh.positions)
    EXPECT_NEAR(p.cwiseAbs().maxCoeff(), 0.1, bullet_tolerance(1e-15, 0.1)) << p.transpose();
  EXPECT_LE(relative_error(volume(mesh), 0.2 * 0.2 * 0.2), bullet_tolerance(1e-12, 1.0, 8));
}

TEST(ShapeMesh, FlatAndStraightHullsGrowIntoASlabAndACapsule) {
  // A rectangle 0.2 x 0.1 and a segment of length 0.3 (no volume of their own) with the default margin,
  // along the axes (where grid directions tie between their points) and tilted.
  const Vec3 tilted_y = Vec3(0.0, 1.0, 1.0).normalized();
  for (const Vec3& side : {Vec3(0.0, 0.0, 1.0), tilted_y}) {
    const Vec3 a(0.2, 0.0, 0.0), b = 0.1 * side;
    btConvexHullShape flat;
    for (const Vec3& p : {Vec3::Zero().eval(), a, (a + b).eval(), b})
      flat.addPoint(to_bt(p), true);
    const double m = flat.getMargin();
    const double max_edge = m / 4;
    const TriangleMesh slab = shape_mesh(flat, with_max_edge(max_edge));
    EXPECT_TRUE(closed_and_oriented(slab));
    // Steiner in 3D for a flat convex set: 2 A m + perimeter pi m^2 / 2 + 4/3 pi m^3.
    const double slab_volume = 2 * 0.02 * m + 0.6 * kPi * m * m / 2 + 4.0 / 3.0 * kPi * m * m * m;
    EXPECT_LE(relative_error(volume(slab), slab_volume), 0.01) << side.transpose();
    expect_within_support(flat, slab, max_edge * max_edge / (2 * m));
  }
  for (const Vec3& end : {Vec3(0.3, 0.0, 0.0), Vec3(0.1, 0.2, 0.2)}) {
    btConvexHullShape straight;
    straight.addPoint(btVector3(0.0, 0.0, 0.0), true);
    straight.addPoint(to_bt(end), true);
    const double m = straight.getMargin();
    const TriangleMesh capsule = shape_mesh(straight, with_max_edge(m / 4));
    EXPECT_TRUE(closed_and_oriented(capsule));
    const Vec3 stored = to_vec3(straight.getScaledPoint(1));
    for (const Vec3& p : capsule.positions) {
      const double s = std::clamp(p.dot(stored) / stored.squaredNorm(), 0.0, 1.0);
      ASSERT_NEAR((p - s * stored).norm(), m, 1e-12) << p.transpose();
    }
    const double exact = kPi * m * m * stored.norm() + 4.0 / 3.0 * kPi * m * m * m;
    EXPECT_LE(relative_error(volume(capsule), exact), 0.01) << end.transpose();
  }
}

TEST(ShapeMesh, IrregularConvexShapesStayWithinBulletsSupport) {
  // Points of a rough rock; the hull, its point cloud and its convex triangle mesh all grow by the margin.
  const std::vector<btVector3> rock = {{0.1, 0.0, 0.02},    {-0.07, 0.05, 0.0},  {0.0, -0.08, 0.03},
                                       {0.02, 0.03, 0.12},  {-0.01, 0.0, -0.09}, {0.05, 0.07, -0.04},
                                       {-0.06, -0.05, 0.06}};
  btConvexHullShape hull(&rock[0].x(), static_cast<int>(rock.size()), sizeof(btVector3));
  hull.setMargin(0.02);
  btConvexPointCloudShape cloud(const_cast<btVector3*>(rock.data()), static_cast<int>(rock.size()),
                                btVector3(1, 1, 1));
  cloud.setMargin(0.02);
  btTriangleMesh triangles;
  for (std::size_t i = 0; i + 2 < rock.size(); ++i)
    triangles.addTriangle(rock[i], rock[i + 1], rock[i + 2]);
  btConvexTriangleMeshShape convex_mesh(&triangles);
  convex_mesh.setMargin(0.02);
  const double max_edge = 0.01;
  for (const btConvexShape* shape :
       {static_cast<const btConvexShape*>(&hull), static_cast<const btConvexShape*>(&cloud),
        static_cast<const btConvexShape*>(&convex_mesh)}) {
    const TriangleMesh mesh = shape_mesh(*shape, with_max_edge(max_edge));
    EXPECT_TRUE(closed_and_oriented(mesh)) << shape->getName();
    EXPECT_GT(volume(mesh), 0.0) << shape->getName();
    expect_within_support(*shape, mesh, max_edge * max_edge / (2 * 0.02));
  }
}

TEST(ShapeMesh, MultiSphereOfTwoEqualSpheresIsACapsule) {
  const btVector3 centers[2] = {{0.0, -0.1, 0.0}, {0.0, 0.1, 0.0}};
  const btScalar radii[2] = {0.05, 0.05};
  btMultiSphereShape spheres(centers, radii, 2);
  const double r = 0.05, h = 0.1, max_edge = r / 5;
  const TriangleMesh mesh = shape_mesh(spheres, with_max_edge(max_edge));
  EXPECT_TRUE(closed_and_oriented(mesh));
  // Bullet's support runs in btScalar: vertices on the capsule to its rounding.
  EXPECT_LE(worst_offset(mesh, 1, {{0.0, -h}, {0.0, h}}, r), bullet_tolerance(1e-12, h + r, 16));
  EXPECT_LE(relative_error(volume(mesh), kPi * r * r * 2 * h + 4.0 / 3.0 * kPi * r * r * r), 0.03);
  expect_within_support(spheres, mesh, max_edge * max_edge / (2 * r));
}

TEST(ShapeMesh, UniformScalingScalesItsChildsMesh) {
  btConeShape cone(0.1, 0.2);
  btUniformScalingShape scaled(&cone, 2.5);
  const TriangleMesh mesh = shape_mesh(scaled, with_max_edge(0.02));
  const TriangleMesh child = shape_mesh(cone, with_max_edge(0.02 / 2.5));
  ASSERT_EQ(mesh.positions.size(), child.positions.size());
  EXPECT_EQ(mesh.triangles, child.triangles);
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    EXPECT_EQ(mesh.positions[i], 2.5 * child.positions[i]);
  EXPECT_LE(longest_curved_edge(mesh,
                                [&](const Vec3& p) {
                                  return std::abs(p.y() + 2.5 * (0.5 * cone.getHeight() + cone.getMargin())) <
                                         1e-12;
                                }),
            0.02);
  expect_within_support(scaled, mesh, 0.02 * 0.02 / (2 * 2.5 * cone.getMargin()));
}

// ---- compound ---------------------------------------------------------------------------------------------

TEST(ShapeMesh, CompoundPutsEachChildWhereItsTransformSays) {
  btBoxShape box(btVector3(0.1, 0.2, 0.3));
  btSphereShape sphere(0.05);
  btCompoundShape compound;
  const btTransform box_at(btQuaternion(btVector3(0, 0, 1), 0.5 * SIMD_PI), btVector3(1.0, 0.0, 0.0));
  const btTransform sphere_at(btQuaternion(btVector3(1, 1, 0).normalized(), 0.3), btVector3(0.0, 0.5, -0.2));
  compound.addChildShape(box_at, &box);
  compound.addChildShape(sphere_at, &sphere);
  const ShapeMeshOptions options = with_max_edge(0.01);
  const TriangleMesh mesh = shape_mesh(compound, options);
  const TriangleMesh box_mesh = shape_mesh(box, options);
  const TriangleMesh sphere_mesh = shape_mesh(sphere, options);
  ASSERT_EQ(mesh.positions.size(), box_mesh.positions.size() + sphere_mesh.positions.size());
  ASSERT_EQ(mesh.triangles.size(), box_mesh.triangles.size() + sphere_mesh.triangles.size());
  EXPECT_TRUE(closed_and_oriented(mesh));
  const double tolerance = bullet_tolerance(1e-15, 1.0, 8);
  std::size_t i = 0;
  for (const auto& [child, at] : {std::pair{&box_mesh, box_at}, std::pair{&sphere_mesh, sphere_at}}) {
    for (const Vec3& p : child->positions) {
      const Vec3 expected = to_vec3(at * to_bt(p));
      EXPECT_LE((mesh.positions[i] - expected).norm(), tolerance) << "vertex " << i;
      ++i;
    }
  }
  // The box turned a quarter about z sits at x = 1 with its 0.2 half extent along -x..x; the sphere about
  // its child origin.
  double box_min_x = 1e9, box_max_x = -1e9;
  for (std::size_t k = 0; k < 8; ++k) {
    box_min_x = std::min(box_min_x, mesh.positions[k].x());
    box_max_x = std::max(box_max_x, mesh.positions[k].x());
  }
  EXPECT_NEAR(box_min_x, 0.8, bullet_tolerance(1e-12, 1.0, 8));
  EXPECT_NEAR(box_max_x, 1.2, bullet_tolerance(1e-12, 1.0, 8));
  for (std::size_t k = 8; k < mesh.positions.size(); ++k)
    EXPECT_NEAR((mesh.positions[k] - Vec3(0.0, 0.5, -0.2)).norm(), 0.05, bullet_tolerance(1e-12, 1.0, 8));
  // Rotations stored in btScalar are orthonormal to Bullet's rounding.
  EXPECT_LE(relative_error(volume(mesh), volume(box_mesh) + volume(sphere_mesh)),
            bullet_tolerance(1e-12, 1.0, 8));
}

// ---- plane
// ---------------------------------------------------------------------------------------------------

TEST(ShapeMesh, TiltedPlaneIsASquareOfSmallCellsOnThePlane) {
  const btStaticPlaneShape plane(btVector3(1.0, 2.0, 3.0), 0.5);  // Bullet normalizes the normal
  const Vec3 n = to_vec3(plane.getPlaneNormal());
  const double c = plane.getPlaneConstant();
  ShapeMeshOptions options;
  options.plane_half_size = 1.0;
  options.plane_cell = 0.15;
  const TriangleMesh mesh = shape_mesh(plane, options);
  ASSERT_FALSE(mesh.triangles.empty());
  const Vec3 center = n * (c / n.squaredNorm());
  for (const Vec3& p : mesh.positions)
    ASSERT_NEAR(n.dot(p), c, 1e-12) << p.transpose();
  // A square of half side 1 about the point of the plane nearest the origin: area 4, corners at sqrt(2).
  EXPECT_NEAR(area(mesh), 4.0, 1e-12);
  double farthest = 0.0;
  for (const Vec3& p : mesh.positions)
    farthest = std::max(farthest, (p - center).norm());
  EXPECT_NEAR(farthest, std::sqrt(2.0), 1e-12);
  // Cells of at most plane_cell: each triangle's two legs; faces toward the normal.
  for (const Triangle& t : mesh.triangles) {
    double edges[3];
    for (int k = 0; k < 3; ++k)
      edges[k] = (mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm();
    std::sort(edges, edges + 3);
    EXPECT_LE(edges[1], options.plane_cell);
    const Vec3 normal = (mesh.positions[t[1]] - mesh.positions[t[0]])
                            .cross(mesh.positions[t[2]] - mesh.positions[t[0]])
                            .normalized();
    EXPECT_NEAR(normal.dot(n.normalized()), 1.0, 1e-12);
  }
}

// BulletRigidBodies meshes a plane's cells under the water: two cells apart and an L of three must lie on
// the plane, face the normal, cover a cell's area each and share the nodes of neighbouring cells.
TEST(ShapeMesh, PlaneCellsShareTheirNodesAndFaceTheNormal) {
  const btStaticPlaneShape plane(btVector3(1.0, 2.0, 3.0), 0.5);
  const Vec3 n = to_vec3(plane.getPlaneNormal());
  const PlaneFrame frame = plane_frame(plane);
  EXPECT_NEAR(frame.axis_u.cross(frame.axis_v).dot(n.normalized()), 1.0, 1e-12);
  const double cell = 0.25;
  const std::vector<PlaneCell> cells = {{-3, 7}, {-2, 7}, {-2, 8}, {40, -12}};
  const TriangleMesh mesh = plane_cells_mesh(frame, cell, cells);
  ASSERT_EQ(mesh.triangles.size(), 8u);
  // The L's 3 cells have 8 nodes, not 12; the lone cell 4.
  EXPECT_EQ(mesh.positions.size(), 12u);
  for (const Vec3& p : mesh.positions)
    EXPECT_NEAR(n.dot(p), plane.getPlaneConstant(), 1e-12) << p.transpose();
  EXPECT_NEAR(area(mesh), 4 * cell * cell, 1e-12);
  for (const Triangle& t : mesh.triangles) {
    const Vec3 normal = (mesh.positions[t[1]] - mesh.positions[t[0]])
                            .cross(mesh.positions[t[2]] - mesh.positions[t[0]])
                            .normalized();
    EXPECT_NEAR(normal.dot(n.normalized()), 1.0, 1e-12);
  }
  // Cell (40, -12) starts at origin + 40 cell axis_u - 12 cell axis_v.
  const Vec3 corner = frame.origin + 40 * cell * frame.axis_u - 12 * cell * frame.axis_v;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Vec3& p : mesh.positions)
    nearest = std::min(nearest, (p - corner).norm());
  EXPECT_LT(nearest, 1e-12);
  EXPECT_THROW(plane_cells_mesh(frame, 0.0, cells), SceneError);
}

// ---- heightfield ----------------------------------------------------------------------------------------

/// Every vertex is the expected grid point and every grid point a vertex; interior edges shared by two faces.
void expect_grid(const TriangleMesh& mesh, const std::vector<Vec3>& expected, int width, int length,
                 double tolerance) {
  ASSERT_EQ(mesh.positions.size(), expected.size());
  ASSERT_EQ(mesh.triangles.size(), static_cast<std::size_t>(2 * (width - 1) * (length - 1)));
  for (const Vec3& grid_point : expected) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3& p : mesh.positions)
      nearest = std::min(nearest, (p - grid_point).norm());
    EXPECT_LE(nearest, tolerance) << grid_point.transpose();
  }
  std::map<std::pair<Index, Index>, int> edges;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      ++edges[std::minmax(t[k], t[(k + 1) % 3])];
  int boundary = 0;
  for (const auto& [edge, count] : edges) {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_EQ(boundary, 2 * (width - 1) + 2 * (length - 1));
}

TEST(ShapeMesh, HeightfieldVerticesAreTheDataAboutBulletsCentredOrigin) {
  const int width = 5, length = 4;
  const double min_height = -1.0, max_height = 2.0;
  std::vector<float> heights(width * length);
  for (int j = 0; j < length; ++j)
    for (int i = 0; i < width; ++i)
      heights[j * width + i] = static_cast<float>(0.1 * i - 0.3 * j + 0.05 * i * j);
  btHeightfieldTerrainShape terrain(width, length, heights.data(), min_height, max_height, 1, false);
  const Vec3 scaling(0.5, 2.0, 0.25);
  terrain.setLocalScaling(to_bt(scaling));
  const TriangleMesh mesh = shape_mesh(terrain);
  // Bullet centres the grid's box: x and z about the grid's middle, heights about (min + max) / 2.
  std::vector<Vec3> expected;
  for (int j = 0; j < length; ++j) {
    for (int i = 0; i < width; ++i) {
      expected.push_back(Vec3(i - (width - 1) / 2.0, heights[j * width + i] - (min_height + max_height) / 2,
                              j - (length - 1) / 2.0)
                             .cwiseProduct(scaling));
    }
  }
  expect_grid(mesh, expected, width, length, bullet_tolerance(1e-15, 4.0));
}

/// A short height as Bullet scales it (in btScalar).
double as_bullet_height(short value, double scale) {
  return static_cast<double>(static_cast<btScalar>(value * static_cast<btScalar>(scale)));
}

TEST(ShapeMesh, HeightfieldOfShortsAlongZ) {
  const int width = 3, length = 6;
  const double scale = 0.01, min_height = -0.5, max_height = 1.5;
  std::vector<short> heights(width * length);
  for (int k = 0; k < width * length; ++k)
    heights[k] = static_cast<short>(7 * k - 20);
  btHeightfieldTerrainShape terrain(width, length, heights.data(), scale, min_height, max_height, 2, true);
  const TriangleMesh mesh = shape_mesh(terrain);
  std::vector<Vec3> expected;
  for (int j = 0; j < length; ++j) {
    for (int i = 0; i < width; ++i) {
      expected.emplace_back(i - (width - 1) / 2.0, j - (length - 1) / 2.0,
                            as_bullet_height(heights[j * width + i], scale) - (min_height + max_height) / 2);
    }
  }
  expect_grid(mesh, expected, width, length, bullet_tolerance(1e-15, 4.0));
}

// ---- triangle meshes
// ---------------------------------------------------------------------------------------

/// Two triangles of a unit square and one that repeats a vertex, in the given storage types.
template <class VertexScalar, class IndexType>
struct SquareArrays {
  std::vector<VertexScalar> vertices = {0, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1, 0.5, 0.25, 0.5};
  std::vector<IndexType> indices = {0, 2, 1, 0, 3, 2, 1, 1, 4};
  btTriangleIndexVertexArray array;

  SquareArrays(PHY_ScalarType vertex_type, PHY_ScalarType index_type) {
    btIndexedMesh part;
    part.m_numTriangles = 3;
    part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indices.data());
    part.m_triangleIndexStride = 3 * sizeof(IndexType);
    part.m_numVertices = 5;
    part.m_vertexBase = reinterpret_cast<const unsigned char*>(vertices.data());
    part.m_vertexStride = 3 * sizeof(VertexScalar);
    part.m_vertexType = vertex_type;
    part.m_indexType = index_type;
    array.addIndexedMesh(part, index_type);
  }
};

void expect_scaled_square(const TriangleMesh& mesh, const Vec3& scaling) {
  ASSERT_EQ(mesh.positions.size(), 5u);  // shared as stored, the unused one kept
  const Vec3 square[4] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(mesh.positions[i], square[i].cwiseProduct(scaling)) << "vertex " << i;
  ASSERT_EQ(mesh.triangles.size(), 2u);  // the face repeating vertex 1 dropped
  EXPECT_EQ(mesh.triangles[0], (Triangle{0, 2, 1}));
  EXPECT_EQ(mesh.triangles[1], (Triangle{0, 3, 2}));
}

TEST(ShapeMesh, TriangleMeshInEveryStorageTypeWithItsLocalScaling) {
  const Vec3 scaling(2.0, 3.0, 0.5);
  {
    SquareArrays<float, unsigned int> arrays(PHY_FLOAT, PHY_INTEGER);
    btBvhTriangleMeshShape shape(&arrays.array, true);
    shape.setLocalScaling(to_bt(scaling));
    expect_scaled_square(shape_mesh(shape), scaling);
  }
  {
    SquareArrays<double, unsigned short> arrays(PHY_DOUBLE, PHY_SHORT);
    btBvhTriangleMeshShape shape(&arrays.array, true);
    shape.setLocalScaling(to_bt(scaling));
    expect_scaled_square(shape_mesh(shape), scaling);
  }
  {
    SquareArrays<float, unsigned char> arrays(PHY_FLOAT, PHY_UCHAR);
    btMultimaterialTriangleMeshShape shape(&arrays.array, true);
    expect_scaled_square(shape_mesh(shape), Vec3(1, 1, 1));
  }
}

TEST(ShapeMesh, ScaledBvhTriangleMeshScalesItsChildsScaledTriangles) {
  SquareArrays<float, unsigned int> arrays(PHY_FLOAT, PHY_INTEGER);
  btBvhTriangleMeshShape child(&arrays.array, true);
  child.setLocalScaling(btVector3(2.0, 1.0, 1.0));
  btScaledBvhTriangleMeshShape scaled(&child, btVector3(0.5, 4.0, 3.0));
  expect_scaled_square(shape_mesh(scaled), Vec3(1.0, 4.0, 3.0));
}

TEST(ShapeMesh, EmptyShapeHasNoTriangles) {
  btEmptyShape empty;
  EXPECT_TRUE(is_supported_shape(empty));
  const TriangleMesh mesh = shape_mesh(empty);
  EXPECT_TRUE(mesh.positions.empty());
  EXPECT_TRUE(mesh.triangles.empty());
}

// ---- errors
// ---------------------------------------------------------------------------------------------------

/// A soft body's collision shape: a shape drench cannot mesh (its cloth is coupled as a cloth).
struct SoftBodyShape {
  btSoftBodyWorldInfo info;
  std::unique_ptr<btSoftBody> body{btSoftBodyHelpers::CreatePatch(
      info, btVector3(0, 0, 0), btVector3(1, 0, 0), btVector3(0, 0, 1), btVector3(1, 0, 1), 2, 2, 0, false)};
  const btCollisionShape& shape() const { return *body->getCollisionShape(); }
};

TEST(ShapeMesh, UnsupportedShapeIsNamedWithItsCompoundPath) {
  SoftBodyShape soft;
  EXPECT_FALSE(is_supported_shape(soft.shape()));
  EXPECT_TRUE(
      throws_containing<Error>([&] { shape_mesh(soft.shape()); },
                               {"SoftBody", "not supported", "btBoxShape", "btHeightfieldTerrainShape"}));

  btBoxShape box(btVector3(0.1, 0.1, 0.1));
  btSphereShape sphere(0.1);
  btCompoundShape inner;
  inner.addChildShape(btTransform::getIdentity(), &sphere);
  inner.addChildShape(btTransform::getIdentity(), const_cast<btCollisionShape*>(&soft.shape()));
  btCompoundShape outer;
  outer.addChildShape(btTransform::getIdentity(), &box);
  outer.addChildShape(btTransform::getIdentity(), &inner);
  EXPECT_FALSE(is_supported_shape(outer));
  EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(outer); },
                                       "btCompoundShape child 1: btCompoundShape child 1: SoftBody: "));
  btCompoundShape fine;
  fine.addChildShape(btTransform::getIdentity(), &box);
  fine.addChildShape(btTransform::getIdentity(), &sphere);
  EXPECT_TRUE(is_supported_shape(fine));
}

TEST(ShapeMesh, OptionsOutOfRangeAreNamedWithTheShape) {
  btSphereShape sphere(0.1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (double bad : {0.0, -0.01, nan, inf}) {
    ShapeMeshOptions o;
    o.max_edge = bad;
    EXPECT_TRUE(
        throws_containing<Error>([&] { shape_mesh(sphere, o); },
                                 {"SPHERE: ", "ShapeMeshOptions::max_edge must be > 0 and finite, got "}));
    o = {};
    o.plane_half_size = bad;
    EXPECT_TRUE(
        throws_containing<Error>([&] { shape_mesh(sphere, o); }, "ShapeMeshOptions::plane_half_size"));
    o = {};
    o.plane_cell = bad;
    EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(sphere, o); }, "ShapeMeshOptions::plane_cell"));
  }
}

TEST(ShapeMesh, MeshesTooFineForTheirShapeAreRefused) {
  btSphereShape sphere(1.0);
  EXPECT_TRUE(throws_containing<Error>(
      [&] { shape_mesh(sphere, with_max_edge(1e-4)); },
      {"SPHERE: ", "triangles at ShapeMeshOptions::max_edge 0.0001", "kMaxShapeMeshTriangles"}));
  const btStaticPlaneShape plane(btVector3(0, 1, 0), 0.0);
  ShapeMeshOptions o;
  o.plane_half_size = 100.0;
  o.plane_cell = 0.01;
  EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(plane, o); }, {"STATICPLANE: ", "plane_cell 0.01"}));
  // Facet counts past int: a multi-sphere of 1e7 m threw std::length_error, naming nothing.
  const btVector3 centre(0, 0, 0);
  const btScalar huge = 1e7;
  btMultiSphereShape spheres(&centre, &huge, 1);
  EXPECT_TRUE(throws_containing<Error>([&] { shape_mesh(spheres, {}); },
                                       {"MultiSphere: ", "max_edge 0.02", "kMaxShapeMeshTriangles"}));
  btConvexHullShape hull;
  for (int i = 0; i < 4; ++i)
    hull.addPoint(btVector3(i == 1, i == 2, i == 3));
  hull.setMargin(1e7);
  EXPECT_TRUE(
      throws_containing<Error>([&] { shape_mesh(hull, {}); }, {"Convex: ", "kMaxShapeMeshTriangles"}));
}

TEST(ShapeMesh, CylinderWhoseMarginExceedsItsExtentsIsRefused) {
  btCylinderShape cylinder(btVector3(0.01, 0.5, 0.01));
  cylinder.setMargin(0.05);  // Bullet keeps the extents and shrinks the core by the margin: a negative radius
  EXPECT_TRUE(throws_containing<Error>(
      [&] { shape_mesh(cylinder); }, {"CylinderY: ", "radius and half height without margin must be >= 0"}));
}

}  // namespace
}  // namespace drench::bullet
