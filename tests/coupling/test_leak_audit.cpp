// The leak audit counts transversal crossings on the final motion, once per particle, and nothing else.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <drench/coupling/leak_audit.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

using test::grid_mesh;

/// One still triangle with legs of 1 m along x and z, in the plane y = 0.
ClothMesh still_right_triangle() {
  ClothMesh mesh;
  mesh.positions_t0 = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)};
  mesh.positions_t1 = mesh.positions_t0;
  mesh.inverse_masses = {0, 0, 0};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

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

// A cloth of small faces beside one face a hundred times larger (a table's top): the audit's grid files the
// large face in every cell it meets, and each (particle, face) pair is examined once. Every particle that
// crosses is counted once, pairs are the brute-force count of overlapping boxes, and a face over 4,096 cells
// is still seen.
TEST(LeakAudit, SmallAndHugeFacesTogetherAreEachAuditedOnce) {
  ClothMesh mesh = grid_mesh(11, 0.1, 0.0, 0.0);  // 200 faces of 1 cm
  const auto add_face = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const auto first = static_cast<Index>(mesh.positions_t0.size());
    for (const Vec3& x : {a, b, c}) {
      mesh.positions_t0.push_back(x);
      mesh.positions_t1.push_back(x);
      mesh.inverse_masses.push_back(0.0);
    }
    mesh.triangles.push_back({first, first + 1, first + 2});
  };
  add_face(Vec3(0.2, 0.0, 0.0), Vec3(0.2, 0.0, 1.0), Vec3(1.2, 0.0, 0.0));   // 1 m: 100 x 100 cells
  add_face(Vec3(-50, -0.5, -50), Vec3(-50, -0.5, 50), Vec3(50, -0.5, -50));  // 100 m: past 4,096 cells
  Vec3Array x0, x1;
  for (int i = 0; i < 40; ++i) {
    const double x = 0.005 + 0.03 * i;  // over the small faces, then over the large one
    x0.emplace_back(x, 0.004, 0.013 + 0.001 * i);
    x1.emplace_back(x, i % 3 == 0 ? -0.004 : 0.002, 0.013 + 0.001 * i);  // every third crosses
  }
  x0.emplace_back(-3.0, -0.4, -3.0);  // through the huge face only
  x1.emplace_back(-3.0, -0.6, -3.0);
  LeakAuditStats stats;
  std::vector<std::uint8_t> leaked;
  const std::uint64_t leaks = audit_leaks(x0, x1, mesh, stats, &leaked);
  std::uint64_t expected_leaks = 0;
  for (std::size_t p = 0; p < x0.size(); ++p) {
    // Over a face: the small grid (x < 0.1) or the large face (x - 0.2 + z < 1 beyond x = 0.2).
    const double x = x0[p].x(), z = x0[p].z();
    const bool over = x < 0.1 || (x > 0.2 && x - 0.2 + z < 1.0);
    const bool crossing = p == 40 || (p % 3 == 0 && over);
    EXPECT_EQ(leaked[p], crossing ? 1 : 0) << "particle " << p;
    expected_leaks += crossing ? 1 : 0;
  }
  EXPECT_EQ(leaks, expected_leaks);
  // The audit stops a particle's search at its first crossing, so only the particles that do not cross
  // give their full pair count; compare those.
  LeakAuditStats quiet;
  Vec3Array y0, y1;
  for (std::size_t p = 0; p < x0.size(); ++p) {
    if (leaked[p]) continue;
    y0.push_back(x0[p]);
    y1.push_back(x1[p]);
  }
  std::uint64_t quiet_pairs = 0;
  for (std::size_t p = 0; p < y0.size(); ++p) {
    const Vec3 lo = y0[p].cwiseMin(y1[p]), hi = y0[p].cwiseMax(y1[p]);
    for (const Triangle& t : mesh.triangles) {
      Vec3 tlo = mesh.positions_t0[t[0]], thi = tlo;
      for (const Index v : t) {
        tlo = tlo.cwiseMin(mesh.positions_t0[v]);
        thi = thi.cwiseMax(mesh.positions_t0[v]);
      }
      quiet_pairs += (hi.array() >= tlo.array()).all() && (thi.array() >= lo.array()).all() ? 1 : 0;
    }
  }
  EXPECT_EQ(audit_leaks(y0, y1, mesh, quiet), 0u);
  EXPECT_EQ(quiet.pairs, quiet_pairs) << "each overlapping pair examined once";
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

