// The coupler (Huber et al. 2013 sec. 3): no particle passes a triangle, momentum is conserved, friction
// obeys eq. 7-8, repulsion keeps the cloth thickness.

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <drench/ccd/ccd_exact_reference.hpp>
#include <drench/common/triangle_geometry.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/leak_audit.hpp>
#include <drench/sph/fluid_solver.hpp>
#include "coupling_fixtures.hpp"

namespace drench {
namespace {

using test::grid_mesh;
using test::Particles;

constexpr double kMass = 1.25e-4;  // one particle of water at 5 mm spacing (unit: kg)

/// Signed distance of a point to the plane y = height of a horizontal mesh.
double above(const Vec3& x, double height) {
  return x.y() - height;
}

/// Fires one particle from 5 cm above at `speed` straight down through `target` (a point of the mesh plane
/// y = 0) with dt = 0.01 s: it would end 5 cm below without coupling.
void expect_stopped(ClothMesh mesh, const Vec3& target, double speed = 10.0, double dt = 0.01) {
  Particles particles;
  particles.add(target + Vec3(0, 0.05, 0), Vec3(0, -speed, 0), dt, kMass);
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  EXPECT_GT(above(particles.x1[0], 0.0), 0.0)
      << "particle passed the cloth: end at y = " << particles.x1[0].y();
  EXPECT_GE(stats.ccd_impacts, 1u);
  EXPECT_EQ(stats.failsafe_activations, 0u);
}

TEST(Coupler, StopsAParticleFiredAtAStaticTriangle) {
  // 10 m/s, dt = 0.01: 10 cm per step, 100 cloth thicknesses; repulsion alone never sees it.
  expect_stopped(grid_mesh(2, 1.0, 0.0, 0.0), Vec3(0.3, 0.0, 0.2));
}

TEST(Coupler, StopsAParticleFiredThroughASharedEdge) {
  // The diagonal of the unit square is the edge shared by its two triangles.
  expect_stopped(grid_mesh(2, 1.0, 0.0, 0.0), Vec3(0.5, 0.0, 0.5));
}

TEST(Coupler, StopsAParticleFiredThroughAVertex) {
  // The centre node of a 3 x 3 grid is shared by six triangles.
  expect_stopped(grid_mesh(3, 1.0, 0.0, 0.0), Vec3(0.5, 0.0, 0.5));
}

TEST(Coupler, StopsAParticleWhenTheTriangleMovesTowardsIt) {
  ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 1.0 / 0.01);  // light, free cloth moving up at 5 m/s
  for (Vec3& x : mesh.positions_t1)
    x.y() += 0.05;
  Particles particles;
  const double dt = 0.01;
  particles.add(Vec3(0.3, 0.03, 0.2), Vec3(0, -10, 0), dt, kMass);
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  // The mesh's end height at the particle's (x, z): all nodes move alike, so the plane is y = mean of the
  // nodes.
  double plane = 0.0;
  for (const Vec3& x : mesh.positions_t1)
    plane += x.y() / 4.0;
  EXPECT_GT(particles.x1[0].y(), plane);
  EXPECT_GE(stats.ccd_impacts, 1u);
}

// The CCD rounds after the first query only particles that can meet a changed pair: here the first round's
// impact throws the light cloth up, through a particle at rest above it that no first-round pair involved
// (it is 3 cm above a cloth that was not moving). The second round must find that particle through the
// triangles that changed, not through its own motion, and stop it on the cloth's upper side.
TEST(Coupler, ALaterCcdRoundStopsAParticleThatTheClothWasThrownInto) {
  const double dt = 0.01;
  ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 1.0 / 0.001);  // a free square of four 1 g nodes at rest at y = 0
  Particles particles;
  particles.add(Vec3(0.3, -0.05, 0.2), Vec3(0, 10, 0), dt, 0.1);  // heavy, fired up through the cloth
  particles.add(Vec3(0.7, 0.03, 0.75), Vec3::Zero(), dt, kMass);  // at rest above the cloth
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  ASSERT_GE(stats.ccd_iterations, 2u);
  // The cloth's height under the resting particle at the step's end (the triangle whose xz projection holds
  // it, interpolated).
  const Vec3& x = particles.x1[1];
  double height = std::numeric_limits<double>::quiet_NaN();
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = mesh.positions_t1[t[0]], b = mesh.positions_t1[t[1]], c = mesh.positions_t1[t[2]];
    const double det = (b.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (b.z() - a.z());
    const double u = ((x.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (x.z() - a.z())) / det;
    const double v = ((b.x() - a.x()) * (x.z() - a.z()) - (x.x() - a.x()) * (b.z() - a.z())) / det;
    if (u >= 0.0 && v >= 0.0 && u + v <= 1.0) height = a.y() + u * (b.y() - a.y()) + v * (c.y() - a.y());
  }
  ASSERT_TRUE(std::isfinite(height)) << "the resting particle is not over the cloth";
  ASSERT_GT(height, 0.03) << "the cloth did not reach the resting particle: the test needs a stronger throw";
  EXPECT_GT(x.y(), height) << "the cloth passed the resting particle";
}

TEST(Coupler, LetsAParticleBesideTheClothFallPast) {
  Particles particles;
  particles.add(Vec3(1.5, 0.05, 0.5), Vec3(0, -10, 0), 0.01, kMass);
  ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 0.0);
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, 0.01, stats);
  EXPECT_DOUBLE_EQ(particles.x1[0].y(), 0.05 - 0.1);
  EXPECT_EQ(stats.ccd_impacts, 0u);
}

