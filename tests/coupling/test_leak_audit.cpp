// The leak audit counts transversal crossings on the final motion, once per particle, and nothing else.

#include <gtest/gtest.h>

#include <drench/coupling/leak_audit.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

using test::grid_mesh;

std::uint64_t leaks_of(const Vec3& start, const Vec3& end, const ClothMesh& mesh) {
  LeakAuditStats stats;
  return audit_leaks(Vec3Array{start}, Vec3Array{end}, mesh, stats);
}

TEST(LeakAudit, CountsAParticleForcedThroughATriangleOnce) {
  EXPECT_EQ(leaks_of(Vec3(0.3, 0.05, 0.2), Vec3(0.3, -0.05, 0.2), grid_mesh(2, 1.0, 0.0, 0.0)), 1u);
}

TEST(LeakAudit, CountsACrossingThroughASharedEdgeOnce) {
  EXPECT_EQ(leaks_of(Vec3(0.5, 0.05, 0.5), Vec3(0.5, -0.05, 0.5), grid_mesh(2, 1.0, 0.0, 0.0)), 1u);
}

TEST(LeakAudit, CountsACrossingThroughAVertexOnce) {
  EXPECT_EQ(leaks_of(Vec3(0.5, 0.05, 0.5), Vec3(0.5, -0.05, 0.5), grid_mesh(3, 1.0, 0.0, 0.0)), 1u);
}

TEST(LeakAudit, CountsEveryParticleThatCrosses) {
  const ClothMesh mesh = grid_mesh(5, 1.0, 0.0, 0.0);
  Vec3Array x0, x1;
  for (int i = 0; i < 10; ++i) {
    x0.emplace_back(0.05 + 0.09 * i, 0.01, 0.37);
    x1.emplace_back(0.05 + 0.09 * i, i % 2 ? -0.01 : 0.005, 0.37);  // odd ones cross
  }
  LeakAuditStats stats;
  std::vector<std::uint8_t> leaked;
  EXPECT_EQ(audit_leaks(x0, x1, mesh, stats, &leaked), 5u);
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(leaked[static_cast<std::size_t>(i)], i % 2) << i;
}

TEST(LeakAudit, DoesNotCountTouchingTheCloth) {
  // Ends exactly on the triangle, then (next step) starts on it and goes back up.
  const ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 0.0);
  EXPECT_EQ(leaks_of(Vec3(0.3, 0.05, 0.2), Vec3(0.3, 0.0, 0.2), mesh), 0u);
  EXPECT_EQ(leaks_of(Vec3(0.3, 0.0, 0.2), Vec3(0.3, 0.05, 0.2), mesh), 0u);
}

TEST(LeakAudit, DoesNotCountATangentialTouchAndReturn) {
  // Triangle (0,0,0), (1,0,0), (0,1,z) tilting with z: 1 -> -1; the point's path makes eq. 6 equal
  // 2 (t - 1/2)^2: it touches the triangle at t = 1/2 and stays on its side.
  ClothMesh mesh;
  mesh.positions_t0 = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 1)};
  mesh.positions_t1 = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, -1)};
  mesh.inverse_masses = {0, 0, 0};
  mesh.triangles = {{0, 1, 2}};
  EXPECT_EQ(leaks_of(Vec3(0.1, 0.25, 0.75), Vec3(0.1, 1.25, -0.75), mesh), 0u);
}

TEST(LeakAudit, DoesNotCountCrossingThePlaneBesideTheTriangle) {
  EXPECT_EQ(leaks_of(Vec3(1.2, 0.05, 0.5), Vec3(1.2, -0.05, 0.5), grid_mesh(2, 1.0, 0.0, 0.0)), 0u);
}

TEST(LeakAudit, CountsACrossingThroughAMovingTriangle) {
  // The particle is still; the cloth sweeps up through it.
  ClothMesh mesh = grid_mesh(2, 1.0, -0.01, 1.0);
  for (Vec3& x : mesh.positions_t1)
    x.y() = 0.01;
  EXPECT_EQ(leaks_of(Vec3(0.3, 0.0, 0.3), Vec3(0.3, 0.0, 0.3), mesh), 1u);
}

}  // namespace
}  // namespace drench
