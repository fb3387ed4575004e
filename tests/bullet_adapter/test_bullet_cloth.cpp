// BulletCloth: node state in and out of btSoftBody exactly, pinned nodes left alone, masses as set, gravity
// and settings applied, and Bullet's own integrator seen through the adapter.

#include <drench/bullet/bullet_cloth.hpp>

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <drench/bullet/soft_body_builder.hpp>
#include "bullet_test_helpers.hpp"

namespace drench::bullet {
namespace {

using test::as_bullet;
using test::bullet_tolerance;
using test::expect_scene_error;
using test::patch_settings;

const Vec3 kGravity(0.0, -9.81, 0.0);
constexpr double kDt = 1e-3;
// btSoftRigidDynamicsWorld::predictUnconstraintMotion hands the soft-body solver float(timeStep), even in the
// double build: soft bodies advance by dt rounded to float (1e-3 becomes 1e-3 (1 + 4.7e-8)). Rigid bodies get
// dt.
const double kBulletDt = static_cast<float>(kDt);

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof(double)) == 0;
}
bool same_bits(const btVector3& a, const btVector3& b) {
  return same_bits(a.x(), b.x()) && same_bits(a.y(), b.y()) && same_bits(a.z(), b.z());
}

struct NodeState {
  std::vector<btVector3> x, q, v;
};

NodeState snapshot(const btSoftBody& body) {
  NodeState s;
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    s.x.push_back(body.m_nodes[i].m_x);
    s.q.push_back(body.m_nodes[i].m_q);
    s.v.push_back(body.m_nodes[i].m_v);
  }
  return s;
}

// Steps a cloth a few times without coupling, so that nodes move and links are stretched.
void settle(BulletCloth& cloth, int steps) {
  for (int n = 0; n < steps; ++n) {
    cloth.begin_step();
    cloth.step(kDt);
    cloth.end_step(kDt);
  }
}

/// Steps `steps` times by kDt with `impulses` (one per node, unit: N s) applied before each step.
void step_under_load(BulletCloth& cloth, const Vec3Array& impulses, int steps) {
  for (int n = 0; n < steps; ++n) {
    cloth.begin_step();
    cloth.apply_impulses(impulses);
    cloth.step(kDt);
    cloth.end_step(kDt);
  }
}

/// A world the way a user builds it, for attach mode.
struct UserWorld : test::SoftRigidWorld {
  btSoftBody* cloth = nullptr;

  UserWorld() {
    world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);
    cloth = btSoftBodyHelpers::CreatePatch(world.getWorldInfo(), btVector3(-0.3, 0.4, -0.3),
                                           btVector3(0.3, 0.4, -0.3), btVector3(-0.3, 0.4, 0.3),
                                           btVector3(0.3, 0.4, 0.3), 9, 9, 1 + 2 + 4 + 8, true);
    cloth->getCollisionShape()->setMargin(0.01);
    cloth->m_cfg.piterations = 5;
    world.addSoftBody(cloth);
  }
  ~UserWorld() {
    world.removeSoftBody(cloth);
    delete cloth;
  }
};

TEST(BulletConversions, ToBulletRoundsEveryCoordinate) {
  // Read through a volatile so that no coordinate is a constant the compiler could fold.
  volatile double scale = 1.0;
  const Vec3 v(0.1 * scale, -9.81 * scale, 0.3 * scale);
  const Vec3 back = to_vec3(to_bt(v));
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(back[k], as_bullet(v[k])) << "coordinate " << k;
}