/// A free 11 x 11 cloth 0.1 m wide at y = 0 (nodes of 0.2 g), its end-of-step nodes moved by up to `jitter`
/// (unit: m) along each axis, drawn from `rng`.
ClothMesh jittered_cloth(std::mt19937_64& rng, double jitter) {
  ClothMesh mesh = grid_mesh(11, 0.1, 0.0, 1.0 / 2e-4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    mesh.positions_t1[i] += jitter * Vec3(u(rng), u(rng), u(rng));
  return mesh;
}

TEST(Coupler, ConservesLinearMomentumWithoutPinsOrGravity) {
  // A free cloth and a cloud of particles moving through it in all directions; g = 0, no pins, no damping.
  std::mt19937_64 rng(7);
  ClothMesh mesh = jittered_cloth(rng, 0.001);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles particles;
  const double dt = 0.002;
  for (int k = 0; k < 400; ++k) {
    const Vec3 x(0.1 * (u(rng) + 1) / 2, 0.004 * u(rng), 0.1 * (u(rng) + 1) / 2);
    particles.add(x, Vec3(0.5 * u(rng), 3.0 * u(rng), 0.5 * u(rng)), dt, kMass);
  }
  const auto momentum = [&] {
    Vec3 total = Vec3::Zero();
    for (std::size_t i = 0; i < particles.x0.size(); ++i)
      total += particles.m[i] * (particles.x1[i] - particles.x0[i]) / dt;
    for (std::size_t i = 0; i < mesh.node_count(); ++i)
      total += (mesh.positions_t1[i] - mesh.positions_t0[i]) / dt / mesh.inverse_masses[i];
    return total;
  };
  double scale = 0.0;  // sum of |m v|, the size rounding errors are relative to
  for (std::size_t i = 0; i < particles.x0.size(); ++i)
    scale += particles.m[i] * particles.v[i].norm();
  const Vec3 before = momentum();
  CouplingSettings settings;
  settings.slip = SlipCondition::NO_SLIP;  // friction impulses too
  Coupler coupler(settings);
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  ASSERT_GT(stats.contacts + stats.ccd_impacts, 10u) << "the test must exercise the coupling";
  ASSERT_EQ(stats.failsafe_activations, 0u)
      << "the fail-safe moves particles alone: its share of the nodes is owed (Coupler::owed_impulses), not "
         "in their positions";
  EXPECT_LE((momentum() - before).norm(), 1e-12 * scale);
}

// CouplingScheme::CARRIED_WATER carries each particle with the triangle its largest impulse went to
// (coupling/impulse_link.hpp): given the particles' ids, the coupler names it.
TEST(Coupler, NamesEachParticlesLargestImpulseWhenGivenIds) {
  const ClothMesh start = grid_mesh(2, 1.0, 0.0, 0.0);
  Particles particles;
  const double dt = 0.01;
  particles.add(Vec3(0.3, 0.05, 0.2), Vec3(0, -10.0, 0), dt, kMass);        // through triangle 0
  particles.add(Vec3(0.7, 0.05, 0.2), Vec3(0.0, 1.0, 0.0), dt, 2 * kMass);  // moving away: no impulse
  const Vec3Array v0 = particles.v;
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  ClothMesh mesh = start;
  coupler.step(particles.view(), mesh, dt, stats);
  EXPECT_TRUE(coupler.impulse_links().empty()) << "no ids, no links";

  particles = Particles{};
  particles.add(Vec3(0.3, 0.05, 0.2), Vec3(0, -10.0, 0), dt, kMass);
  particles.add(Vec3(0.7, 0.05, 0.2), Vec3(0.0, 1.0, 0.0), dt, 2 * kMass);
  const std::vector<std::uint32_t> ids{41, 7};
  FluidView view = particles.view();
  view.ids = &ids;
  mesh = start;
  coupler.step(view, mesh, dt, stats);
  ASSERT_EQ(coupler.impulse_links().size(), 1u);
  const ImpulseLink& link = coupler.impulse_links()[0];
  EXPECT_EQ(link.particle_id, 41u);
  // One impulse (the impact's): its size is the particle's momentum change.
  EXPECT_NEAR(link.impulse, kMass * (particles.v[0] - v0[0]).norm(), 1e-15 * kMass * 10.0);
  ASSERT_LT(link.triangle, mesh.triangle_count());
  const Triangle& tri = mesh.triangles[link.triangle];
  const Vec3 point = link.weights[0] * mesh.positions_t0[tri[0]] +
                     link.weights[1] * mesh.positions_t0[tri[1]] +
                     link.weights[2] * mesh.positions_t0[tri[2]];
  EXPECT_LT((point - Vec3(0.3, 0.0, 0.2)).norm(), 1e-9) << "the weights name the point it hit";
  EXPECT_EQ(particles.v[1], v0[1]);
}

/// One particle resting in contact (half a thickness above) on a triangle that slides along +x at 1 m/s; the
/// particle moves along +z at 0.5 m/s and slightly down.
struct SlidingContact {
  ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 1.0 / 0.01);
  Particles particles;
  double dt = 0.001;
  CouplingStepStats stats;

  explicit SlidingContact(const CouplingSettings& settings) {
    for (Vec3& x : mesh.positions_t1)
      x.x() += 1.0 * dt;
    particles.add(Vec3(0.3, 0.0005, 0.3), Vec3(0, -0.2, 0.5), dt, kMass);
    Coupler coupler(settings);
    coupler.step(particles.view(), mesh, dt, stats);
  }
  /// At the contact point: triangle 0 of the grid, (0, 2, 1), holds (0.3, 0.3); the weights are those of the
  /// closest point at the start, as the coupler takes them.
  Vec3 relative_tangential_velocity() const {
    const Triangle& tri = mesh.triangles[0];
    const Vec3 w = closest_point_barycentric(particles.x0[0], mesh.positions_t0[tri[0]],
                                             mesh.positions_t0[tri[1]], mesh.positions_t0[tri[2]]);
    Vec3 cloth_velocity = Vec3::Zero();
    for (int i = 0; i < 3; ++i)
      cloth_velocity += w[i] * (mesh.positions_t1[tri[i]] - mesh.positions_t0[tri[i]]) / dt;
    Vec3 v = (particles.x1[0] - particles.x0[0]) / dt - cloth_velocity;
    v.y() = 0.0;
    return v;
  }
};

