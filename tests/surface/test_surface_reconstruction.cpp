// The fluid surface of sec. 4: a closed mesh around a ball of particles, no crossing of a cloth the fluid
// rests on when contact-aware (and some without, so the count can fail), two surfaces for water on both
// sides of a cloth, and clear errors for bad input.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>
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

/// The settings of each way of reconstructing: the two isotropic fields and Yu & Turk's anisotropic kernels.
enum class Method { ZHU_BRIDSON, DENSITY, ANISOTROPIC };

SurfaceSettings settings_of(Method m) {
  SurfaceSettings s;
  s.field = m == Method::ZHU_BRIDSON ? SurfaceField::ZHU_BRIDSON : SurfaceField::DENSITY;
  s.kernel = m == Method::ANISOTROPIC ? SurfaceKernel::ANISOTROPIC : SurfaceKernel::ISOTROPIC;
  return s;
}

std::string name_of(const testing::TestParamInfo<Method>& param) {
  return param.param == Method::ZHU_BRIDSON ? "ZhuBridson"
         : param.param == Method::DENSITY   ? "Density"
                                            : "Anisotropic";
}

class SurfaceOfABall : public testing::TestWithParam<Method> {};

TEST_P(SurfaceOfABall, IsAClosedOutwardMeshOfTheBallsVolume) {
  Vec3Array ball;
  for (const Vec3& p : block(Vec3::Constant(-0.1), Vec3::Constant(0.1)))
    if (p.norm() <= 0.1) ball.push_back(p);
  const SurfaceSettings settings = settings_of(GetParam());
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
                         testing::Values(Method::ZHU_BRIDSON, Method::DENSITY, Method::ANISOTROPIC), name_of);

class ContactAware : public testing::TestWithParam<Method> {};

TEST_P(ContactAware, SurfaceDoesNotCrossTheClothTheWaterRestsOn) {
  const Sheet cloth(0.0, 0.15, 31);
  // The lowest particles 1 mm above the cloth.
  const Vec3Array slab = block(Vec3(-0.05, 0.001 - 0.5 * kSpacing, -0.05), Vec3(0.05, 0.031, 0.05));
  const SurfaceSettings aware = settings_of(GetParam());
  SurfaceSettings plain = aware;
  plain.contact_aware = false;
  const SurfaceMesh with = reconstruct_surface(slab, kSpacing, aware, cloth.obstacles());
  const SurfaceMesh without = reconstruct_surface(slab, kSpacing, plain, cloth.obstacles());
  EXPECT_EQ(count_surface_intersections(with, cloth.obstacles()), 0u);
  EXPECT_GT(count_surface_intersections(without, cloth.obstacles()), 0u) << "the count must be able to fail";
  for (const Vec3& x : with.positions)
    ASSERT_GT(x.y(), 0.0) << "a vertex under the cloth";
}

TEST_P(ContactAware, WaterOnBothSidesOfAClothGivesTwoSurfaces) {
  const Sheet cloth(0.0, 0.15, 31);
  Vec3Array water = block(Vec3(-0.05, 0.001 - 0.5 * kSpacing, -0.05), Vec3(0.05, 0.021, 0.05));
  for (const Vec3& p : block(Vec3(-0.05, -0.021, -0.05), Vec3(0.05, -0.001 + 0.5 * kSpacing, 0.05)))
    water.push_back(p);
  const SurfaceSettings aware = settings_of(GetParam());
  SurfaceSettings plain = aware;
  plain.contact_aware = false;
  const SurfaceMesh two = reconstruct_surface(water, kSpacing, aware, cloth.obstacles());
  const SurfaceMesh one = reconstruct_surface(water, kSpacing, plain, cloth.obstacles());
  EXPECT_EQ(pieces(two), 2);
  EXPECT_EQ(count_surface_intersections(two, cloth.obstacles()), 0u);
  EXPECT_EQ(pieces(one), 1) << "without the cloth the two slabs merge into one blob";
}