TEST(BulletCloth, OwnedEngineAppliesGravityMarginAndSettings) {
  ClothSettings s = patch_settings(11, 7);
  s.position_iterations = 6;
  s.damping = 0.01;
  BulletCloth cloth(s, Vec3(0.5, -9.81, 0.25));
  ASSERT_TRUE(cloth.owns_world());
  btSoftRigidDynamicsWorld& world = *cloth.world();
  EXPECT_EQ(to_vec3(world.getWorldInfo().m_gravity), as_bullet(Vec3(0.5, -9.81, 0.25)));
  EXPECT_EQ(to_vec3(world.getGravity()), as_bullet(Vec3(0.5, -9.81, 0.25)));
  EXPECT_EQ(world.getSoftBodyArray().size(), 1);
  EXPECT_EQ(world.getSoftBodyArray()[0], &cloth.body());
  EXPECT_EQ(cloth.body().getCollisionShape()->getMargin(), as_bullet(CLOTH_COLLISION_MARGIN));
  EXPECT_EQ(cloth.body().m_cfg.piterations, 6);
  EXPECT_EQ(cloth.body().m_cfg.kDP, as_bullet(0.01));
  EXPECT_EQ(cloth.body().getActivationState(), DISABLE_DEACTIVATION);
  EXPECT_EQ(cloth.mesh().node_count(), 77u);
  EXPECT_EQ(cloth.mesh().triangle_count(), 2u * 10 * 6);
  EXPECT_NO_THROW(cloth.mesh().validate());
}

TEST(BulletCloth, TrianglesAreTheBodysFacesByNodeIndex) {
  BulletCloth cloth(patch_settings(57, 57), kGravity);
  const btSoftBody& body = cloth.body();
  ASSERT_EQ(cloth.mesh().triangle_count(), 6272u);
  for (int f = 0; f < body.m_faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(cloth.mesh().triangles[f][k], static_cast<Index>(body.m_faces[f].m_n[k] - &body.m_nodes[0]));
    }
  }
  EXPECT_NO_THROW(cloth.mesh().validate());
}

TEST(BulletCloth, UnchangedEndPositionsLeaveBulletBitIdentical) {
  BulletCloth cloth(patch_settings(21, 17), kGravity);
  settle(cloth, 5);
  cloth.begin_step();
  cloth.step(kDt);
  const NodeState before = snapshot(cloth.body());
  for (std::size_t i = 0; i < cloth.mesh().node_count(); ++i)
    ASSERT_TRUE(same_bits(to_bt(cloth.mesh().positions_t1[i]), before.x[i])) << "node " << i;
  cloth.end_step(kDt);
  const NodeState after = snapshot(cloth.body());
  for (std::size_t i = 0; i < before.x.size(); ++i) {
    ASSERT_TRUE(same_bits(after.x[i], before.x[i])) << "node " << i;
    ASSERT_TRUE(same_bits(after.v[i], before.v[i])) << "node " << i;
    ASSERT_TRUE(same_bits(after.q[i], before.q[i])) << "node " << i;
  }
}

TEST(BulletCloth, PositionsT0AreTheNodesAtBeginStep) {
  BulletCloth cloth(patch_settings(9, 9), kGravity);
  settle(cloth, 3);
  const NodeState start = snapshot(cloth.body());
  cloth.begin_step();
  for (std::size_t i = 0; i < start.x.size(); ++i)
    ASSERT_TRUE(same_bits(to_bt(cloth.mesh().positions_t0[i]), start.x[i])) << "node " << i;
  cloth.step(kDt);
  for (std::size_t i = 0; i < start.x.size(); ++i)
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_q, start.x[i])) << "node " << i;  // Bullet's q = x_t0
}

TEST(BulletCloth, KnownCorrectionArrivesExactlyAsPositionAndVelocity) {
  BulletCloth cloth(patch_settings(21, 17), kGravity);
  settle(cloth, 5);
  cloth.begin_step();
  cloth.step(kDt);
  const NodeState before = snapshot(cloth.body());
  const int moved = 8 * 21 + 10;  // node (10, 8), interior and free
  ASSERT_GT(cloth.body().m_nodes[moved].m_im, 0.0);
  const Vec3 predicted = cloth.mesh().positions_t1[moved];
  const Vec3 corrected = predicted + Vec3(1e-4, 3e-4, -2e-4);
  cloth.mesh().positions_t1[moved] = corrected;
  cloth.end_step(kDt);

  const btSoftBody::Node& node = cloth.body().m_nodes[moved];
  EXPECT_TRUE(same_bits(node.m_x, to_bt(corrected)));
  // Bullet adds the velocity change in its own precision.
  const btVector3 expected_bt_v = before.v[moved] + to_bt((corrected - predicted) / kDt);
  const Vec3 expected_v = to_vec3(expected_bt_v);
  EXPECT_TRUE(same_bits(node.m_v, expected_bt_v))
      << to_vec3(node.m_v).transpose() << " vs " << expected_v.transpose();
  EXPECT_TRUE(same_bits(node.m_q, before.q[moved]));
  for (int i = 0; i < cloth.body().m_nodes.size(); ++i) {
    if (i == moved) continue;
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_x, before.x[i])) << "node " << i;
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_v, before.v[i])) << "node " << i;
  }
  EXPECT_EQ(cloth.ignored_pinned_corrections(), 0);
}