TEST(Coupler, NoSlipZeroesTheRelativeTangentialVelocity) {
  CouplingSettings settings;
  settings.slip = SlipCondition::NO_SLIP;
  SlidingContact c(settings);
  ASSERT_EQ(c.stats.contacts, 1u);
  EXPECT_LE(c.relative_tangential_velocity().norm(), 1e-12);
}

TEST(Coupler, FreeSlipLeavesTheRelativeTangentialVelocity) {
  SlidingContact c(CouplingSettings{});  // friction coefficient 0
  ASSERT_EQ(c.stats.contacts, 1u);
  EXPECT_NEAR(c.relative_tangential_velocity().x(), -1.0, 1e-12);
  EXPECT_NEAR(c.relative_tangential_velocity().z(), 0.5, 1e-12);
}

TEST(Coupler, CoulombFrictionFollowsEquation8) {
  CouplingSettings settings;
  settings.friction_coefficient = 0.5;
  SlidingContact c(settings);
  ASSERT_EQ(c.stats.contacts, 1u);
  // dv_N is what repulsion gave the relative normal velocity; eq. 8 scales v_t_pre by max(1 - mu dv_N/|v_t|,
  // 0).
  const Vec3 pre(-1.0, 0.0, 0.5);
  const Vec3 now = c.relative_tangential_velocity();
  EXPECT_LT(now.norm(), pre.norm());
  EXPECT_NEAR(now.normalized().dot(pre.normalized()), 1.0, 1e-9) << "friction acts against v_t only";
}