/// Fig. 8's V: two planes meeting along the z axis at 90 degrees, opening upwards, each `size` wide from the
/// fold and 2 size long in z, in n x n cells.
struct VPlane {
  Vec3Array positions;
  std::vector<Triangle> triangles;
  VPlane(double size, int n) {
    for (int side = 0; side < 2; ++side) {
      const Vec3 along = Vec3(side == 0 ? -1.0 : 1.0, 1.0, 0.0).normalized();
      const Index first = static_cast<Index>(positions.size());
      for (int k = 0; k <= n; ++k)
        for (int i = 0; i <= n; ++i)
          positions.push_back(along * size * i / n + Vec3(0, 0, -size + 2.0 * size * k / n));
      for (int k = 0; k < n; ++k)
        for (int i = 0; i < n; ++i) {
          const Index a = first + k * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
          triangles.push_back({a, b, c});
          triangles.push_back({b, d, c});
        }
    }
  }
  std::vector<SurfaceObstacle> obstacles() const { return {SurfaceObstacle{&positions, &triangles}}; }
};

TEST_P(ContactAware, SurfaceDoesNotCrossTheV) {
  const VPlane v(0.1, 10);
  // Water in the fold, its particles at least 1 mm off both planes, and a sheet one particle thick under the
  // right plane, 1 mm below it: a kernel that reached through the V would make the two surfaces meet there.
  Vec3Array water;
  for (const Vec3& p : block(Vec3(-0.05, 0.0, -0.04), Vec3(0.05, 0.05, 0.04)))
    if (p.y() - std::abs(p.x()) >= 0.001 * std::sqrt(2.0)) water.push_back(p);
  const Vec3 normal = Vec3(-1, 1, 0).normalized();  // of the right plane, into the fold
  for (double u = 0.01; u < 0.09; u += kSpacing)
    for (double z = -0.04; z < 0.04; z += kSpacing)
      water.push_back(Vec3(1, 1, 0).normalized() * u + Vec3(0, 0, z) - 0.001 * normal);
  const SurfaceSettings aware = settings_of(GetParam());
  SurfaceSettings plain = aware;
  plain.contact_aware = false;
  const SurfaceMesh with = reconstruct_surface(water, kSpacing, aware, v.obstacles());
  ASSERT_FALSE(with.triangles.empty());
  EXPECT_EQ(count_surface_intersections(with, v.obstacles()), 0u);
  EXPECT_GT(
      count_surface_intersections(reconstruct_surface(water, kSpacing, plain, v.obstacles()), v.obstacles()),
      0u)
      << "the count must be able to fail";
}

INSTANTIATE_TEST_SUITE_P(Fields, ContactAware,
                         testing::Values(Method::ZHU_BRIDSON, Method::DENSITY, Method::ANISOTROPIC), name_of);

/// A sheet one particle thick in the plane y = 0 (on a layer of grid nodes), n x n particles `pitch` apart.
Vec3Array flat_sheet(int n, double pitch) {
  Vec3Array p;
  for (int k = 0; k < n; ++k)
    for (int i = 0; i < n; ++i)
      p.emplace_back((i - 0.5 * (n - 1)) * pitch, 0.0, (k - 0.5 * (n - 1)) * pitch);
  return p;
}