TEST(BulletCloth, VelocityChangeSurvivesBulletsNextStep) {
  // A free patch in free fall moves rigidly, so its links stay at rest length and Bullet's next step is pure
  // symplectic Euler: x += (v + g dt) dt. A correction dx of every node must show up as dv = dx / dt in it.
  BulletCloth cloth(patch_settings(9, 9, "none"), kGravity);
  settle(cloth, 3);
  cloth.begin_step();
  cloth.step(kDt);
  const Vec3 dx(2e-5, 1e-5, -3e-5);
  for (Vec3& x : cloth.mesh().positions_t1)
    x += dx;
  cloth.end_step(kDt);
  const NodeState corrected = snapshot(cloth.body());
  cloth.begin_step();
  cloth.step(kDt);
  for (int i = 0; i < cloth.body().m_nodes.size(); ++i) {
    const Vec3 expected_step = (to_vec3(corrected.v[i]) + kGravity * kBulletDt) * kBulletDt;
    const Vec3 step = to_vec3(cloth.body().m_nodes[i].m_x) - to_vec3(corrected.x[i]);
    const double position = to_vec3(corrected.x[i]).norm();
    EXPECT_LT((step - expected_step).norm(), bullet_tolerance(1e-12, position)) << "node " << i;  // (unit: m)
    const Vec3 expected_v = to_vec3(corrected.v[i]) + kGravity * kBulletDt;
    EXPECT_LT((to_vec3(cloth.body().m_nodes[i].m_v) - expected_v).norm(),
              bullet_tolerance(1e-9, position / kBulletDt))
        << "node " << i;  // m/s
  }
  // And the correction itself: v = 4 g dt + dx / dt after four steps from rest.
  const Vec3 v_expected = 4.0 * kGravity * kBulletDt + dx / kDt;
  EXPECT_LT((to_vec3(corrected.v[40]) - v_expected).norm(),
            bullet_tolerance(1e-9, to_vec3(corrected.x[40]).norm() / kBulletDt));
}

TEST(BulletCloth, ImpulseOnPinnedNodeChangesNothing) {
  // The coupler never moves a pinned node (inverse mass 0); the adapter also ignores such a change from
  // anyone else, counts it, and shows the node where Bullet keeps it.
  BulletCloth cloth(patch_settings(9, 9, "corners"), kGravity);
  settle(cloth, 3);
  cloth.begin_step();
  cloth.step(kDt);
  const NodeState before = snapshot(cloth.body());
  const int corner = 8;
  ASSERT_EQ(cloth.body().m_nodes[corner].m_im, 0.0);
  ASSERT_EQ(cloth.mesh().inverse_masses[corner], 0.0);
  const Vec3 pinned_at = cloth.mesh().positions_t1[corner];
  cloth.mesh().positions_t1[corner] += Vec3(0.0, -0.01, 0.0);
  cloth.end_step(kDt);
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[corner].m_x, before.x[corner]));
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[corner].m_v, before.v[corner]));
  EXPECT_EQ(cloth.mesh().positions_t1[corner], pinned_at);
  EXPECT_EQ(cloth.ignored_pinned_corrections(), 1);
  for (int i = 0; i < cloth.body().m_nodes.size(); ++i) {
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_x, before.x[i])) << "node " << i;
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_v, before.v[i])) << "node " << i;
  }
  settle(cloth, 10);
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[corner].m_x, to_bt(pinned_at)));
}

