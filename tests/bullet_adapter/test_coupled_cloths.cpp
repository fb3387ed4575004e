// Several cloths in one CoupledWorld (issue 40): one fluid, one Bullet step per coupled step, each cloth
// catching water without a leak, wetting weighed in each cloth's own Bullet masses, ropes refused, and
// every bad call refused with nothing changed.

#include <drench/bullet/coupled_world.hpp>

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <drench/bullet/soft_body_builder.hpp>
#include "bullet_test_helpers.hpp"

namespace drench::bullet {
namespace {

using test::bullet_tolerance;
using test::expect_scene_error;

constexpr double kDt = 1e-3;
constexpr double kClothY = 0.5;               // both patches lie at this height (unit: m)
constexpr double kClothSize = 0.3;            // side of each square patch (unit: m)
constexpr double kClothX[2] = {-0.25, 0.25};  // their centres along x; z = 0 (unit: m)

/// Two nozzles, one 6 cm above the middle of each patch.
SceneConfig two_jets() {
  SceneConfig scene;
  scene.source = "two jets";
  scene.fluid.particle_spacing = 0.01;
  scene.time.dt = kDt;
  for (const double x : kClothX) {
    EmitterSettings jet;
    jet.kind = EmitterSettings::Kind::NOZZLE;
    jet.nozzle.center = Vec3(x, kClothY + 0.06, 0.0);
    jet.nozzle.radius = 0.02;
    jet.nozzle.speed = 1.0;
    jet.nozzle.max_particles = 300;
    scene.emitters.push_back(jet);
  }
  scene.effects = {"coupling", "leak_audit"};
  return scene;
}

/// A game's world with two square patches side by side, corners pinned, of total masses `mass[0]` and
/// `mass[1]` (unit: kg), a free rigid sphere far away, and a count of the world's steps.
struct TwoClothWorld : test::SoftRigidWorld {
  btSphereShape sphere_shape{0.05};
  btDefaultMotionState motion_state{btTransform(btQuaternion::getIdentity(), btVector3(2, 5, 2))};
  btRigidBody sphere{1.0, &motion_state, &sphere_shape, btVector3(0.001, 0.001, 0.001)};
  std::vector<btSoftBody*> cloths;
  btSoftBody* rope = nullptr;
  int steps = 0;

