// Broad phases return exactly the brute-force set of (particle, triangle) pairs whose swept boxes overlap.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>

#include <drench/ccd/point_triangle_ccd.hpp>
#include <drench/common/parallel.hpp>
#include <drench/coupling/broad_phase.hpp>
#include <drench/coupling/cloth_obstacle.hpp>
#include <drench/coupling/coupler_stages.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

void expect_same_pairs_as_brute_force(BroadPhaseKind kind) {
  ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vec3& x : mesh.positions_t1)
    x += 0.01 * Vec3(u(rng), u(rng), u(rng));
  test::Particles particles;
  for (int k = 0; k < 3000; ++k) {
    const Vec3 x(0.35 * u(rng) + 0.15, 0.02 * u(rng), 0.35 * u(rng) + 0.15);
    particles.add(x, Vec3(u(rng), 3 * u(rng), u(rng)), 0.004, 1e-4);
  }
  particles.add(Vec3(-5, 0, 0), Vec3(1e4, 0, 0), 0.001, 1e-4);  // sweeps across the whole cloth in one step
  std::vector<std::pair<Index, Index>> expected, got;
  for (double margin : {0.0, 0.001, 0.02}) {
    find_pairs_brute_force(particles.x0, particles.x1, mesh, margin, expected);
    make_broad_phase(kind)->find_pairs(particles.x0, particles.x1, mesh, margin, nullptr, got);
    ASSERT_GT(expected.size(), 100u);
    EXPECT_EQ(got, expected) << "margin " << margin;
  }
}

TEST(BroadPhase, GridFindsExactlyTheBruteForcePairs) {
  expect_same_pairs_as_brute_force(BroadPhaseKind::GRID);
}

TEST(BroadPhase, FclFindsExactlyTheBruteForcePairs) {
  expect_same_pairs_as_brute_force(BroadPhaseKind::FCL);
}

// A query's few triangles, sorted in place with repeats dropped: the same list as std::sort and std::unique
// for every length the insertion sort takes (a particle's box in several cells sees a face several times).
TEST(BroadPhase, SortsAFewTrianglesAsStdSortAndUnique) {
  std::mt19937_64 rng(17);
  for (int round = 0; round < 2000; ++round) {
    std::vector<Index> hits(1 + round % 16);
    std::uniform_int_distribution<Index> pick(0, round % 3 == 0 ? 3 : 40);
    for (Index& t : hits)
      t = pick(rng);
    std::vector<Index> expected = hits;
    std::sort(expected.begin(), expected.end());
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
    sort_unique_few(hits);
    ASSERT_EQ(hits, expected) << "round " << round;
  }
}

// One object kept over steps, as the coupler keeps it (the FCL tree is refitted, not rebuilt), with the
// `only` flags, at 1 and 2 threads: still exactly the brute-force pairs of the flagged particles.
TEST(BroadPhase, ReusedOverMovingStepsMatchesBruteForceAtAnyThreadCount) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  test::Particles particles;
  for (int k = 0; k < 3000; ++k)
    particles.add(Vec3(0.35 * u(rng) + 0.15, 0.02 * u(rng), 0.35 * u(rng) + 0.15),
                  Vec3(u(rng), u(rng), u(rng)), 0.003, 1e-4);
  std::vector<std::uint8_t> only(particles.x0.size());
  for (auto& flag : only)
    flag = u(rng) > 0.0 ? 1 : 0;
  const int threads = thread_count();
  for (BroadPhaseKind kind : {BroadPhaseKind::GRID, BroadPhaseKind::FCL}) {
    const std::unique_ptr<TriangleBroadPhase> broad_phase = make_broad_phase(kind);
    ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
    std::vector<std::pair<Index, Index>> expected, got;
    for (int step = 0; step < 6; ++step) {
      mesh.positions_t0 = mesh.positions_t1;
      for (Vec3& x : mesh.positions_t1)
        x += 0.01 * Vec3(u(rng), u(rng), u(rng));
      const double margin = 0.002 * (step % 3);
      find_pairs_brute_force(particles.x0, particles.x1, mesh, margin, expected);
      expected.erase(std::remove_if(expected.begin(), expected.end(),
                                    [&](const auto& pair) { return !only[pair.first]; }),
                     expected.end());
      ASSERT_GT(expected.size(), 100u);
      set_thread_count(1 + step % 2);
      broad_phase->find_pairs(particles.x0, particles.x1, mesh, margin, &only, got);
      set_thread_count(threads);
      EXPECT_EQ(got, expected) << "step " << step << ", broad phase " << static_cast<int>(kind);
    }
  }
}