TEST(BulletCloth, AppliedImpulseIsAVelocityChangeOfJOverMass) {
  // The sub-step obstacle's impulses enter before Bullet's step: v += J m_im exactly, pinned nodes untouched.
  BulletCloth cloth(patch_settings(9, 9, "corners"), kGravity);
  settle(cloth, 3);
  cloth.begin_step();
  const NodeState before = snapshot(cloth.body());
  Vec3Array impulses(cloth.mesh().node_count(), Vec3::Zero());
  const int free_node = 40, corner = 8;
  impulses[free_node] = Vec3(0.0, -2e-4, 1e-4);
  impulses[corner] = Vec3(0.0, -1.0, 0.0);
  cloth.apply_impulses(impulses);
  const btSoftBody::Node& node = cloth.body().m_nodes[free_node];
  EXPECT_TRUE(same_bits(node.m_v, before.v[free_node] + to_bt(impulses[free_node]) * node.m_im));
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[corner].m_v, before.v[corner]));
  for (int i = 0; i < cloth.body().m_nodes.size(); ++i) {
    if (i == free_node) continue;
    ASSERT_TRUE(same_bits(cloth.body().m_nodes[i].m_v, before.v[i])) << "node " << i;
  }
  EXPECT_THROW(cloth.apply_impulses(Vec3Array(3, Vec3::Zero())), std::invalid_argument);
}

TEST(BulletCloth, CarriedMassesWeighOnTheNodesForOneStepOnly) {
  // Water carried through Bullet's step (coupling/carried_water.hpp): node i moves as m_i + carried_i, pinned
  // nodes stay pinned, and afterwards masses, link constants and rest lengths are the body's own, bit for
  // bit (no setMass: its flag would make Bullet reset every rest length to the stretched length).
  BulletCloth cloth(patch_settings(9, 9, "corners"), kGravity);
  settle(cloth, 3);
  const btSoftBody& body = cloth.body();
  std::vector<double> own_im, rest, c0;
  for (int i = 0; i < body.m_nodes.size(); ++i)
    own_im.push_back(body.m_nodes[i].m_im);
  for (int k = 0; k < body.m_links.size(); ++k) {
    rest.push_back(body.m_links[k].m_rl);
    c0.push_back(body.m_links[k].m_c0);
  }
  cloth.begin_step();
  const int wet = 40, corner = 8;
  ScalarArray carried(cloth.mesh().node_count(), 0.0);
  carried[wet] = 0.01;  // kg, 30 times the node's own mass
  carried[corner] = 0.5;
  cloth.set_carried_masses(carried);
  EXPECT_TRUE(same_bits(body.m_nodes[wet].m_im, as_bullet(1.0 / (1.0 / own_im[wet] + 0.01))));
  EXPECT_EQ(body.m_nodes[corner].m_im, 0.0);
  for (int k = 0; k < body.m_links.size(); ++k) {
    const btSoftBody::Link& link = body.m_links[k];
    ASSERT_EQ(link.m_c0, (link.m_n[0]->m_im + link.m_n[1]->m_im) / link.m_material->m_kLST) << "link " << k;
  }
  // An impulse on the wet node moves node and water together.
  Vec3Array impulses(cloth.mesh().node_count(), Vec3::Zero());
  impulses[wet] = Vec3(0.0, -1e-3, 0.0);
  const double vy = body.m_nodes[wet].m_v.y();
  cloth.apply_impulses(impulses);
  EXPECT_NEAR(body.m_nodes[wet].m_v.y() - vy, -1e-3 / (1.0 / own_im[wet] + 0.01),
              bullet_tolerance(1e-15, std::abs(vy) + 0.1));
  cloth.step(kDt);
  cloth.end_step(kDt);
  for (int i = 0; i < body.m_nodes.size(); ++i)
    ASSERT_TRUE(same_bits(body.m_nodes[i].m_im, own_im[i])) << "node " << i;
  for (int k = 0; k < body.m_links.size(); ++k) {
    ASSERT_TRUE(same_bits(body.m_links[k].m_rl, rest[k])) << "link " << k;
    ASSERT_TRUE(same_bits(body.m_links[k].m_c0, c0[k])) << "link " << k;
  }
  for (std::size_t i = 0; i < cloth.mesh().node_count(); ++i)
    ASSERT_TRUE(same_bits(cloth.mesh().inverse_masses[i], own_im[i])) << "node " << i;
  EXPECT_THROW(cloth.set_carried_masses(ScalarArray(3, 0.0)), std::invalid_argument);
}