  explicit TwoClothWorld(double mass0 = 0.018, double mass1 = 0.018) {
    const btVector3 gravity(0, -9.81, 0);
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;
    const double masses[2] = {mass0, mass1};
    for (int c = 0; c < 2; ++c) {
      const double h = 0.5 * kClothSize;
      const double x = kClothX[c];
      btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(
          world.getWorldInfo(), btVector3(x - h, kClothY, -h), btVector3(x + h, kClothY, -h),
          btVector3(x - h, kClothY, h), btVector3(x + h, kClothY, h), 13, 13, 1 + 2 + 4 + 8, true);
      cloth->getCollisionShape()->setMargin(0.005);
      cloth->m_cfg.piterations = 4;
      cloth->setTotalMass(masses[c]);  // keeps the pins (fromfaces = false)
      world.addSoftBody(cloth);
      cloths.push_back(cloth);
    }
    world.addRigidBody(&sphere);
    world.setInternalTickCallback(
        [](btDynamicsWorld* w, btScalar) { ++static_cast<TwoClothWorld*>(w->getWorldUserInfo())->steps; },
        this);
  }
  /// Adds a rope of 10 nodes (links, no faces) to the world, after the cloths.
  void add_rope() {
    rope =
        btSoftBodyHelpers::CreateRope(world.getWorldInfo(), btVector3(0, 1, 0), btVector3(0.2, 1, 0), 8, 1);
    world.addSoftBody(rope);
  }
  /// Removes cloth c from the world and deletes it, as a game that is done with it does.
  void delete_cloth(int c) {
    world.removeSoftBody(cloths[c]);
    delete cloths[c];
    cloths[c] = nullptr;
  }
  ~TwoClothWorld() {
    world.removeRigidBody(&sphere);
    for (btSoftBody* cloth : cloths) {
      if (!cloth) continue;
      world.removeSoftBody(cloth);
      delete cloth;
    }
    if (rope) {
      world.removeSoftBody(rope);
      delete rope;
    }
  }
};

/// Particles over cloth c's square, between its lowest node less 2 cm and 5 cm over its rest height: water
/// the cloth holds (or that runs off its edge).
std::size_t particles_on(const CoupledWorld& coupled, int c) {
  const ClothMesh& mesh = coupled.cloth_mesh();
  const std::size_t first = coupled.cloths().first_node(c);
  double lowest = kClothY;
  for (std::size_t i = first; i < first + coupled.cloths().node_count(c); ++i)
    lowest = std::min(lowest, mesh.positions_t1[i].y());
  std::size_t count = 0;
  for (const Vec3& x : coupled.particles().positions) {
    const bool over = std::abs(x.x() - kClothX[c]) < 0.5 * kClothSize && std::abs(x.z()) < 0.5 * kClothSize;
    if (over && x.y() > lowest - 0.02 && x.y() < kClothY + 0.05) ++count;
  }
  return count;
}

TEST(CoupledCloths, TwoClothsCatchTheirJetsWithoutLeaksInOneBulletStepPerStep) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, user.cloths, two_jets());
  ASSERT_EQ(coupled.cloth_count(), 2u);
  std::uint64_t leaks = 0;
  const int steps = 250;
  for (int n = 1; n <= steps; ++n) {
    const CoupledStepReport report = coupled.step();
    ASSERT_FALSE(report.failed()) << "step " << n << ": " << report.fluid.describe();
    ASSERT_EQ(user.steps, n) << "one Bullet step per coupled step, whatever the number of cloths";
    leaks += report.leak_stats.leaks;
  }
  EXPECT_EQ(leaks, 0u);
  // Both cloths were moved by their water: their middles sag below the rest height.
  for (int c = 0; c < 2; ++c) {
    const btSoftBody& body = coupled.cloth(c).body();
    EXPECT_LT(body.m_nodes[6 * 13 + 6].m_x.y(), kClothY - 1e-3) << "cloth " << c;
  }
  // Each nozzle emits 300 particles; each cloth holds most of its own jet's.
  for (int c = 0; c < 2; ++c) {
    const std::size_t on = particles_on(coupled, c);
    ::testing::Test::RecordProperty("particles_on_cloth_" + std::to_string(c), static_cast<int>(on));
    EXPECT_GT(on, 200u) << "cloth " << c;
  }
  // No particle below either cloth's square: none went through.
  for (const Vec3& x : coupled.particles().positions) {
    for (int c = 0; c < 2; ++c) {
      const bool over = std::abs(x.x() - kClothX[c]) < 0.4 * kClothSize && std::abs(x.z()) < 0.4 * kClothSize;
      if (over) {
        EXPECT_GT(x.y(), kClothY - 0.1) << "under cloth " << c;
      }
    }
  }
}

TEST(CoupledCloths, EveryClothOfTheWorldIsCoupledInTheWorldsOrderAndFoundBack) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, two_jets());
  ASSERT_EQ(coupled.cloth_count(), 2u);
  const BulletClothSet& set = coupled.cloths();
  const ClothMesh& mesh = coupled.cloth_mesh();
  EXPECT_EQ(mesh.node_count(), 2u * 169u);
  EXPECT_EQ(mesh.triangle_count(), 2u * 288u);
  for (int c = 0; c < 2; ++c) {
    const btSoftBody& body = coupled.cloth(c).body();
    EXPECT_EQ(&body, user.world.getSoftBodyArray()[c]);
    EXPECT_EQ(set.first_node(c), 169u * c);
    EXPECT_EQ(set.first_triangle(c), 288u * c);
    // Every node and face of the mesh is its cloth's, at its own index.
    for (int i = 0; i < body.m_nodes.size(); ++i) {
      const ClothElement at = set.locate_node(static_cast<std::int64_t>(set.first_node(c)) + i);
      ASSERT_EQ(at.cloth, c);
      ASSERT_EQ(at.index, i);
      ASSERT_EQ(mesh.positions_t0[set.first_node(c) + i], to_vec3(body.m_nodes[i].m_x));
    }
    for (int f = 0; f < body.m_faces.size(); ++f) {
      const std::size_t global = set.first_triangle(c) + f;
      const ClothElement at = set.locate_triangle(static_cast<std::int64_t>(global));
      ASSERT_EQ(at.cloth, c);
      ASSERT_EQ(at.index, f);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(mesh.triangles[global][k],
                  set.first_node(c) + static_cast<std::size_t>(node_index(body, body.m_faces[f].m_n[k])));
      }
    }
  }
  EXPECT_EQ(set.locate_triangle(2 * 288).cloth, -1) << "past the cloths' faces: a static mesh's";
  EXPECT_EQ(set.locate_node(-1).cloth, -1);
}