// A particle crossing a triangle's plane inside its box but beside it (past its long edge), the triangle
// still and tilting: no leak, decided without the exact reference (the in-plane edge test); through the
// triangle it is still one leak.
TEST(LeakAudit, DecidesACrossingBesideTheTriangleWithoutTheExactReference) {
  ClothMesh mesh = still_right_triangle();
  for (double tilt : {0.0, 0.02}) {
    mesh.positions_t1[2].y() = tilt;
    LeakAuditStats beside;
    EXPECT_EQ(audit_leaks(Vec3Array{Vec3(0.8, 0.05, 0.8)}, Vec3Array{Vec3(0.8, -0.05, 0.75)}, mesh, beside),
              0u);
    EXPECT_EQ(beside.pairs, 1u) << "tilt " << tilt;
    EXPECT_EQ(beside.exact_checks, 0u) << "tilt " << tilt;
    LeakAuditStats through;
    EXPECT_EQ(audit_leaks(Vec3Array{Vec3(0.3, 0.05, 0.3)}, Vec3Array{Vec3(0.3, -0.05, 0.25)}, mesh, through),
              1u)
        << "tilt " << tilt;
  }
}

// A particle whose path runs from beyond one edge of the triangle to beyond another, crossing the plane
// beside it, and one crossing the triangle on a slant: the audit's own tests decide neither (no one edge has
// the particle beyond it at both ends), the CCD filter decides both, without the exact reference.
TEST(LeakAudit, DecidesSlantingPathsWithoutTheExactReference) {
  ClothMesh mesh = still_right_triangle();
  for (double tilt : {0.0, 0.02}) {
    mesh.positions_t1[2].y() = tilt;
    // Past the corner at (1, 0, 0): in the plane near t = 5/12 at z < 0.
    LeakAuditStats beside;
    EXPECT_EQ(audit_leaks(Vec3Array{Vec3(0.5, 0.05, -0.3)}, Vec3Array{Vec3(1.3, -0.07, 0.25)}, mesh, beside),
              0u)
        << "tilt " << tilt;
    EXPECT_EQ(beside.pairs, 1u) << "tilt " << tilt;
    EXPECT_EQ(beside.exact_checks, 0u) << "tilt " << tilt;
    LeakAuditStats through;
    EXPECT_EQ(audit_leaks(Vec3Array{Vec3(0.2, 0.05, -0.1)}, Vec3Array{Vec3(0.4, -0.07, 0.5)}, mesh, through),
              1u)
        << "tilt " << tilt;
    EXPECT_EQ(through.exact_checks, 0u) << "tilt " << tilt;
  }
}