/// Largest ratio of a triangle edge's length to its length at construction, after `steps` steps of a 21 x 21
/// patch pinned at its corners with a 200 g weight (four times its own mass) hung from its centre node (as
/// impulses before each step).
double stretch_under_load(int substeps, int steps) {
  ClothSettings s = patch_settings(21, 21, "corners");
  s.substeps = substeps;
  BulletCloth cloth(s, kGravity);
  const Vec3Array rest = cloth.mesh().positions_t0;
  Vec3Array impulses(rest.size(), Vec3::Zero());
  impulses[10 * 21 + 10] = 0.2 * kGravity * kDt;
  step_under_load(cloth, impulses, steps);
  double worst = 0.0;
  const ClothMesh& m = cloth.mesh();
  for (const Triangle& t : m.triangles) {
    for (int e = 0; e < 3; ++e) {
      const Index a = t[e], b = t[(e + 1) % 3];
      worst = std::max(worst, (m.positions_t1[a] - m.positions_t1[b]).norm() / (rest[a] - rest[b]).norm());
    }
  }
  return worst;
}

TEST(BulletCloth, SubstepsStretchALoadedClothLess) {
  // A position-based cloth's links give under a point load; smaller steps hold them closer to their length.
  const double one = stretch_under_load(1, 300);
  const double four = stretch_under_load(4, 300);
  RecordProperty("max_stretch_1_substep", std::to_string(one));
  RecordProperty("max_stretch_4_substeps", std::to_string(four));
  EXPECT_GT(one, 1.05);  // the load is felt
  EXPECT_LT(four - 1.0, 0.5 * (one - 1.0));
}

TEST(BulletCloth, AllPinnedPatchStaysExactlyPut) {
  // Every link joins two pinned nodes (Bullet's link constant (im0 + im1) / kLST is 0): no NaN, no motion.
  BulletCloth cloth(patch_settings(2, 2, "corners"), kGravity);
  const NodeState start = snapshot(cloth.body());
  settle(cloth, 10);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(same_bits(cloth.body().m_nodes[i].m_x, start.x[i])) << "node " << i;
    EXPECT_EQ(to_vec3(cloth.body().m_nodes[i].m_v), Vec3::Zero()) << "node " << i;
  }
  EXPECT_EQ(cloth.total_mass(), 0.0);
}

TEST(BulletCloth, NonFiniteCorrectionNeverReachesBullet) {
  BulletCloth cloth(patch_settings(9, 9), kGravity);
  cloth.begin_step();
  cloth.step(kDt);
  const NodeState before = snapshot(cloth.body());
  cloth.mesh().positions_t1[40].y() = std::numeric_limits<double>::quiet_NaN();
  cloth.end_step(kDt);
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[40].m_x, before.x[40]));
  EXPECT_TRUE(same_bits(cloth.body().m_nodes[40].m_v, before.v[40]));
  EXPECT_TRUE(cloth.mesh().positions_t1[40].allFinite());
  EXPECT_EQ(cloth.non_finite_corrections(), 1);
}