/// Movable nodes' Bullet masses (1 / m_im), 0 for pinned ones.
ScalarArray bullet_masses(const btSoftBody& body) {
  ScalarArray m(body.m_nodes.size(), 0.0);
  for (int i = 0; i < body.m_nodes.size(); ++i)
    if (body.m_nodes[i].m_im > 0) m[i] = 1.0 / body.m_nodes[i].m_im;
  return m;
}

SceneConfig wet_two_jets() {
  SceneConfig scene = two_jets();
  scene.wetting.max_saturation = 20.0;     // room for several particles per node,
  scene.wetting.absorption_rate = 1000.0;  // taken whole in a step or two
  scene.effects = {"coupling", "leak_audit", "wetting"};
  return scene;
}

TEST(CoupledCloths, WettingChangesEachClothsBulletMassByTheWaterItHolds) {
  TwoClothWorld user(0.018, 0.036);
  const ScalarArray dry[2] = {bullet_masses(*user.cloths[0]), bullet_masses(*user.cloths[1])};
  CoupledWorld coupled(user.world, user.cloths, wet_two_jets());
  for (int n = 0; n < 200; ++n) {
    const CoupledStepReport report = coupled.step();
    ASSERT_FALSE(report.failed()) << "step " << n << ": " << report.fluid.describe();
  }
  const ScalarArray& water = coupled.simulation().wetting()->water();
  const double particle_mass = coupled.fluid().particle_mass();
  for (int c = 0; c < 2; ++c) {
    const std::size_t first = coupled.cloths().first_node(c);
    const ScalarArray wet = bullet_masses(coupled.cloth(c).body());
    double mass_change = 0.0, held_by_moving = 0.0, held = 0.0, wet_mass = 0.0;
    for (std::size_t i = 0; i < wet.size(); ++i) {
      held += water[first + i];
      if (dry[c][i] == 0.0) {
        EXPECT_EQ(wet[i], 0.0) << "a pinned node stays pinned";
        continue;
      }
      mass_change += wet[i] - dry[c][i];
      held_by_moving += water[first + i];
      wet_mass += wet[i];
    }
    ::testing::Test::RecordProperty("water_held_by_cloth_" + std::to_string(c) + "_kg", std::to_string(held));
    EXPECT_GT(held_by_moving, 20.0 * particle_mass) << "cloth " << c << " took the water of its jet";
    EXPECT_DOUBLE_EQ(coupled.water_held(c), held);
    ::testing::Test::RecordProperty("bullet_mass_change_minus_water_cloth_" + std::to_string(c) + "_kg",
                                    format_number(mass_change - held_by_moving));
    // Each node's 1 / (1 / m_dry + water), inverted again: its rounding in Bullet's precision, per node.
    EXPECT_NEAR(mass_change, held_by_moving, bullet_tolerance(1e-15, wet_mass, 4.0 * 169)) << "cloth " << c;
  }
  // Every kilogram is in the fluid or in a cloth.
  const ScalarArray& m = coupled.particles().masses;
  const double fluid = std::accumulate(m.begin(), m.end(), 0.0);
  EXPECT_NEAR(fluid + coupled.water_held(0) + coupled.water_held(1), coupled.simulation().emitted_mass(),
              1e-12 * coupled.simulation().emitted_mass());
}