TEST(Coupler, RepulsionStopsAnApproachWithinTheThickness) {
  // Half a thickness above a pinned triangle, approaching at 0.1 m/s: eq. 2 stops it, eq. 4 pushes it out.
  ClothMesh mesh = grid_mesh(2, 1.0, 0.0, 0.0);
  Particles particles;
  const double dt = 0.001;
  particles.add(Vec3(0.3, 0.0005, 0.3), Vec3(0, -0.1, 0), dt, kMass);
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, dt, stats);
  EXPECT_EQ(stats.contacts, 1u);
  EXPECT_GE(particles.v[0].y(), 0.0);
  EXPECT_LE(particles.v[0].y(), 0.1 * 0.0005 / dt + 1e-12) << "the elastic impulse is capped at 0.1 d / dt";
}

/// Sec. 3.1's proximity test finds every particle-triangle pair whose start-of-step distance is below the
/// cloth thickness, whatever the broad phase proposes: the contacts of one step equal the count over all
/// pairs, each particle's closest points counted once (triangles sharing the edge or vertex a particle is
/// closest to give one contact). Particles fly fast (swept boxes of several thicknesses) and the cloth
/// moves, so a broad phase that grows its boxes too little would lose pairs.
TEST(Coupler, FindsEveryContactWithinTheThickness) {
  for (const double thickness : {0.001, 0.005}) {
    std::mt19937_64 rng(11);
    const ClothMesh mesh = jittered_cloth(rng, 0.003);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Particles particles;
    const double dt = 0.002;
    for (int k = 0; k < 600; ++k) {
      const Vec3 x(0.1 * (u(rng) + 1) / 2, 2.0 * thickness * u(rng), 0.1 * (u(rng) + 1) / 2);
      particles.add(x, Vec3(2.0 * u(rng), 2.0 * u(rng), 2.0 * u(rng)), dt, kMass);
    }
    // A closest point counts once, and only when no triangle it lies on is closer to the particle (a point on
    // an edge or vertex shadowed by the face the particle is over).
    const auto closest = [&mesh](const Vec3& x, const Triangle& t) {
      const Vec3& a = mesh.positions_t0[t[0]];
      const Vec3& b = mesh.positions_t0[t[1]];
      const Vec3& c = mesh.positions_t0[t[2]];
      const Vec3 w = closest_point_barycentric(x, a, b, c);
      return Vec3(w[0] * a + w[1] * b + w[2] * c);
    };
    std::size_t expected = 0;
    for (const Vec3& x : particles.x0) {
      Vec3Array closest_points;
      for (const Triangle& t : mesh.triangles) {
        const Vec3 point = closest(x, t);
        const double distance = (x - point).norm();
        if (!(distance < thickness)) continue;
        const bool shadowed =
            std::any_of(mesh.triangles.begin(), mesh.triangles.end(), [&](const Triangle& s) {
              return (closest(point, s) - point).norm() <= 1e-12 &&
                     (x - closest(x, s)).norm() < distance * (1 - 1e-9);
            });
        if (shadowed) continue;
        const bool seen = std::any_of(closest_points.begin(), closest_points.end(), [&](const Vec3& q) {
          return (q - point).norm() <= 1e-12 * (1.0 + point.norm());
        });
        if (!seen) closest_points.push_back(point);
      }
      expected += closest_points.size();
    }
    ASSERT_GT(expected, 200u) << "the test needs many particles within the thickness";
    for (const BroadPhaseKind broad_phase : {BroadPhaseKind::FCL, BroadPhaseKind::GRID}) {
      Particles copy = particles;
      ClothMesh cloth = mesh;
      CouplingSettings settings;
      settings.cloth_thickness = thickness;
      settings.continuous = false;
      settings.broad_phase = broad_phase;
      Coupler coupler(settings);
      CouplingStepStats stats;
      coupler.step(copy.view(), cloth, dt, stats);
      EXPECT_EQ(stats.contacts, expected) << "thickness " << thickness << " m, broad phase "
                                          << (broad_phase == BroadPhaseKind::FCL ? "fcl" : "grid");
    }
  }
}