TEST(BulletCloth, MassesReadBackFromBulletEqualWhatWasSet) {
  const ClothSettings s = patch_settings(57, 57, "corners");
  BulletCloth cloth(s, kGravity);
  const btSoftBody& body = cloth.body();
  const ScalarArray set = node_masses_from_area(body, s.area_density);  // before pinning
  const std::vector<int> pinned = pinned_nodes(body, s.pinned);
  double pinned_mass = 0;
  for (int i = 0; i < body.m_nodes.size(); ++i) {
    const bool is_pinned = std::find(pinned.begin(), pinned.end(), i) != pinned.end();
    EXPECT_EQ(cloth.mesh().inverse_masses[i], body.m_nodes[i].m_im) << "node " << i;
    if (is_pinned) {
      EXPECT_EQ(body.m_nodes[i].m_im, 0.0) << "node " << i;
      pinned_mass += set[i];
    } else {
      EXPECT_NEAR(1.0 / body.m_nodes[i].m_im, set[i], bullet_tolerance(1e-15 * set[i], set[i]))
          << "node " << i;  // 1 / (1 / m)
    }
  }
  const double cloth_mass = s.area_density * s.size_x * s.size_z;
  // A corner node carries one or two triangles: 1/6 or 1/3 of a cell.
  EXPECT_GT(pinned_mass, 0.0);
  // Node masses come from triangle areas over corners Bullet stores rounded (an edge of length l between
  // points of size |x| is off by about |x| / l units of rounding), and a sum of n of them rounds n times.
  const double n = body.m_nodes.size();
  const double area_ulps = 4.0 * (s.center.norm() + s.size_x) / (s.size_z / (s.nodes_z - 1));
  EXPECT_NEAR(cloth.total_mass(), cloth_mass - pinned_mass,
              bullet_tolerance(1e-12 * cloth_mass, cloth_mass, area_ulps + n));
  BulletCloth unpinned(patch_settings(57, 57, "none"), kGravity);
  EXPECT_NEAR(unpinned.total_mass(), cloth_mass,
              bullet_tolerance(1e-12 * cloth_mass, cloth_mass, area_ulps + n));
}

TEST(BulletCloth, FreeFallingPatchMovesByGDtSquaredMorePerStep) {
  // Bullet's symplectic Euler from rest: v_k = k g dt and x_k - x_(k-1) = k g dt^2, for every node, with
  // Bullet's dt (kBulletDt).
  BulletCloth cloth(patch_settings(57, 57, "none"), kGravity);
  for (int k = 1; k <= 20; ++k) {
    cloth.begin_step();
    cloth.step(kDt);
    const Vec3 expected_step = k * kGravity * kBulletDt * kBulletDt;
    const Vec3Array v = cloth.velocities();
    for (std::size_t i = 0; i < cloth.mesh().node_count(); ++i) {
      const Vec3 step = cloth.mesh().positions_t1[i] - cloth.mesh().positions_t0[i];
      // Each of Bullet's k velocity updates and the two positions round once.
      const double position = cloth.mesh().positions_t1[i].norm();
      ASSERT_LT((step - expected_step).norm(), bullet_tolerance(1e-12, position))
          << "step " << k << " node " << i;  // (unit: m)
      ASSERT_LT((v[i] - k * kGravity * kBulletDt).norm(), bullet_tolerance(1e-9, position / kBulletDt))
          << "step " << k << " node " << i;  // (unit: m/s)
    }
    cloth.end_step(kDt);
  }
}

TEST(BulletCloth, BulletAdvancesSoftBodiesByDtRoundedToFloat) {
  BulletCloth cloth(patch_settings(5, 5), kGravity);
  cloth.begin_step();
  cloth.step(kDt);
  EXPECT_EQ(cloth.body().m_sst.sdt, kBulletDt);
  EXPECT_NE(kBulletDt, kDt);
  EXPECT_NEAR(kBulletDt / kDt - 1.0, 4.7e-8, 1e-9);
}