TEST(CoupledCloths, CapacitiesComeFromEachClothsOwnBulletMasses) {
  // Cloth 1 weighs twice cloth 0, node for node.
  TwoClothWorld user(0.018, 0.036);
  const SceneConfig scene = wet_two_jets();
  CoupledWorld coupled(user.world, user.cloths, scene);
  const ScalarArray& capacity = coupled.simulation().wetting()->capacities();
  const double saturation = scene.wetting.max_saturation;
  for (int c = 0; c < 2; ++c) {
    const btSoftBody& body = coupled.cloth(c).body();
    const ScalarArray area = node_masses_from_area(body, 1.0);  // a third of each face's area (m^2)
    // The cloth's mean area density: the mass Bullet moves (setTotalMass's) over the area of the moving
    // nodes, a third of each face's area to each node.
    double pinned_area = 0.0;
    for (int i = 0; i < body.m_nodes.size(); ++i)
      if (body.m_nodes[i].m_im == 0) pinned_area += area[i];
    const double density = (c == 0 ? 0.018 : 0.036) / (kClothSize * kClothSize - pinned_area);
    const std::size_t first = coupled.cloths().first_node(c);
    for (int i = 0; i < body.m_nodes.size(); ++i) {
      const double im = body.m_nodes[i].m_im;
      // A moving node: its Bullet mass; a pinned corner: its faces' area at the cloth's mean density.
      const double expected = im > 0 ? saturation / im : saturation * density * area[i];
      ASSERT_NEAR(capacity[first + i], expected, bullet_tolerance(1e-12 * expected, expected, 64.0))
          << c << ", " << i;
    }
  }
  for (std::size_t i = 0; i < 169; ++i)
    ASSERT_NEAR(capacity[169 + i], 2.0 * capacity[i],
                bullet_tolerance(1e-12 * capacity[i], capacity[i], 64.0))
        << i;

  // A scene that gives its `cloth` sets the area density explicitly: every cloth weighs the same then.
  SceneConfig explicit_density = scene;
  explicit_density.cloth = ClothSettings{};
  explicit_density.cloth->area_density = 0.5;
  CoupledWorld set(user.world, user.cloths, explicit_density);
  const ScalarArray& capacity_set = set.simulation().wetting()->capacities();
  for (int c = 0; c < 2; ++c) {
    // Each cloth's own areas: a single-precision Bullet rounds the two cloths' positions differently.
    const ScalarArray area = node_masses_from_area(set.cloth(c).body(), 1.0);
    for (std::size_t i = 0; i < 169; ++i) {
      const double expected = saturation * 0.5 * area[i];
      ASSERT_NEAR(capacity_set[169 * c + i], expected, 1e-12 * expected) << c << ", " << i;
    }
  }
  for (std::size_t i = 0; i < 169; ++i) {
    ASSERT_NEAR(capacity_set[169 + i], capacity_set[i],
                bullet_tolerance(1e-12 * capacity_set[i], capacity_set[i], 64.0))
        << "the heavier cloth holds no more: " << i;
  }
}

TEST(CoupledCloths, ARopeAndOtherBadListsAreRefusedNamingTheIndex) {
  TwoClothWorld user;
  user.add_rope();
  const SceneConfig scene = two_jets();
  expect_scene_error(
      [&] {
        CoupledWorld(user.world, {user.cloths[0], user.rope}, scene);
      },
      {"soft body 1 has no faces", "10 nodes, 9 links: a rope?", "would let it through"});
  // Every soft body of the world: the rope is its third.
  expect_scene_error([&] { CoupledWorld(user.world, scene); }, {"soft body 2 has no faces"});
  expect_scene_error(
      [&] {
        CoupledWorld(user.world, {user.cloths[0], nullptr}, scene);
      },
      {"soft body 1 is null"});
  expect_scene_error(
      [&] {
        CoupledWorld(user.world, {user.cloths[1], user.cloths[1]}, scene);
      },
      {"soft body 1 is soft body 0 again"});
  expect_scene_error([&] { CoupledWorld(user.world, std::vector<btSoftBody*>{}, scene); },
                     {"the list of cloths is empty"});
  user.world.removeSoftBody(user.cloths[1]);
  expect_scene_error([&] { CoupledWorld(user.world, user.cloths, scene); },
                     {"soft body 1 is not in the Bullet world"});
  user.world.addSoftBody(user.cloths[1]);
}

TEST(CoupledCloths, AnEmptyWorldHasNoClothToCouple) {
  test::SoftRigidWorld bullet;
  btSoftRigidDynamicsWorld& world = bullet.world;
  world.setGravity(btVector3(0, -9.81, 0));
  world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);
  expect_scene_error([&] { CoupledWorld{world, two_jets()}; }, {"has no soft body", "two jets"});
}

/// Everything a step would change: time, steps, particles, every node's state and mass, the world's steps.
struct Snapshot {
  double time;
  std::int64_t steps;
  Vec3Array positions, velocities;
  std::vector<btVector3> nodes;
  std::vector<btScalar> inverse_masses;
  int world_steps;