TEST(Anisotropic, ThinSheetIsOneSheetWhereIsotropicKernelsBreakIt) {
  // Spread to 2.4 spacings, as the jet's sheet thins on the V: no isotropic kernel of radius 2 spacings
  // spans the gap (the density field's midpoint between two particles is 2 (1 - 0.36)^3 = 0.52 < 0.6).
  // Each particle has 4 (corner) to 9 neighbours within r_i = 4 spacings, fewer than Yu & Turk's N_eps =
  // 25, which would leave it isotropic: the test asks for 4.
  const Vec3Array sheet = flat_sheet(12, 2.4 * kSpacing);
  SurfaceSettings anisotropic = settings_of(Method::ANISOTROPIC);
  anisotropic.min_neighbours = 4;
  SurfaceStats stats;
  const SurfaceMesh one = reconstruct_surface(sheet, kSpacing, anisotropic, {}, &stats);
  EXPECT_EQ(stats.anisotropic, sheet.size());
  EXPECT_EQ(pieces(one), 1);
  // Flat: every vertex within the thickness of the flattened kernels (k_r = 4: a quarter of the long axis).
  for (const Vec3& x : one.positions)
    ASSERT_LT(std::abs(x.y()), kSpacing) << "vertex at y = " << x.y();
  const SurfaceMesh beads = reconstruct_surface(sheet, kSpacing, settings_of(Method::DENSITY), {});
  EXPECT_EQ(pieces(beads), static_cast<int>(sheet.size())) << "isotropic: one bead per particle";
}

double area(const SurfaceMesh& m) {
  double a = 0.0;
  for (const Triangle& t : m.triangles)
    a += 0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
  return a;
}

TEST(Anisotropic, TiltedThinSheetIsTheSheetTurned) {
  // The flat sheet of the test above turned off the grid's axes (35 degrees about x, then 20 about z): its
  // flattened kernels are tilted ellipsoids, spread over rows of nodes their supports cross obliquely. The
  // surface does not depend on how the sheet lies on the grid: one sheet as thin, and its area (both
  // faces) that of the sheet lying on the grid within 1% (the grid's cells meet the sheet differently;
  // measured 0.03%).
  const Vec3Array flat = flat_sheet(12, 2.4 * kSpacing);
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(20.0 * M_PI / 180.0, Vec3::UnitZ()) *
                                Eigen::AngleAxisd(35.0 * M_PI / 180.0, Vec3::UnitX()))
                                   .toRotationMatrix();
  Vec3Array tilted;
  for (const Vec3& p : flat)
    tilted.push_back(turn * p);
  SurfaceSettings anisotropic = settings_of(Method::ANISOTROPIC);
  anisotropic.min_neighbours = 4;
  const SurfaceMesh lying = reconstruct_surface(flat, kSpacing, anisotropic, {});
  SurfaceStats stats;
  const SurfaceMesh turned = reconstruct_surface(tilted, kSpacing, anisotropic, {}, &stats);
  EXPECT_EQ(stats.anisotropic, tilted.size());
  EXPECT_EQ(pieces(turned), 1);
  const Vec3 normal = turn * Vec3::UnitY();
  for (const Vec3& x : turned.positions)
    ASSERT_LT(std::abs(normal.dot(x)), kSpacing) << "vertex " << x.transpose() << " off the sheet";
  EXPECT_NEAR(area(turned), area(lying), 0.01 * area(lying));
}

TEST(Anisotropic, RestingBlockKeepsTheIsotropicVolume) {
  // 20 x 8 x 20 particles, a block not used to choose the level (the ball was).
  const Vec3Array water = block(Vec3(-0.1, 0.0, -0.1), Vec3(0.1, 0.08, 0.1));
  const double isotropic =
      signed_volume(reconstruct_surface(water, kSpacing, settings_of(Method::DENSITY), {}));
  const double anisotropic =
      signed_volume(reconstruct_surface(water, kSpacing, settings_of(Method::ANISOTROPIC), {}));
  // 3%: the block's edges and corners, which the level was not fitted to, round off differently.
  EXPECT_NEAR(anisotropic, isotropic, 0.03 * isotropic);
}