TEST(Coupler, NeverMovesPinnedNodes) {
  ClothMesh mesh = grid_mesh(3, 1.0, 0.0, 1.0 / 0.01);
  mesh.inverse_masses[4] = 0.0;  // the centre
  Particles particles;
  particles.add(Vec3(0.5, 0.05, 0.5), Vec3(0, -10, 0), 0.01, kMass);
  Coupler coupler(CouplingSettings{});
  CouplingStepStats stats;
  coupler.step(particles.view(), mesh, 0.01, stats);
  EXPECT_EQ(mesh.positions_t1[4], mesh.positions_t0[4]);
  EXPECT_GT(particles.x1[0].y(), 0.0);
}

/// Two unit squares at heights y_top and y_bottom, both moving by their own dy in one step, their nodes
/// pinned (inverse mass 0: kinematic, as the default "carried_water" scheme shows the cloth to the coupler).
ClothMesh two_sheets(double y_top, double dy_top, double y_bottom, double dy_bottom) {
  ClothMesh top = grid_mesh(2, 1.0, y_top, 0.0), bottom = grid_mesh(2, 1.0, y_bottom, 0.0);
  for (Vec3& x : top.positions_t1)
    x.y() += dy_top;
  for (Vec3& x : bottom.positions_t1)
    x.y() += dy_bottom;
  ClothMesh both = top;
  const Index offset = static_cast<Index>(top.node_count());
  both.positions_t0.insert(both.positions_t0.end(), bottom.positions_t0.begin(), bottom.positions_t0.end());
  both.positions_t1.insert(both.positions_t1.end(), bottom.positions_t1.begin(), bottom.positions_t1.end());
  both.inverse_masses.insert(both.inverse_masses.end(), bottom.inverse_masses.begin(),
                             bottom.inverse_masses.end());
  for (const Triangle& t : bottom.triangles)
    both.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return both;
}

/// Nodes of `mesh` whose end position is within `tolerance` (m) of start + displacement.
std::size_t nodes_moved_by(const ClothMesh& mesh, const Vec3& displacement, double tolerance) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    count += (mesh.positions_t1[i] - mesh.positions_t0[i] - displacement).norm() <= tolerance ? 1 : 0;
  return count;
}

/// One coupling step of 4 ms, with 4 CCD rounds before the fail-safe, of a particle at rest at y = 0 between
/// two sheets (two_sheets' arguments, unit: m): the fold of the crumpled cloth (issue 39) in small. The
/// sheets' own nodes weigh 10 g, as the carried-water scheme tells the coupler (Coupler::step's
/// engine_inverse_masses), so the impact zones may move them; `pinned` makes their engine hold them instead.
struct FoldStep {
  ClothMesh mesh;
  Particles particles;
  CouplingStepStats stats;
  std::uint32_t status = COUPLING_OK;
  std::pair<std::int64_t, std::int64_t> unresolved;
  std::vector<std::uint8_t> squeezed;

  FoldStep(double y_top, double dy_top, double y_bottom, double dy_bottom, bool pinned = false)
      : mesh(two_sheets(y_top, dy_top, y_bottom, dy_bottom)) {
    const double dt = 0.004;
    particles.add(Vec3(0.3, 0.0, 0.2), Vec3::Zero(), dt, kMass);
    CouplingSettings settings;
    settings.max_ccd_iterations = 4;
    Coupler coupler(settings);
    const ScalarArray own(mesh.node_count(), pinned ? 0.0 : 1.0 / 0.01);
    status = coupler.step(particles.view(), mesh, dt, stats, &own);
    unresolved = coupler.unresolved();
    squeezed = coupler.squeezed_out();
  }
  std::size_t leaks() {
    LeakAuditStats audit;
    return audit_leaks(particles.x0, particles.x1, mesh, audit);
  }
};