// The triangle boxes are kept while the cloth and the margin stay the same (TriangleBoxKey): queried again
// with other particles it must still be exact, and any change (the margin, one node moved by 1 mm, one
// triangle's nodes) must be seen.
TEST(BroadPhase, KeepsItsTriangleBoxesOnlyWhileClothAndMarginStayTheSame) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random_particles = [&] {
    test::Particles particles;
    for (int k = 0; k < 2000; ++k)
      particles.add(Vec3(0.35 * u(rng) + 0.15, 0.01 * u(rng), 0.35 * u(rng) + 0.15),
                    Vec3(u(rng), u(rng), u(rng)), 0.003, 1e-4);
    return particles;
  };
  for (BroadPhaseKind kind : {BroadPhaseKind::GRID, BroadPhaseKind::FCL}) {
    const std::unique_ptr<TriangleBroadPhase> broad_phase = make_broad_phase(kind);
    ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
    std::vector<std::pair<Index, Index>> expected, got;
    const auto check = [&](const test::Particles& particles, double margin, const char* what) {
      find_pairs_brute_force(particles.x0, particles.x1, mesh, margin, expected);
      broad_phase->find_pairs(particles.x0, particles.x1, mesh, margin, nullptr, got);
      EXPECT_EQ(got, expected) << what << ", broad phase " << static_cast<int>(kind);
    };
    const test::Particles first = random_particles();
    check(first, 0.001, "first call");
    check(random_particles(), 0.001, "same cloth, other particles");
    check(first, 0.004, "margin changed");
    mesh.positions_t1[220] += Vec3(0.0, 0.001, 0.0);
    check(first, 0.004, "one node moved at the end of the step");
    mesh.positions_t0[100] += Vec3(0.0, -0.001, 0.0);
    check(first, 0.004, "one node moved at the start of the step");
    std::swap(mesh.triangles[7], mesh.triangles[300]);
    check(first, 0.004, "two triangles swapped");
  }
}

// The grid keeps its bins across calls and rebins only the triangles whose box now covers other cells (a
// game level's ground never moves, a cloth moves by a part of a cell per step): with most of the mesh still
// and a few nodes moving by up to 3 cm, a triangle's nodes swapped, a NaN node and back, the whole mesh
// scaled by 3 (a new cell size), then every node moved by up to 2 mm (most triangles keep their cells, their
// boxes all change), it must stay exactly the brute-force set.
TEST(BroadPhase, GridRebinningOnlyTrianglesThatChangeCellsMatchesBruteForce) {
  for (BroadPhaseKind kind : {BroadPhaseKind::GRID}) {
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    test::Particles particles;
    for (int k = 0; k < 2000; ++k)
      particles.add(Vec3(0.35 * u(rng) + 0.15, 0.01 * u(rng), 0.35 * u(rng) + 0.15),
                    Vec3(u(rng), u(rng), u(rng)), 0.003, 1e-4);
    const std::unique_ptr<TriangleBroadPhase> broad_phase = make_broad_phase(kind);
    ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
    std::vector<std::pair<Index, Index>> expected, got;
    const auto check = [&](const char* what) {
      find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.002, expected);
      broad_phase->find_pairs(particles.x0, particles.x1, mesh, 0.002, nullptr, got);
      ASSERT_GT(expected.size(), 100u) << what;
      EXPECT_EQ(got, expected) << what << ", broad phase " << static_cast<int>(kind);
    };
    check("first call");
    for (int step = 0; step < 12; ++step) {
      for (int k = 0; k < 10; ++k) {  // 10 of 441 nodes moved by up to 3 cm: most triangles keep their box
        const auto node = static_cast<std::size_t>(rng() % mesh.positions_t1.size());
        mesh.positions_t0[node] = mesh.positions_t1[node];
        mesh.positions_t1[node] += 0.03 * Vec3(u(rng), u(rng), u(rng));
      }
      check("a few nodes moved");
    }
    std::swap(mesh.triangles[3], mesh.triangles[500]);
    check("two triangles swapped");
    const Vec3 kept = mesh.positions_t1[50];
    mesh.positions_t1[50] = Vec3(std::nan(""), 0.0, 0.0);
    find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.002, expected);
    broad_phase->find_pairs(particles.x0, particles.x1, mesh, 0.002, nullptr, got);
    EXPECT_EQ(got, expected) << "a NaN node, broad phase " << static_cast<int>(kind);
    mesh.positions_t1[50] = kept;
    check("the NaN node restored");
    for (Vec3& x : mesh.positions_t0)
      x *= 3.0;
    for (Vec3& x : mesh.positions_t1)
      x *= 3.0;
    check("scaled by 3: a new cell size");
    for (int step = 0; step < 3; ++step) {
      mesh.positions_t0 = mesh.positions_t1;
      for (Vec3& x : mesh.positions_t1)
        x += 0.002 * Vec3(u(rng), u(rng), u(rng));
      check("every node moved by up to 2 mm");
    }
  }
}