TEST(Anisotropic, SameMeshForAnyThreadCount) {
  // The V's water with its sheet under one plane: kernels near faces, occluded neighbours, kept centres.
  const VPlane v(0.1, 10);
  Vec3Array water;
  for (const Vec3& p : block(Vec3(-0.05, 0.0, -0.04), Vec3(0.05, 0.05, 0.04)))
    if (p.y() - std::abs(p.x()) >= 0.001 * std::sqrt(2.0)) water.push_back(p);
  const int before = thread_count();
  set_thread_count(1);
  const SurfaceMesh one =
      reconstruct_surface(water, kSpacing, settings_of(Method::ANISOTROPIC), v.obstacles());
  set_thread_count(3);
  const SurfaceMesh three =
      reconstruct_surface(water, kSpacing, settings_of(Method::ANISOTROPIC), v.obstacles());
  set_thread_count(before);
  ASSERT_FALSE(one.triangles.empty());
  EXPECT_EQ(one.triangles, three.triangles);
  EXPECT_EQ(one.positions, three.positions) << "bit for bit";
}

class ContactOffset : public testing::TestWithParam<std::tuple<Method, double>> {};

TEST_P(ContactOffset, SurfaceKeepsTheOffsetFromTheCloth) {
  // The bound: a node within contact_offset of a face is outside, so each vertex lies on (OpenVDB: is the
  // mean of) crossings of grid edges that start at an inside node, at least offset from the plane of a flat
  // cloth, and end at most one cell nearer: the signed distance to the plane is linear along an edge and
  // its mean is the mean's, so every vertex is at least offset - cell from the cloth.
  const auto [method, offset_in_cells] = GetParam();
  // The cloth between two layers of grid nodes (at 0.26 cells), so that each offset resets its own layers.
  const double height = 0.0013;
  const Sheet cloth(height, 0.15, 31);
  const Vec3Array slab =
      block(Vec3(-0.05, height + 0.001 - 0.5 * kSpacing, -0.05), Vec3(0.05, height + 0.031, 0.05));
  SurfaceSettings settings = settings_of(method);
  const double cell = settings.resolved_cell_size(kSpacing);
  settings.contact_offset = offset_in_cells * cell;
  const SurfaceMesh mesh = reconstruct_surface(slab, kSpacing, settings, cloth.obstacles());
  ASSERT_FALSE(mesh.triangles.empty());
  double lowest = std::numeric_limits<double>::infinity();
  for (const Vec3& x : mesh.positions)
    lowest = std::min(lowest, x.y() - height);
  EXPECT_GE(lowest, settings.contact_offset - cell - 1e-9);
  // And the offset is what holds it there: the water reaches the cloth (its lowest particles 1 mm above),
  // so the surface comes within a cell and a half of the offset, or of one cell below that, where the nodes
  // of the cells the face passes through (within a cell of it on every axis) are what is outside.
  EXPECT_LE(lowest, std::max(settings.contact_offset, cell) + 1.5 * cell);
  EXPECT_EQ(count_surface_intersections(mesh, cloth.obstacles()), 0u);
}

INSTANTIATE_TEST_SUITE_P(Range, ContactOffset,
                         testing::Combine(testing::Values(Method::ZHU_BRIDSON, Method::ANISOTROPIC),
                                          testing::Values(0.0, 0.5, 1.0, 1.8, 2.0, 3.0)),
                         [](const testing::TestParamInfo<std::tuple<Method, double>>& param) {
                           return name_of(testing::TestParamInfo<Method>(std::get<0>(param.param), 0)) + "_" +
                                  std::to_string(
                                      static_cast<int>(std::lround(10 * std::get<1>(param.param)))) +
                                  "TenthsOfACell";
                         });

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
  SurfaceSettings aniso = settings_of(Method::ANISOTROPIC);
  aniso.field = SurfaceField::ZHU_BRIDSON;
  try {
    reconstruct_surface(ball, kSpacing, aniso, {});
    ADD_FAILURE() << "no error for the anisotropic kernel in the Zhu-Bridson field";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("surface.field"), std::string::npos) << e.what();
  }
  aniso = settings_of(Method::ANISOTROPIC);
  aniso.smoothing = 1.5;
  try {
    reconstruct_surface(ball, kSpacing, aniso, {});
    ADD_FAILURE() << "no error for smoothing 1.5";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("surface.smoothing"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace drench