TEST(BulletCloth, PinnedPatchHangsFiniteAndSags) {
  // The notes' pitfall: piterations 1 blows this patch up at dt = 1 ms; the adapter's minimum 4 holds it.
  BulletCloth cloth(patch_settings(57, 57, "corners"), kGravity);
  settle(cloth, 500);
  for (const Vec3& x : cloth.mesh().positions_t1)
    ASSERT_TRUE(x.allFinite());
  const int centre = 28 * 57 + 28;
  const double sag = 0.5 - cloth.body().m_nodes[centre].m_x.y();
  EXPECT_GT(sag, 0.01);  // it hangs (unit: m)
  EXPECT_LT(sag, 0.5);   // and holds together: the patch is 0.6 x 0.4 m
}

TEST(BulletCloth, AttachedClothReadsTheUsersBodyAndLeavesItsSettings) {
  UserWorld user;
  BulletCloth cloth(*user.cloth, &user.world);
  EXPECT_FALSE(cloth.owns_world());
  EXPECT_EQ(cloth.world(), &user.world);
  EXPECT_EQ(cloth.mesh().node_count(), 81u);
  EXPECT_EQ(cloth.mesh().triangle_count(), 128u);
  EXPECT_EQ(cloth.mesh().inverse_masses[0], 0.0);   // CreatePatch's fixeds = 1 + 2 + 4 + 8
  EXPECT_EQ(cloth.mesh().inverse_masses[40], 1.0);  // CreatePatch's mass 1 per node
  EXPECT_EQ(user.cloth->getCollisionShape()->getMargin(), as_bullet(0.01));
  EXPECT_EQ(user.cloth->m_cfg.piterations, 5);
  EXPECT_EQ(cloth.total_mass(), 77.0);

  cloth.begin_step();
  cloth.step(kDt);  // steps the user's world once
  // Free nodes fall; links to the pinned corners pull them back a little.
  EXPECT_LT(cloth.velocities()[40].y(), -0.5 * 9.81 * kDt);
  EXPECT_GT(cloth.velocities()[40].y(), -2.0 * 9.81 * kDt);
  for (std::size_t i = 0; i < 81; ++i)
    ASSERT_TRUE(same_bits(to_bt(cloth.mesh().positions_t1[i]), user.cloth->m_nodes[i].m_x));
  cloth.end_step(kDt);
}

TEST(BulletCloth, AttachedWithoutWorldOnlyCapturesWhatTheUserStepped) {
  UserWorld user;
  BulletCloth cloth(*user.cloth);
  EXPECT_EQ(cloth.world(), nullptr);
  cloth.begin_step();
  user.world.stepSimulation(kDt, 0);
  const NodeState stepped = snapshot(*user.cloth);
  cloth.step(kDt);  // no world: nothing is stepped again
  for (std::size_t i = 0; i < 81; ++i) {
    ASSERT_TRUE(same_bits(user.cloth->m_nodes[i].m_x, stepped.x[i]));
    ASSERT_TRUE(same_bits(to_bt(cloth.mesh().positions_t1[i]), stepped.x[i]));
  }
  cloth.capture_end();  // the same, spelled out
  cloth.end_step(kDt);
  EXPECT_TRUE(same_bits(user.cloth->m_nodes[40].m_x, stepped.x[40]));
}

TEST(BulletCloth, UserPinsBetweenStepsAreSeenAtBeginStep) {
  UserWorld user;
  BulletCloth cloth(*user.cloth, &user.world);
  user.cloth->setMass(40, 0.0);
  cloth.begin_step();
  EXPECT_EQ(cloth.mesh().inverse_masses[40], 0.0);
}

/// Steps an owned 11 x 11 patch, pinned at its corners, for 0.1 s with 20 g hung on its centre node, so that
/// its links are longer than their rest lengths. Returns the centre node's index.
int stretch_a_loaded_patch(BulletCloth& cloth) {
  const int centre = 5 * 11 + 5;
  Vec3Array load(cloth.mesh().node_count(), Vec3::Zero());
  load[centre] = Vec3(0.0, -0.02 * 9.81 * kDt, 0.0);
  step_under_load(cloth, load, 100);
  return centre;
}

std::vector<double> rest_lengths(const btSoftBody& body) {
  std::vector<double> rl;
  for (int i = 0; i < body.m_links.size(); ++i)
    rl.push_back(body.m_links[i].m_rl);
  return rl;
}