// A LeakAudit kept over the steps of a run files again only the faces that moved to other cells: over steps
// where a cloth waves above a still floor of larger faces, then shrinks to a tenth (a new cell size), then
// has a NaN node, it flags exactly the particles a fresh audit flags, with the same pair counts.
TEST(LeakAudit, KeptOverStepsFlagsWhatAFreshAuditFlags) {
  ClothMesh mesh = grid_mesh(9, 0.4, 0.05, 1.0);                    // 128 moving faces of 5 cm
  const ClothMesh floor = grid_mesh(5, 1.0, 0.0, 0.0, -0.3, -0.3);  // 32 still faces of 25 cm
  const auto cloth_nodes = static_cast<Index>(mesh.node_count());
  for (std::size_t v = 0; v < floor.node_count(); ++v) {
    mesh.positions_t0.push_back(floor.positions_t0[v]);
    mesh.positions_t1.push_back(floor.positions_t0[v]);
    mesh.inverse_masses.push_back(0.0);
  }
  for (const Triangle& t : floor.triangles)
    mesh.triangles.push_back({t[0] + cloth_nodes, t[1] + cloth_nodes, t[2] + cloth_nodes});
  const ClothMesh rest = mesh;
  LeakAudit kept;
  for (int step = 0; step < 8; ++step) {
    for (Index v = 0; v < cloth_nodes; ++v) {
      const Vec3& x = rest.positions_t0[v];
      const double scale = step >= 5 ? 0.1 : 1.0;
      mesh.positions_t0[v] = scale * x + Vec3(0, 0.01 * std::sin(7.0 * x.x() + step), 0);
      mesh.positions_t1[v] = scale * x + Vec3(0, 0.01 * std::sin(7.0 * x.x() + step + 1), 0);
    }
    if (step == 7) mesh.positions_t1[3].y() = std::numeric_limits<double>::quiet_NaN();
    Vec3Array x0, x1;
    for (int i = 0; i < 200; ++i) {
      const double x = -0.2 + 0.004 * i, z = 0.03 + 0.0017 * i;
      const double y = i % 2 ? 0.05 : 0.0;  // about the cloth, or about the floor
      x0.emplace_back(x, y + 0.02, z);
      x1.emplace_back(x, y + (i % 3 == 0 ? -0.02 : 0.015), z);  // every third goes through the plane
    }
    LeakAuditStats fresh_stats, kept_stats;
    std::vector<std::uint8_t> fresh_flags, kept_flags;
    const std::uint64_t fresh = audit_leaks(x0, x1, mesh, fresh_stats, &fresh_flags);
    EXPECT_EQ(kept.audit(x0, x1, mesh, kept_stats, &kept_flags), fresh) << "step " << step;
    EXPECT_GT(fresh, 0u) << "step " << step;
    EXPECT_EQ(kept_flags, fresh_flags) << "step " << step;
    EXPECT_EQ(kept_stats.pairs, fresh_stats.pairs) << "step " << step;
    // The same triangle named: the kept grid lists each cell's triangles in a fresh grid's order.
    EXPECT_EQ(kept_stats.leak_triangle, fresh_stats.leak_triangle) << "step " << step;
  }
}

// Between two steps the particles stay still and a face moves from where the last step left it to where the
// next starts it: a face that moves over a particle counts it once, named with the face's index in the
// whole mesh; a face that stays, or moves without passing a particle, counts nothing.
TEST(LeakAudit, AFaceThatJumpsOverAStillParticleBetweenStepsIsALeak) {
  const ClothMesh mesh = grid_mesh(3, 1.0, 0.0, 0.0);  // 8 triangles in y = 0
  const Vec3Array particles = {Vec3(0.8, 0.001, 0.8), Vec3(0.2, 0.001, 0.2), Vec3(0.3, 0.5, 0.3)};
  Vec3Array start = mesh.positions_t0;
  LeakAuditStats still;
  EXPECT_EQ(audit_face_jumps(particles, mesh.triangles, mesh.positions_t0, start, still), 0u);
  EXPECT_EQ(still.pairs, 0u);  // no face moved: none examined
  // The far corner node (1, 0, 1) rises 1 cm: under the first particle, where its weight is 0.2, its face
  // rises 2 mm, past the particle 1 mm above it.
  const std::size_t corner = 8;
  ASSERT_EQ(mesh.positions_t0[corner], Vec3(1, 0, 1));
  start[corner].y() += 0.01;
  LeakAuditStats jumped;
  std::vector<std::uint8_t> leaked;
  EXPECT_EQ(audit_face_jumps(particles, mesh.triangles, mesh.positions_t0, start, jumped, &leaked), 1u);
  EXPECT_EQ(jumped.leaks, 1u);
  EXPECT_EQ(jumped.jump_leaks, 1u);
  EXPECT_EQ(leaked, (std::vector<std::uint8_t>{1, 0, 0}));
  EXPECT_EQ(jumped.leak_particle, 0);
  ASSERT_GE(jumped.leak_triangle, 0);
  const Triangle& face = mesh.triangles[static_cast<std::size_t>(jumped.leak_triangle)];
  EXPECT_TRUE(face[0] == corner || face[1] == corner || face[2] == corner);
  EXPECT_THROW(audit_face_jumps(particles, mesh.triangles, mesh.positions_t0, Vec3Array(3), jumped),
               std::invalid_argument);
}

}  // namespace
}  // namespace drench