// A particle in a fold whose two layers pass through it from both sides (the crumpled cloth of issue 39): it
// cannot follow both, so the fail-safe alone left a crossing. The last resort joins the particle and both
// layers' colliding triangles into one zone that moves by the mean of its nodes' displacements, here zero up
// to rounding (1e-15 m): the start was free of crossings, and a rigid zone keeps it so.
TEST(Coupler, AParticleCaughtInAFoldNeverCrossesEitherLayer) {
  FoldStep fold(0.002, -0.012, -0.003, 0.012);
  EXPECT_NE(fold.status & COUPLING_FAILSAFE_USED, 0u)
      << "the fold must need the fail-safe, else it tests nothing";
  EXPECT_NE(fold.status & COUPLING_ZONES_STOPPED, 0u);
  EXPECT_EQ(fold.status & COUPLING_UNRESOLVED, 0u);
  EXPECT_EQ(fold.unresolved, std::make_pair(std::int64_t{-1}, std::int64_t{-1}));
  EXPECT_EQ(fold.leaks(), 0u);
  // The zone: the particle and the two triangles it was between (three nodes each); the others moved as
  // their engine said.
  EXPECT_LT((fold.particles.x1[0] - fold.particles.x0[0]).norm(), 1e-15);
  EXPECT_EQ(fold.stats.stopped_particles, 1u);
  EXPECT_EQ(fold.stats.stopped_nodes, 6u);
  EXPECT_EQ(nodes_moved_by(fold.mesh, Vec3::Zero(), 1e-15), 6u);
}

// The crumpled cloth at dt 4 ms: folds falling at several m/s. Zones at rest held the caught nodes back by
// their whole step while their neighbours fell, and the cloth overstretched (strain 10). Here both layers
// fall, the upper faster, through a particle at rest: the zone moves by its six nodes' mean displacement
// (-8 mm), and the particle stays between the layers.
TEST(Coupler, AnImpactZoneInAFallingFoldMovesWithItsNodes) {
  FoldStep fold(0.002, -0.012, -0.003, -0.004);
  ASSERT_NE(fold.status & COUPLING_ZONES_STOPPED, 0u)
      << "the fold must need the last resort, else it tests nothing";
  EXPECT_EQ(fold.status & COUPLING_UNRESOLVED, 0u);
  EXPECT_EQ(fold.leaks(), 0u);
  const Vec3 zone(0.0, -0.008, 0.0);
  EXPECT_LT((fold.particles.x1[0] - fold.particles.x0[0] - zone).norm(), 1e-15);
  EXPECT_EQ(fold.stats.stopped_nodes, 6u);
  EXPECT_EQ(nodes_moved_by(fold.mesh, zone, 1e-15), 6u);
}

// The same fold with both layers held by their engine (pins, or two bodies): no motion of the particle keeps
// it between layers that each end where they were given, so the zone squeezes it out, its mass and momentum
// booked, and moves no node.
TEST(Coupler, AParticleCaughtBetweenTwoPinnedLayersIsSqueezedOut) {
  FoldStep fold(0.002, -0.012, -0.003, 0.012, true);
  ASSERT_NE(fold.status & COUPLING_ZONES_STOPPED, 0u)
      << "the fold must need the last resort, else it tests nothing";
  EXPECT_EQ(fold.status & COUPLING_UNRESOLVED, 0u);
  EXPECT_EQ(fold.squeezed, std::vector<std::uint8_t>{1});
  EXPECT_EQ(fold.stats.squeezed_out, 1u);
  EXPECT_EQ(fold.stats.squeezed_out_mass, kMass);
  EXPECT_EQ(fold.stats.squeezed_out_momentum, kMass * fold.particles.v[0]);
  EXPECT_EQ(fold.stats.zone_ignored_shift, 0.0);
  // Every node ends where it was given (rounding: none, they are never written).
  const ClothMesh given = two_sheets(0.002, -0.012, -0.003, 0.012);
  EXPECT_EQ(fold.mesh.positions_t1, given.positions_t1);
}