/// Appends `part`'s nodes and triangles to `mesh`, as a world joins its cloths and bodies into one mesh.
void append_mesh(ClothMesh& mesh, const ClothMesh& part) {
  const auto offset = static_cast<Index>(mesh.node_count());
  mesh.positions_t0.insert(mesh.positions_t0.end(), part.positions_t0.begin(), part.positions_t0.end());
  mesh.positions_t1.insert(mesh.positions_t1.end(), part.positions_t1.begin(), part.positions_t1.end());
  mesh.inverse_masses.insert(mesh.inverse_masses.end(), part.inverse_masses.begin(),
                             part.inverse_masses.end());
  for (Triangle t : part.triangles) {
    for (Index& v : t)
      v += offset;
    mesh.triangles.push_back(t);
  }
}

// A game's level joins faces of many sizes in one mesh (a ground of big faces, cloths of small ones), and
// a grid's cells suit some sizes better than others (a grid that files faces by size moves them between its
// levels as they grow and shrink). With a ground of 20 cm faces, a cloth of 1 cm faces just above it and a
// 4 m quad below, while a corner of the cloth is stretched 8-fold and back (its faces grow by a factor 8
// and shrink again), the cloth slides by 25 cm in one step, some faces collapse to a point (zero extent)
// and one node flies 1 km, then 1e30 m away and back, it must stay exactly the brute-force set, at 1 and 2
// threads.
TEST(BroadPhase, GridWithFacesOfManySizesMatchesBruteForceAsTheyGrowAndMove) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  test::Particles particles;
  for (int k = 0; k < 3000; ++k)
    particles.add(Vec3(0.35 * u(rng) + 0.15, 0.02 * u(rng) + 0.01, 0.35 * u(rng) + 0.15),
                  Vec3(u(rng), u(rng), u(rng)), 0.01, 1e-4);
  ClothMesh mesh = test::grid_mesh(11, 2.0, 0.0, 0.0, -1.0, -1.0);  // the ground, x and z in [-1, 1]
  const auto first_cloth_node = static_cast<Index>(mesh.node_count());
  append_mesh(mesh, test::grid_mesh(31, 0.3, 0.01, 1.0));  // the cloth, x and z in [0, 0.3]
  const auto cloth_end = static_cast<Index>(mesh.node_count());
  append_mesh(mesh, test::grid_mesh(2, 4.0, -0.005, 0.0, -2.0, -2.0));
  const Vec3Array rest = mesh.positions_t1;
  const std::unique_ptr<TriangleBroadPhase> broad_phase = make_broad_phase(BroadPhaseKind::GRID);
  const int threads = thread_count();
  int calls = 0;
  std::vector<std::pair<Index, Index>> expected, got;
  const auto check = [&](const char* what) {
    find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.002, expected);
    set_thread_count(1 + calls++ % 2);
    broad_phase->find_pairs(particles.x0, particles.x1, mesh, 0.002, nullptr, got);
    set_thread_count(threads);
    ASSERT_GT(expected.size(), 100u) << what;
    EXPECT_EQ(got, expected) << what;
  };
  // The next step: every node starts where it ended, and `move` sets where the cloth's nodes end.
  const auto step = [&](const auto& move) {
    mesh.positions_t0 = mesh.positions_t1;
    for (Index i = first_cloth_node; i < cloth_end; ++i)
      move(i, mesh.positions_t1[i]);
  };
  check("first call");
  const auto stretch = [&](Index i, Vec3& x) {
    if (rest[i].x() < 0.05 && rest[i].z() < 0.05) x = Vec3(8.0 * rest[i].x(), rest[i].y(), 8.0 * rest[i].z());
  };
  step(stretch);
  check("a corner stretched 8-fold in the step");
  step(stretch);
  check("the corner stretched, at rest");
  step([&](Index i, Vec3& x) { x = rest[i]; });
  check("the corner back in the step");
  step([&](Index i, Vec3& x) { x = rest[i]; });
  check("the corner back, at rest");
  step([&](Index, Vec3& x) { x += Vec3(0.25, 0.0, 0.0); });
  check("the cloth slid by 25 cm in the step");
  step([&](Index, Vec3& x) { x += 0.002 * Vec3(u(rng), u(rng), u(rng)); });
  check("the cloth slid, moving by up to 2 mm");
  step([&](Index i, Vec3& x) {
    if (i % 31 < 3) x = rest[first_cloth_node];  // the faces between the first three columns: one point
  });
  step([](Index, Vec3&) {});
  check("some faces collapsed to a point");
  for (const double far : {1e3, 1e30}) {
    step([&](Index i, Vec3& x) {
      if (i == first_cloth_node + 400) x = Vec3(far, 0.0, 0.0);
    });
    check("one node flying far away");
    step([&](Index i, Vec3& x) {
      if (i == first_cloth_node + 400) x = rest[i];
    });
    check("the node back in the step");
  }
  step([&](Index i, Vec3& x) { x = rest[i]; });
  step([&](Index i, Vec3& x) { x = rest[i]; });
  check("the cloth back at rest");
}