  Snapshot(const CoupledWorld& coupled, const std::vector<const btSoftBody*>& bodies, int steps_of_world)
      : time(coupled.time()),
        steps(coupled.steps()),
        positions(coupled.particles().positions),
        velocities(coupled.particles().velocities),
        world_steps(steps_of_world) {
    for (const btSoftBody* body : bodies) {
      for (int i = 0; i < body->m_nodes.size(); ++i) {
        nodes.push_back(body->m_nodes[i].m_x);
        nodes.push_back(body->m_nodes[i].m_v);
        inverse_masses.push_back(body->m_nodes[i].m_im);
      }
    }
  }
  bool operator==(const Snapshot& o) const {
    return time == o.time && steps == o.steps && positions == o.positions && velocities == o.velocities &&
           nodes == o.nodes && inverse_masses == o.inverse_masses && world_steps == o.world_steps;
  }
};

/// Expects `f` to throw E whose message contains every one of `parts`.
template <typename E>
void expect_throw(const std::function<void()>& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "nothing thrown";
  } catch (const E& e) {
    for (const auto& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "message: " << e.what() << "\nexpected: " << part;
  }
}

// Coupled as every soft body of the world, a soft body the game added later was not coupled: 1,538 of
// 1,932 particles passed through a cloth added after construction, every step reported ok.
TEST(CoupledCloths, ASoftBodyAddedAfterEveryOneWasCoupledIsRefused) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, two_jets());
  ASSERT_TRUE(coupled.step().ok());
  const std::vector<const btSoftBody*> bodies = {user.cloths[0], user.cloths[1]};
  const Snapshot before(coupled, bodies, user.steps);
  user.add_rope();
  expect_throw<Error>([&] { coupled.step(); },
                      {"the world has 3 soft bodies, 2 when this CoupledWorld coupled every one"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
}

TEST(CoupledWorldChecks, ABadTimeStepIsRefusedAndChangesNothing) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, user.cloths, wet_two_jets());
  for (int n = 0; n < 40; ++n)
    ASSERT_TRUE(coupled.step().ok());
  ASSERT_GT(coupled.particles().size(), 0u);
  const std::vector<const btSoftBody*> bodies = {user.cloths[0], user.cloths[1]};
  const Snapshot before(coupled, bodies, user.steps);
  const double inf = std::numeric_limits<double>::infinity();
  const std::pair<double, const char*> bad[] = {{0.0, "got 0 s"},
                                                {-1.0 / 60.0, "got -0.01666"},
                                                {std::nan(""), "got nan s"},
                                                {inf, "got inf s"},
                                                {-inf, "got -inf s"}};
  for (const auto& [dt, shown] : bad) {
    expect_throw<std::invalid_argument>([&] { coupled.step(dt); },
                                        {"CoupledWorld::step: dt must be > 0 and finite", shown});
    EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before) << "dt " << dt;
  }
  // One step of time.dt / 200 sent a cloth node to 827 m/s (the coupling's corrections over a sliver of
  // time); a game's frame remainder must be carried over instead.
  expect_throw<std::invalid_argument>([&] { coupled.step(kDt / 200); },
                                      {"CoupledWorld::step: dt", "less than the scene's time.dt / 16"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
  EXPECT_TRUE(coupled.step(kDt / 16).ok()) << "the shortest step allowed";
  EXPECT_TRUE(coupled.step(kDt).ok()) << "a good step after the refused ones";
  EXPECT_EQ(coupled.steps(), before.steps + 2);
  // The cloth engines refuse them too.
  expect_throw<std::invalid_argument>([&] { coupled.cloth(0).step(-1.0); },
                                      {"BulletCloth::step: dt", "got -1 s"});
  expect_throw<std::invalid_argument>([&] { coupled.cloths().end_step(0.0); },
                                      {"BulletClothSet::end_step: dt"});
}

TEST(CoupledWorldChecks, AClothRemovedOrDeletedIsNamedAtTheNextStepAndNothingChanges) {
  TwoClothWorld user;
  auto coupled = std::make_unique<CoupledWorld>(user.world, user.cloths, two_jets());
  for (int n = 0; n < 40; ++n)
    ASSERT_TRUE(coupled->step().ok());
  const std::vector<const btSoftBody*> first_only = {user.cloths[0]};
  user.world.removeSoftBody(user.cloths[1]);
  const Snapshot before(*coupled, first_only, user.steps);
  expect_throw<Error>([&] { coupled->step(); },
                      {"cloth 1 is no longer in the Bullet world", "removeSoftBody"});
  EXPECT_TRUE(Snapshot(*coupled, first_only, user.steps) == before);
  // Back in the world, it steps again.
  user.world.addSoftBody(user.cloths[1]);
  EXPECT_TRUE(coupled->step().ok());
  // Removed and deleted: named without being read, and the CoupledWorld still goes cleanly.
  user.delete_cloth(1);
  const Snapshot after_delete(*coupled, first_only, user.steps);
  expect_throw<Error>([&] { coupled->step(); }, {"cloth 1 is no longer in the Bullet world"});
  EXPECT_TRUE(Snapshot(*coupled, first_only, user.steps) == after_delete);
  coupled.reset();
}

TEST(CoupledWorldChecks, AClothThatLostNodesIsNamed) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, user.cloths, two_jets());
  ASSERT_TRUE(coupled.step().ok());
  // A node added is followed (a tear adds nodes); taken away again, the cloth has fewer than at the last
  // step.
  user.cloths[0]->appendNode(btVector3(0, 2, 0), 1.0);
  ASSERT_TRUE(coupled.step().ok());
  EXPECT_EQ(coupled.cloths().node_count(0), 170u);
  btSoftBody& cloth = *user.cloths[0];
  cloth.m_ndbvt.remove(cloth.m_nodes[169].m_leaf);
  cloth.m_nodes.pop_back();
  const std::vector<const btSoftBody*> bodies = {user.cloths[0], user.cloths[1]};
  const Snapshot before(coupled, bodies, user.steps);
  expect_throw<Error>([&] { coupled.step(); }, {"cloth 0 has 169 nodes, but had 170 at the last step"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
}

TEST(CoupledWorldChecks, AClothWithoutFacesLeftIsNamed) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, user.cloths, two_jets());
  ASSERT_TRUE(coupled.step().ok());
  // The game took every face out (the water would pass through what is left, as through a rope).
  btSoftBody& cloth = *user.cloths[1];
  for (int f = 0; f < cloth.m_faces.size(); ++f) {
    if (cloth.m_faces[f].m_leaf) cloth.m_fdbvt.remove(cloth.m_faces[f].m_leaf);
  }
  cloth.m_faces.clear();
  const std::vector<const btSoftBody*> bodies = {user.cloths[0], user.cloths[1]};
  const Snapshot before(coupled, bodies, user.steps);
  expect_throw<Error>([&] { coupled.step(); }, {"cloth 1 has no faces left"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
}

/// What a run of TwoClothWorld with wet_two_jets water shows after a tear of cloth 0 (or none).
struct TearRun {
  int nodes0 = 0;            // cloth 0's nodes at the end
  std::size_t through = 0;   // the most particles at once under cloth 0's middle, 10 cm below it or more
  double water_over1 = 0.0;  // cloth 1's water, held and on it, at the end (unit: kg)
  // The largest |Bullet mass - dry - water| of cloth 1's nodes, over its tolerance (each node's wet mass
  // rounded in Bullet's precision); <= 1 passes.
  double worst_node1 = 0.0;
  double dry_error0 = 0.0;   // cloth 0's Bullet mass less its water, less its dry mass (unit: kg)
  double dry_mass0 = 0.0;    // cloth 0's dry mass (unit: kg)
  double unaccounted = 0.0;  // emitted mass less the fluid's and the cloths' water (unit: kg)
  double emitted = 0.0;      // (unit: kg)
  std::uint64_t leaks = 0;
};

/// 300 steps of water onto both cloths, a cut of cloth 0 across its middle when `tear`, 400 steps more.
TearRun run_and_tear(bool tear) {
  TwoClothWorld user;
  const ScalarArray dry0 = bullet_masses(*user.cloths[0]);
  const ScalarArray dry1 = bullet_masses(*user.cloths[1]);
  SceneConfig scene = wet_two_jets();
  scene.wetting.max_saturation = 200.0;  // room for the jet's water: no node drips
  scene.wetting.absorption_rate = 10.0;  // most of the water stays water, to run through the tear
  CoupledWorld coupled(user.world, user.cloths, scene);
  TearRun run;
  const auto step = [&](int n) {
    const CoupledStepReport report = coupled.step();
    ASSERT_TRUE(report.ok() && !report.failed()) << "step " << n << ": " << report.fluid.describe();
    run.leaks += report.leak_stats.leaks;
  };
  const auto below = [&](int c) {
    std::size_t count = 0;
    for (const Vec3& x : coupled.particles().positions) {
      const bool over = std::abs(x.x() - kClothX[c]) < 0.4 * kClothSize && std::abs(x.z()) < 0.4 * kClothSize;
      if (over && x.y() < kClothY - 0.1) ++count;
    }
    return count;
  };
  for (int n = 0; n < 300; ++n) {
    step(n);
    if (::testing::Test::HasFatalFailure()) return run;
  }
  EXPECT_EQ(below(0), 0u);
  EXPECT_GT(coupled.water_held(0), 0.0);
  if (tear) test::refine_across(*user.cloths[0], kClothX[0] + 0.01);
  run.nodes0 = user.cloths[0]->m_nodes.size();
  for (int n = 0; n < 400; ++n) {
    step(300 + n);
    if (::testing::Test::HasFatalFailure()) return run;
    run.through = std::max(run.through, below(0));
  }
  EXPECT_EQ(coupled.cloths().node_count(0), static_cast<std::size_t>(run.nodes0));
  EXPECT_EQ(coupled.cloths().first_node(1), static_cast<std::size_t>(run.nodes0));
  // Cloth 1's water: held, and in particles over it (particles_on's).
  const ClothMesh& mesh = coupled.cloth_mesh();
  double lowest = kClothY;
  for (std::size_t i = run.nodes0; i < run.nodes0 + coupled.cloths().node_count(1); ++i)
    lowest = std::min(lowest, mesh.positions_t1[i].y());
  run.water_over1 = coupled.water_held(1);
  const ParticleSet& p = coupled.particles();
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec3& x = p.positions[k];
    const bool over = std::abs(x.x() - kClothX[1]) < 0.5 * kClothSize && std::abs(x.z()) < 0.5 * kClothSize;
    if (over && x.y() > lowest - 0.02 && x.y() < kClothY + 0.05) run.water_over1 += p.masses[k];
  }
  const ScalarArray& water = coupled.simulation().wetting()->water();
  const btSoftBody& cloth1 = coupled.cloth(1).body();
  for (int i = 0; i < cloth1.m_nodes.size(); ++i) {
    if (dry1[i] == 0.0) continue;
    const double wet = 1.0 / cloth1.m_nodes[i].m_im;
    const double error = wet - dry1[i] - water[run.nodes0 + i];
    run.worst_node1 = std::max(run.worst_node1, std::abs(error) / bullet_tolerance(1e-15, wet, 4.0));
  }
  const btSoftBody& cloth0 = coupled.cloth(0).body();
  run.dry_mass0 = std::accumulate(dry0.begin(), dry0.end(), 0.0);
  run.dry_error0 = -run.dry_mass0;
  for (int i = 0; i < cloth0.m_nodes.size(); ++i) {
    if (cloth0.m_nodes[i].m_im > 0) run.dry_error0 += 1.0 / cloth0.m_nodes[i].m_im - water[i];
  }
  const double fluid = std::accumulate(p.masses.begin(), p.masses.end(), 0.0);
  run.emitted = coupled.simulation().emitted_mass();
  run.unaccounted = run.emitted - fluid - coupled.water_held(0) - coupled.water_held(1);
  return run;
}