/// One coupling step of 4 ms, with 4 CCD rounds before the fail-safe, of particles at rest at `starts` (unit:
/// m) between and around two sheets: the upper one a body, turned by 0.01 rad about the z axis through
/// (0.3, 0, 0.2) and lowered by 12 mm, its nodes held by their engine; the lower one rising by 12 mm, its
/// nodes weighing 10 g.
struct TurningBodyStep {
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.01, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 pivot{0.3, 0.0, 0.2}, drop{0.0, -0.012, 0.0};
  ClothMesh mesh = two_sheets(0.002, 0.0, -0.003, 0.012);
  ClothMesh given;
  Particles particles;
  CouplingStepStats stats;
  std::uint32_t status = COUPLING_OK;

  Vec3 body_motion(const Vec3& x) const { return turn * (x - pivot) + pivot + drop; }

  explicit TurningBodyStep(const std::vector<Vec3>& starts) {
    for (std::size_t i = 0; i < 4; ++i)
      mesh.positions_t1[i] = body_motion(mesh.positions_t0[i]);
    given = mesh;
    const double dt = 0.004;
    for (const Vec3& x : starts)
      particles.add(x, Vec3::Zero(), dt, kMass);
    CouplingSettings settings;
    settings.max_ccd_iterations = 4;
    Coupler coupler(settings);
    ScalarArray own(mesh.node_count(), 1.0 / 0.01);  // the lower sheet: 10 g nodes
    for (std::size_t i = 0; i < 4; ++i)
      own[i] = 0.0;  // the body's, held by its engine
    status = coupler.step(particles.view(), mesh, dt, stats, &own);
  }
  std::size_t leaks() {
    LeakAuditStats audit;
    return audit_leaks(particles.x0, particles.x1, mesh, audit);
  }
};

// A body turning as it falls through a particle onto a sheet rising under it: the zone takes the body's
// one rigid motion (Kabsch's fit of its held nodes), so the particle and the sheet's caught nodes turn and
// fall with the body's face, as if stuck to it, and stay on their sides. The body's nodes end exactly where
// they were given: a move would leave the particle inside the body at the next step (jump_leaks).
TEST(Coupler, AZoneWithATurningBodyTakesTheBodysRigidMotion) {
  TurningBodyStep step({Vec3(0.3, 0.0, 0.2)});
  ASSERT_NE(step.status & COUPLING_ZONES_STOPPED, 0u)
      << "the step must need the last resort, else it tests nothing";
  EXPECT_EQ(step.status & COUPLING_UNRESOLVED, 0u);
  EXPECT_EQ(step.stats.squeezed_out, 0u) << "one rigid motion serves the zone";
  EXPECT_EQ(step.stats.zone_ignored_shift, 0.0);
  EXPECT_EQ(step.leaks(), 0u);
  // The body's nodes are never written; the particle and every node that moved off its given end moved
  // with the body's motion (rounding of the fit: 1e-12 m).
  const ClothMesh& mesh = step.mesh;
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_EQ(mesh.positions_t1[i], step.given.positions_t1[i]) << "body node " << i;
  EXPECT_LT((step.particles.x1[0] - step.body_motion(step.particles.x0[0])).norm(), 1e-12);
  std::size_t turned = 0;
  for (std::size_t i = 4; i < mesh.node_count(); ++i) {
    if (mesh.positions_t1[i] == step.given.positions_t1[i]) continue;
    EXPECT_LT((mesh.positions_t1[i] - step.body_motion(mesh.positions_t0[i])).norm(), 1e-12) << "node " << i;
    ++turned;
  }
  EXPECT_EQ(turned, 3u) << "the lower sheet's triangle under the particle";
}