TEST(BulletCloth, SetNodeMassesKeepsRestLengthsWhereSetMassResetsThem) {
  // Bullet's own setMass: the next step makes the current (stretched) lengths the rest lengths.
  BulletCloth reference(patch_settings(11, 11), kGravity);
  const int centre = stretch_a_loaded_patch(reference);
  const std::vector<double> before = rest_lengths(reference.body());
  double longest = 0.0;  // current length over rest length: the patch is stretched
  for (int i = 0; i < reference.body().m_links.size(); ++i) {
    const btSoftBody::Link& l = reference.body().m_links[i];
    longest = std::max(longest, double((l.m_n[0]->m_x - l.m_n[1]->m_x).length() / l.m_rl));
  }
  ASSERT_GT(longest, 1.001);
  reference.body().setMass(centre, 0.0);
  reference.begin_step();
  reference.step(kDt);
  EXPECT_NE(rest_lengths(reference.body()), before);

  // set_node_masses: rest lengths bit-identical, the node pinned, the link constants follow the masses.
  BulletCloth cloth(patch_settings(11, 11), kGravity);
  stretch_a_loaded_patch(cloth);
  btSoftBody& body = cloth.body();
  ASSERT_EQ(rest_lengths(body), before);  // same steps, same state
  const Vec3 pinned_at = to_vec3(body.m_nodes[centre].m_x);
  set_node_masses(body, {{centre, 0.0}, {centre + 1, 0.5}});
  EXPECT_EQ(body.m_nodes[centre].m_im, 0.0);
  EXPECT_EQ(body.m_nodes[centre + 1].m_im, 2.0);
  settle(cloth, 10);
  EXPECT_EQ(rest_lengths(body), before);
  EXPECT_EQ(to_vec3(body.m_nodes[centre].m_x), pinned_at);
  for (int i = 0; i < body.m_links.size(); ++i) {
    const btSoftBody::Link& l = body.m_links[i];
    EXPECT_EQ(l.m_c0, (l.m_n[0]->m_im + l.m_n[1]->m_im) / l.m_material->m_kLST) << "link " << i;
  }
}

TEST(BulletCloth, SetNodeMassesRefusesBadPairsAndChangesNothing) {
  BulletCloth cloth(patch_settings(5, 5), kGravity);
  btSoftBody& body = cloth.body();
  const double im = body.m_nodes[3].m_im;
  const auto expect_refused = [&](const std::vector<std::pair<int, double>>& masses,
                                  const std::string& what) {
    try {
      set_node_masses(body, masses);
      ADD_FAILURE() << "no exception for " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_EQ(body.m_nodes[3].m_im, im);
  };
  expect_refused({{3, 1.0}, {25, 1.0}}, "node 25 out of range [0, 25)");
  expect_refused({{3, 1.0}, {-1, 1.0}}, "node -1 out of range");
  expect_refused({{3, 1.0}, {4, -0.5}}, "node 4 mass must be >= 0, got -0.5");
  expect_refused({{3, 1.0}, {4, std::nan("")}}, "node 4 mass must be >= 0, got nan");
}

TEST(BulletCloth, FactoryBuildsAnOwnedBulletCloth) {
  const ClothEngineFactory factory = cloth_engine_factory();
  const std::unique_ptr<ClothEngine> engine = factory(ClothSettings{}, kGravity);
  auto* cloth = dynamic_cast<BulletCloth*>(engine.get());
  ASSERT_NE(cloth, nullptr);
  EXPECT_TRUE(cloth->owns_world());
  EXPECT_EQ(engine->mesh().node_count(), 57u * 57u);
  EXPECT_EQ(engine->mesh().triangle_count(), 6272u);
  expect_scene_error([&] { factory(patch_settings(1, 5), kGravity); }, {"cloth.nodes_x must be >= 2"});
  expect_scene_error([&] { factory(ClothSettings{}, Vec3(0, std::nan(""), 0)); }, {"gravity must be finite"});
}

}  // namespace
}  // namespace drench::bullet