// A game tears a cloth under water (Bullet's cutting, btSoftBody::refine: nodes and faces added, some of
// its mass moved to them): drench follows it. The water held in the torn cloth's sag runs through the tear;
// the other cloth, whose nodes now sit further along the coupling's mesh, keeps its water node for node and
// holds what it holds in the same run without the tear; both weigh their dry mass plus their water in
// Bullet; every kilogram is in the fluid or a cloth, and nothing leaks.
TEST(CoupledCloths, ATornClothIsFollowedAndItsWaterRunsThroughTheTear) {
  const TearRun whole = run_and_tear(false);
  ASSERT_FALSE(HasFatalFailure());
  const TearRun torn = run_and_tear(true);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_GT(torn.nodes0, 169) << "the cut added nodes";
  EXPECT_EQ(whole.leaks, 0u);
  EXPECT_EQ(torn.leaks, 0u);
  RecordProperty("particles_under_the_cloth_whole", static_cast<int>(whole.through));
  RecordProperty("particles_through_the_tear", static_cast<int>(torn.through));
  EXPECT_GT(torn.through, 2 * whole.through + 20) << "the water runs through the tear";
  RecordProperty("water_over_cloth_1_kg", format_number(torn.water_over1));
  EXPECT_NEAR(torn.water_over1, whole.water_over1, 0.01 * whole.water_over1)
      << "the other cloth holds what it holds without the tear";
  for (const TearRun* run : {&whole, &torn}) {
    EXPECT_LE(run->worst_node1, 1.0) << "cloth 1's nodes: dry plus water, over the tolerance";
    EXPECT_NEAR(run->dry_error0, 0.0,
                bullet_tolerance(1e-12 * run->dry_mass0, run->dry_mass0, 4.0 * run->nodes0))
        << "the torn cloth weighs its dry mass plus its water";
    EXPECT_NEAR(run->unaccounted, 0.0, 1e-12 * run->emitted) << "every kilogram in the fluid or a cloth";
  }
}