// The same body and sheet, with a second particle at rest under the sheet's caught triangle, clear of the
// sheet as the engine moves it (rising) and of the body. The zone moves that triangle down with the body,
// through the second particle: it is carried down by the triangle's move where it hits, and stays out of the
// zone. Joining it moved more nodes, whose water joined in turn: zones of up to 1,500 particles grew so
// between a ball and a hammock (bench_game_frame).
TEST(Coupler, WaterUnderAFaceAZoneMovesIsCarriedByItNotJoined) {
  // 8 mm under the sheet; the zone moves the sheet's face there by the body's motion to about 13.5 mm down.
  const Vec3 under(0.35, -0.011, 0.15);
  TurningBodyStep step({Vec3(0.3, 0.0, 0.2), under});
  ASSERT_NE(step.status & COUPLING_ZONES_STOPPED, 0u)
      << "the step must need the last resort, else it tests nothing";
  EXPECT_EQ(step.status & COUPLING_UNRESOLVED, 0u);
  EXPECT_EQ(step.leaks(), 0u);
  EXPECT_EQ(step.stats.stopped_particles, 1u) << "the particle between the body and the sheet only";
  EXPECT_EQ(step.stats.carried_by_zones, 1u);
  EXPECT_LT((step.particles.x1[0] - step.body_motion(step.particles.x0[0])).norm(), 1e-12);
  // Carried by the zone's move of the face at the point above it, from where the engine put the face (the
  // sheet's rise) to where the zone did (the body's motion); the face turns, so the point it met shifts by
  // about 0.01 rad times the 8 mm (unit: m).
  const Vec3 above(under.x(), -0.003, under.z());
  const Vec3 zone_move = step.body_motion(above) - (above + Vec3(0.0, 0.012, 0.0));
  EXPECT_LT((step.particles.x1[1] - under - zone_move).norm(), 2e-4);
}

TEST(Coupler, RejectsBadSettingsNamingThem) {
  CouplingSettings settings;
  settings.cloth_thickness = -1.0;
  try {
    Coupler coupler(settings);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("coupling.cloth_thickness"), std::string::npos) << e.what();
  }
}

// A droplet falling 3 mm onto a static horizontal plate under free slip: the plate's normal is vertical, so
// it may change only the water's vertical momentum (the fluid step alone changes the horizontal one by about
// 1e-8 N s). A particle over one face is also within the thickness of the neighbouring faces, whose closest
// points lie on the shared edges and vertices; their slanted normals, unless dropped (find_contacts), push
// the water sideways along the triangulation's diagonal: 1.4% of the vertical impulse, a drift of 1 cm/s.
TEST(Coupler, ADropletLandingOnAStaticPlateGainsNoSidewaysMomentum) {
  constexpr Scalar spacing = 0.001, dt = 0.0005;
  FluidSettings settings;
  settings.particle_spacing = spacing;
  settings.pressure_solver = PressureSolverKind::DFSPH;
  FluidSolver fluid(settings, Vec3(0.0, -9.81, 0.0), BoundaryParticles{}, {}, true, 10.0);
  test::add_droplet(fluid, Vec3(0.0, 4.0 * spacing, 0.0), spacing);
  ClothMesh plate = ClothMesh::grid(41, 0.06, 0.0, 0.0, -0.03, -0.03);
  CouplingSettings coupling;
  coupling.cloth_thickness = 0.5 * spacing;
  Coupler coupler(coupling, false);
  const auto momentum = [&fluid]() {
    const ParticleSet& p = fluid.particles();
    Vec3 m = Vec3::Zero();
    for (std::size_t i = 0; i < p.size(); ++i)
      m += p.masses[i] * p.velocities[i];
    return m;
  };
  Vec3 from_coupler = Vec3::Zero();
  for (int step = 1; step <= 150; ++step) {
    ASSERT_TRUE(fluid.step(dt).ok()) << step;
    ParticleSet& p = fluid.particles();
    const FluidView view{&p.positions_t0, &p.positions, &p.velocities, &p.masses, nullptr};
    CouplingStepStats stats;
    const Vec3 before = momentum();
    ASSERT_EQ(coupler.step(view, plate, dt, stats), COUPLING_OK) << step;
    from_coupler += momentum() - before;
  }
  std::printf("[ measured ] the coupler's impulse on the water: (%.3g, %.3g, %.3g) N s\n", from_coupler.x(),
              from_coupler.y(), from_coupler.z());
  const Scalar tolerance = 1e-3 * std::abs(from_coupler.y());
  EXPECT_LT(std::abs(from_coupler.x()), tolerance);
  EXPECT_LT(std::abs(from_coupler.z()), tolerance);
}

}  // namespace
}  // namespace drench