// The CCD rounds keep every pair of the motion and bring it up to date from the particles that can be in a
// changed pair (coupling_detail::update_pairs) instead of asking for every particle again: after impulses
// (a particle and its triangle's nodes move), fail-safe placements (particles only), impact-zone node moves
// (every end position of a second sheet lifted by 5 cm, then put back)
// and a round without a change, the kept set must be exactly the brute-force set of the current motion.
TEST(BroadPhase, UpdatedPairsEqualAFullQueryAfterEveryKindOfChange) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dt = 0.003;
  test::Particles particles;
  for (int k = 0; k < 3000; ++k)
    particles.add(Vec3(0.4 * u(rng) + 0.35, 0.005 * u(rng), 0.35 * u(rng) + 0.15),
                  Vec3(u(rng), 3.0 * u(rng), u(rng)), dt, 1e-4);
  // Two sheets side by side, x in [0, 0.3] and [0.4, 0.7].
  ClothMesh mesh = test::grid_mesh(21, 0.3, 0.0, 1.0);
  const ClothMesh second = test::grid_mesh(21, 0.3, 0.0, 1.0, 0.4);
  const auto first_nodes = static_cast<Index>(mesh.node_count());
  mesh.positions_t0.insert(mesh.positions_t0.end(), second.positions_t0.begin(), second.positions_t0.end());
  mesh.positions_t1.insert(mesh.positions_t1.end(), second.positions_t1.begin(), second.positions_t1.end());
  mesh.inverse_masses.insert(mesh.inverse_masses.end(), second.inverse_masses.begin(),
                             second.inverse_masses.end());
  for (Triangle t : second.triangles) {
    for (Index& v : t)
      v += first_nodes;
    mesh.triangles.push_back(t);
  }
  for (std::size_t i = 0; i < mesh.node_count(); i += 7)
    mesh.inverse_masses[i] = 0.0;  // some static nodes: an impulse leaves them where they are
  const FluidView view = particles.view();
  CouplingStepStats stats;
  Vec3Array node_impulses(mesh.node_count(), Vec3::Zero());
  coupling_detail::StepContext ctx(view, mesh, dt, stats, node_impulses, nullptr);
  for (BroadPhaseKind kind : {BroadPhaseKind::GRID, BroadPhaseKind::FCL}) {
    const std::unique_ptr<TriangleBroadPhase> broad_phase = make_broad_phase(kind);
    std::vector<std::pair<Index, Index>> all, fresh, merged, expected, before;
    std::vector<std::uint8_t> only;
    ctx.clear_changes();
    broad_phase->find_pairs(particles.x0, particles.x1, mesh, 0.0, nullptr, all);
    const auto random_index = [&](std::size_t n) { return static_cast<Index>(rng() % n); };
    for (int round = 0; round < 8; ++round) {
      find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.0, before);
      const int kind_of_change = round % 4;
      for (int k = 0; k < 30 && kind_of_change < 2; ++k) {
        const Index p = random_index(particles.x0.size());
        const Index t = random_index(mesh.triangles.size());
        const Vec3 w(0.2, 0.3, 0.5);
        if (kind_of_change == 0) {
          ctx.apply(p, t, w, 1e-3 * Vec3(u(rng), u(rng), u(rng)));  // a particle moves by up to 3 cm
        } else {
          ctx.place(p, particles.x0[p] + 0.01 * Vec3(u(rng), u(rng), u(rng)), t, w);
        }
      }
      if (kind_of_change == 2) {
        const double lift = round < 4 ? 0.05 : -0.05;
        for (Index i = first_nodes; i < mesh.node_count(); ++i)
          ctx.move_node(i, mesh.positions_t1[i] + Vec3(0.0, lift, 0.0));
      }
      coupling_detail::update_pairs(ctx, *broad_phase, only, fresh, all, merged);
      ctx.clear_changes();
      find_pairs_brute_force(particles.x0, particles.x1, mesh, 0.0, expected);
      ASSERT_GT(expected.size(), 100u);
      if (kind_of_change != 3) {
        EXPECT_NE(expected, before) << "round " << round << ": the change must matter";
      }
      EXPECT_EQ(all, expected) << "round " << round << ", broad phase " << static_cast<int>(kind);
      for (const auto& pair : fresh)
        EXPECT_TRUE(only[pair.first]) << "round " << round << ": a pair of an unmarked particle";
    }
  }
}

