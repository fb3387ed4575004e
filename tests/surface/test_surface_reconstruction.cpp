// The fluid surface of sec. 4: a closed mesh around a ball of particles, no crossing of a cloth the fluid
// rests on when contact-aware (and some without, so the count can fail), two surfaces for water on both
// sides of a cloth, and clear errors for bad input.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/surface/surface_reconstruction.hpp>

namespace drench {
namespace {

constexpr double kSpacing = 0.01;  // particle spacing (m)

/// Particles on a cubic lattice of kSpacing filling the box [lo, hi] (cell centres).
Vec3Array block(const Vec3& lo, const Vec3& hi) {
  Vec3Array p;
  for (double z = lo.z() + 0.5 * kSpacing; z < hi.z(); z += kSpacing)
    for (double y = lo.y() + 0.5 * kSpacing; y < hi.y(); y += kSpacing)
      for (double x = lo.x() + 0.5 * kSpacing; x < hi.x(); x += kSpacing)
        p.emplace_back(x, y, z);
  return p;
}

/// A flat square cloth in the plane y = height, n x n nodes over [-half, half]^2 in x and z.
struct Sheet {
  Vec3Array positions;
  std::vector<Triangle> triangles;
  Sheet(double height, double half, int n) {
    for (int k = 0; k < n; ++k)
      for (int i = 0; i < n; ++i)
        positions.emplace_back(-half + 2 * half * i / (n - 1), height, -half + 2 * half * k / (n - 1));
    for (int k = 0; k + 1 < n; ++k)
      for (int i = 0; i + 1 < n; ++i) {
        const Index a = k * n + i, b = a + 1, c = a + n, d = c + 1;
        triangles.push_back({a, c, b});
        triangles.push_back({b, c, d});
      }
  }
  std::vector<SurfaceObstacle> obstacles() const { return {SurfaceObstacle{&positions, &triangles}}; }
};

double signed_volume(const SurfaceMesh& m) {
  double v = 0.0;
  for (const Triangle& t : m.triangles)
    v += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6.0;
  return v;
}

/// Number of connected pieces of the mesh (triangles sharing a vertex are connected).
int pieces(const SurfaceMesh& m) {
  std::vector<Index> parent(m.positions.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](Index v) {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const Triangle& t : m.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::vector<bool> used(m.positions.size(), false);
  for (const Triangle& t : m.triangles)
    used[t[0]] = true;
  int count = 0;
  for (Index v = 0; v < parent.size(); ++v)
    if (used[v] && find(v) == v) ++count;
  return count;
}

TEST(TriangleGeometry, TriangleOverlapsCubeBySeparatingAxes) {
  const Vec3 centre = Vec3::Zero();
  // A large triangle through the cube's middle, whose corners are all outside it.
  EXPECT_TRUE(triangle_overlaps_cube(Vec3(-5, 0, -5), Vec3(5, 0, -5), Vec3(0, 0, 5), centre, 1.0));
  // The plane x + y + z = 2.9 cuts the cube's corner (1, 1, 1); x + y + z = 3.1 misses it, though the
  // triangle's box overlaps the cube: only the normal axis separates.
  const auto tilted = [&](double d) {
    return triangle_overlaps_cube(Vec3(d, 0, 0) + Vec3(-4, 2, 2), Vec3(d, 0, 0) + Vec3(2, -4, 2),
                                  Vec3(d, 0, 0) + Vec3(2, 2, -4), centre, 1.0);
  };
  EXPECT_TRUE(tilted(2.9));
  EXPECT_FALSE(tilted(3.1));
  EXPECT_FALSE(triangle_overlaps_cube(Vec3(2, 2, 2), Vec3(3, 2, 2), Vec3(2, 3, 2), centre, 1.0));
  // An edge passing by the corner on the outside: separated by an edge-cross axis only.
  EXPECT_FALSE(triangle_overlaps_cube(Vec3(3.5, -1, 0), Vec3(-1, 3.5, 0), Vec3(4, 4, 0), centre, 1.0));
}

class SurfaceOfABall : public testing::TestWithParam<SurfaceField> {};

TEST_P(SurfaceOfABall, IsAClosedOutwardMeshOfTheBallsVolume) {
  Vec3Array ball;
  for (const Vec3& p : block(Vec3::Constant(-0.1), Vec3::Constant(0.1)))
    if (p.norm() <= 0.1) ball.push_back(p);
  SurfaceSettings settings;
  settings.field = GetParam();
  SurfaceStats stats;
  const SurfaceMesh mesh = reconstruct_surface(ball, kSpacing, settings, {}, &stats);
  ASSERT_FALSE(mesh.triangles.empty());
  // Closed and consistently oriented: every directed edge appears once and its reverse once.
  std::map<std::pair<Index, Index>, int> edges;
  for (const Triangle& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, n] : edges) {
    ASSERT_EQ(n, 1) << "edge " << e.first << "-" << e.second << " used twice in one direction";
    ASSERT_EQ(edges.count({e.second, e.first}), 1u) << "edge " << e.first << "-" << e.second << " is open";
  }
  // The ball the particles fill: N spacing^3 of water.
  const double volume = static_cast<double>(ball.size()) * std::pow(kSpacing, 3);
  const double radius = std::cbrt(3.0 * volume / (4.0 * M_PI));
  EXPECT_NEAR(signed_volume(mesh), volume, 0.05 * volume) << "positive: the triangles face out";
  const double cell = settings.resolved_cell_size(kSpacing);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    ASSERT_NEAR(mesh.positions[v].norm(), radius, cell) << "vertex " << v;
    ASSERT_GT(mesh.normals[v].dot(mesh.positions[v].normalized()), 0.5) << "vertex " << v;
  }
  EXPECT_EQ(stats.nodes > 0, true);
}

INSTANTIATE_TEST_SUITE_P(Fields, SurfaceOfABall,
                         testing::Values(SurfaceField::ZHU_BRIDSON, SurfaceField::DENSITY),
                         [](const testing::TestParamInfo<SurfaceField>& param) {
                           return param.param == SurfaceField::ZHU_BRIDSON ? "ZhuBridson" : "Density";
                         });

TEST(Surface, ContactAwareSurfaceDoesNotCrossTheClothTheWaterRestsOn) {
  const Sheet cloth(0.0, 0.15, 31);
  // The lowest particles 1 mm above the cloth.
  const Vec3Array slab = block(Vec3(-0.05, 0.001 - 0.5 * kSpacing, -0.05), Vec3(0.05, 0.031, 0.05));
  SurfaceSettings aware;
  SurfaceSettings plain;
  plain.contact_aware = false;
  const SurfaceMesh with = reconstruct_surface(slab, kSpacing, aware, cloth.obstacles());
  const SurfaceMesh without = reconstruct_surface(slab, kSpacing, plain, cloth.obstacles());
  EXPECT_EQ(count_surface_intersections(with, cloth.obstacles()), 0u);
  EXPECT_GT(count_surface_intersections(without, cloth.obstacles()), 0u) << "the count must be able to fail";
  for (const Vec3& x : with.positions)
    ASSERT_GT(x.y(), 0.0) << "a vertex under the cloth";
}

TEST(Surface, WaterOnBothSidesOfAClothGivesTwoSurfaces) {
  const Sheet cloth(0.0, 0.15, 31);
  Vec3Array water = block(Vec3(-0.05, 0.001 - 0.5 * kSpacing, -0.05), Vec3(0.05, 0.021, 0.05));
  for (const Vec3& p : block(Vec3(-0.05, -0.021, -0.05), Vec3(0.05, -0.001 + 0.5 * kSpacing, 0.05)))
    water.push_back(p);
  SurfaceSettings aware;
  SurfaceSettings plain;
  plain.contact_aware = false;
  const SurfaceMesh two = reconstruct_surface(water, kSpacing, aware, cloth.obstacles());
  const SurfaceMesh one = reconstruct_surface(water, kSpacing, plain, cloth.obstacles());
  EXPECT_EQ(pieces(two), 2);
  EXPECT_EQ(count_surface_intersections(two, cloth.obstacles()), 0u);
  EXPECT_EQ(pieces(one), 1) << "without the cloth the two slabs merge into one blob";
}

TEST(Surface, BadInputIsNamed) {
  const Vec3Array ball = block(Vec3::Constant(-0.02), Vec3::Constant(0.02));
  SurfaceSettings s;
  s.cell_size = -0.001;
  EXPECT_THROW(
      {
        try {
          reconstruct_surface(ball, kSpacing, s, {});
        } catch (const SceneError& e) {
          EXPECT_NE(std::string(e.what()).find("surface.cell_size"), std::string::npos) << e.what();
          throw;
        }
      },
      SceneError);
  s.cell_size = std::nan("");
  EXPECT_THROW(reconstruct_surface(ball, kSpacing, s, {}), SceneError);
  Vec3Array bad = ball;
  bad[7].y() = std::nan("");
  try {
    reconstruct_surface(bad, kSpacing, SurfaceSettings{}, {});
    ADD_FAILURE() << "no error for a NaN particle";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("particle 7"), std::string::npos) << e.what();
  }
  Sheet cloth(0.0, 0.1, 3);
  cloth.triangles[1][2] = 99;
  try {
    reconstruct_surface(ball, kSpacing, SurfaceSettings{}, cloth.obstacles());
    ADD_FAILURE() << "no error for a triangle out of range";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1 names node 99"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(reconstruct_surface({}, kSpacing, SurfaceSettings{}, {}).triangles.empty());
}

}  // namespace
}  // namespace drench