TEST(CoupledWorldChecks, RigidGravityOtherThanSoftBodyGravityIsRefusedAtConstructionAndAtStep) {
  TwoClothWorld user;
  user.world.setGravity(btVector3(0, -10, 0));  // the soft bodies keep -9.81
  expect_scene_error([&] { CoupledWorld(user.world, user.cloths, two_jets()); },
                     {"rigid-body gravity world.getGravity() (0, -10, 0)",
                      "soft-body gravity getWorldInfo().m_gravity (0, -9.81", "two jets"});
  user.world.setGravity(btVector3(0, -9.81, 0));
  CoupledWorld coupled(user.world, user.cloths, two_jets());
  for (int n = 0; n < 20; ++n)
    ASSERT_TRUE(coupled.step().ok());
  const std::vector<const btSoftBody*> bodies = {user.cloths[0], user.cloths[1]};
  // The game changes one gravity later: the next step is refused, and nothing moves.
  user.world.setGravity(btVector3(0, 0, 0));
  const Snapshot before(coupled, bodies, user.steps);
  expect_throw<Error>([&] { coupled.step(); }, {"rigid-body gravity world.getGravity() (0, 0, 0) differs"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
  user.world.setGravity(btVector3(0, -9.81, 0));
  user.world.getWorldInfo().m_gravity = btVector3(0, -5, 0);
  expect_throw<Error>([&] { coupled.step(); }, {"getWorldInfo().m_gravity (0, -5, 0)"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
  // A NaN passed "differs by more than the tolerance", and every step then blamed a cloth node.
  const btScalar nan = std::numeric_limits<btScalar>::quiet_NaN();
  user.world.getWorldInfo().m_gravity = btVector3(0, nan, 0);
  expect_throw<Error>([&] { coupled.step(); }, {"getWorldInfo().m_gravity (0, nan, 0)"});
  user.world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);
  user.world.setGravity(btVector3(nan, -9.81, 0));
  expect_throw<Error>([&] { coupled.step(); }, {"rigid-body gravity world.getGravity() (nan, -9.81"});
  EXPECT_TRUE(Snapshot(coupled, bodies, user.steps) == before);
  user.world.setGravity(btVector3(0, -9.81, 0));
  user.world.getWorldInfo().m_gravity = btVector3(0, -9.81, 0);
  EXPECT_TRUE(coupled.step().ok());
}

TEST(CoupledWorldChecks, ClothIndicesOutOfRangeAreRefused) {
  TwoClothWorld user;
  CoupledWorld coupled(user.world, user.cloths, two_jets());
  expect_throw<std::out_of_range>([&] { coupled.cloth(2); }, {"cloth 2 out of range: 2 cloth(s) coupled"});
  expect_throw<std::out_of_range>([&] { coupled.water_held(7); }, {"cloth 7 out of range"});
  EXPECT_EQ(coupled.water_held(1), 0.0) << "without wetting";
}

}  // namespace
}  // namespace drench::bullet