// Moves a game makes outside the fluid's step (water moved out of a body that appeared) against a cloth at
// rest: those through a face or onto it cross it; those short of it, along it or beside it do not; a move or
// a face with a NaN crosses nothing and throws nothing. The one broad-phase pass finds what testing each move
// against every face finds.
TEST(ClothCrossing, MovesThroughOrOntoAFaceCrossItOthersDoNot) {
  ClothMesh cloth = test::grid_mesh(11, 0.2, 0.0, 1.0);                // y = 0, x and z in [0, 0.2]
  cloth.positions_t1.assign(cloth.node_count(), Vec3(0.1, 5.0, 0.1));  // not read: the cloth at rest
  const Vec3 in(0.053, 0.004, 0.071);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3Array from = {in, in, in, in, Vec3(0.3, 0.004, 0.1), in, Vec3(nan, 0.004, 0.1)};
  const Vec3Array to = {in - Vec3(0, 0.01, 0),      // through
                        Vec3(in.x(), 0.0, in.z()),  // onto
                        in - Vec3(0, 0.003, 0),     // short of it
                        in + Vec3(0.05, 0, 0.02),   // along it
                        Vec3(0.3, -0.01, 0.1),      // beside it
                        Vec3(in.x(), nan, in.z()),  // to NaN
                        Vec3(0.1, -0.01, 0.1)};     // from NaN
  std::vector<std::uint8_t> crosses;
  moves_crossing_cloth(cloth, from, to, crosses);
  EXPECT_EQ(crosses, (std::vector<std::uint8_t>{1, 1, 0, 0, 0, 0, 0}));

  // Random moves about the cloth, one of its nodes NaN: the same flags as each move tested against every
  // face that has no NaN.
  cloth.positions_t0[60] = Vec3(nan, nan, nan);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec3Array a, b;
  for (int k = 0; k < 2000; ++k) {
    a.push_back(Vec3(0.12 * u(rng) + 0.1, 0.01 * u(rng), 0.12 * u(rng) + 0.1));
    b.push_back(a.back() + 0.01 * Vec3(u(rng), u(rng), u(rng)));
  }
  moves_crossing_cloth(cloth, a, b, crosses);
  std::size_t crossing = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    bool expected = false;
    for (const Triangle& t : cloth.triangles) {
      const Vec3 &p = cloth.positions_t0[t[0]], &q = cloth.positions_t0[t[1]], &r = cloth.positions_t0[t[2]];
      if (p.allFinite() && q.allFinite() && r.allFinite())
        expected = expected || ccd::point_static_triangle_ccd(a[k], b[k], p, q, r).hit;
    }
    EXPECT_EQ(crosses[k] != 0, expected) << "move " << k;
    crossing += expected ? 1 : 0;
  }
  EXPECT_GT(crossing, 200u);
  EXPECT_LT(crossing, 1800u);
}

}  // namespace
}  // namespace drench
