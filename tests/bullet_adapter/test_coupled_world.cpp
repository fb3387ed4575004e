// CoupledWorld: one Bullet step per coupled step, the documented order, the attach-mode checks, and the
// fluid built as the scene code builds it.

#include <drench/bullet/coupled_world.hpp>

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

#include <drench/scene/simulation.hpp>
#include "../assertions.hpp"
#include "bullet_test_helpers.hpp"

namespace drench::bullet {
namespace {

using test::bullet_tolerance;
using test::expect_scene_error;
using test::patch_settings;

constexpr double kDt = 1e-3;

SceneConfig jet_scene(double nozzle_height = 0.8) {
  SceneConfig scene;
  scene.source = "test scene";
  scene.fluid.particle_spacing = 0.01;
  scene.time.dt = kDt;
  EmitterSettings jet;
  jet.kind = EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = Vec3(0.1, nozzle_height, -0.2);
  jet.nozzle.radius = 0.02;
  jet.nozzle.speed = 1.5;
  jet.nozzle.max_particles = 500;
  scene.emitters.push_back(jet);
  scene.effects = {"coupling", "leak_audit"};
  return scene;
}

/// A user's world with a patch (corners pinned) and a free-falling rigid sphere, and a count of its steps.
struct UserWorld : test::SoftRigidWorld {
  btSphereShape sphere_shape{0.05};
  btDefaultMotionState motion_state{btTransform(btQuaternion::getIdentity(), btVector3(2, 5, 2))};
  btRigidBody sphere{1.0, &motion_state, &sphere_shape, btVector3(0.001, 0.001, 0.001)};
  btSoftBody* cloth = nullptr;
  int steps = 0;

  explicit UserWorld(const btVector3& gravity = btVector3(0, -9.81, 0)) {
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;
    cloth = btSoftBodyHelpers::CreatePatch(world.getWorldInfo(), btVector3(-0.2, 0.5, -0.5),
                                           btVector3(0.4, 0.5, -0.5), btVector3(-0.2, 0.5, 0.1),
                                           btVector3(0.4, 0.5, 0.1), 13, 13, 1 + 2 + 4 + 8, true);
    cloth->getCollisionShape()->setMargin(0.005);
    cloth->m_cfg.piterations = 4;
    cloth->setTotalMass(0.1);  // keeps the pins (fromfaces = false)
    world.addSoftBody(cloth);
    world.addRigidBody(&sphere);
    world.setInternalTickCallback(
        [](btDynamicsWorld* w, btScalar) { ++static_cast<UserWorld*>(w->getWorldUserInfo())->steps; }, this);
  }
  ~UserWorld() {
    world.removeRigidBody(&sphere);
    world.removeSoftBody(cloth);
    delete cloth;
  }
};

bool same_bits(const Vec3& a, const Vec3& b) {
  return std::memcmp(a.data(), b.data(), 3 * sizeof(double)) == 0;
}

TEST(CoupledWorld, WithoutFluidTheClothStepsAsTheEngineAlone) {
  SceneConfig scene;
  scene.time.dt = kDt;
  scene.cloth = patch_settings(21, 21);
  scene.effects = {"coupling"};
  CoupledWorld coupled(scene);
  BulletCloth alone(patch_settings(21, 21), scene.gravity);
  for (int n = 0; n < 20; ++n) {
    const CoupledStepReport report = coupled.step();
    EXPECT_TRUE(report.ok());
    alone.begin_step();
    alone.step(kDt);
    alone.end_step(kDt);
  }
  for (int i = 0; i < alone.body().m_nodes.size(); ++i) {
    ASSERT_TRUE(
        same_bits(to_vec3(coupled.cloth().body().m_nodes[i].m_x), to_vec3(alone.body().m_nodes[i].m_x)));
    ASSERT_TRUE(
        same_bits(to_vec3(coupled.cloth().body().m_nodes[i].m_v), to_vec3(alone.body().m_nodes[i].m_v)));
  }
  EXPECT_EQ(coupled.steps(), 20);
  EXPECT_NEAR(coupled.time(), 20 * kDt, 1e-15);
}

TEST(CoupledWorld, EachCoupledStepIsExactlyOneBulletStepOfTheUsersWorld) {
  UserWorld user;
  CoupledWorld coupled(user.world, *user.cloth, jet_scene());
  for (int n = 1; n <= 5; ++n) {
    coupled.step(kDt);
    EXPECT_EQ(user.steps, n);
    // The user's rigid bodies are stepped with the world: free fall, v = n g dt (n additions in Bullet's
    // precision).
    EXPECT_NEAR(user.sphere.getLinearVelocity().y(), -9.81 * n * kDt,
                bullet_tolerance(1e-12, n * 9.81 * n * kDt));
  }
}

TEST(CoupledWorld, StepRecordsStartAndEndOfBothSides) {
  UserWorld user;
  CoupledWorld coupled(user.world, *user.cloth, jet_scene());
  std::size_t emitted = 0;
  for (int n = 0; n < 30; ++n) {
    const Vec3 node_before = to_vec3(user.cloth->m_nodes[84].m_x);
    const CoupledStepReport report = coupled.step();
    ASSERT_TRUE(report.ok());
    EXPECT_TRUE(report.coupled);
    emitted += report.emitted;
    // The cloth's start is where the node was before the step, its end where Bullet (and the coupling) put
    // it.
    EXPECT_TRUE(same_bits(coupled.cloth_mesh().positions_t0[84], node_before));
    EXPECT_TRUE(same_bits(coupled.cloth_mesh().positions_t1[84], to_vec3(user.cloth->m_nodes[84].m_x)));
  }
  const ParticleSet& p = coupled.particles();
  EXPECT_GT(p.size(), 0u);
  EXPECT_EQ(static_cast<std::int64_t>(emitted), coupled.created());
  EXPECT_EQ(p.positions_t0.size(), p.size());
  for (std::size_t i = 0; i < p.size(); ++i)
    EXPECT_LT(p.positions_t0[i].y(), 0.8 + 1e-12);  // at or below the nozzle at the step's start (unit: m)
}

/// A flat square of 2 n^2 triangles at height y over [x0, x0 + size] x [z0, z0 + size], in a btTriangleMesh
/// (Bullet's own indexed storage, btScalar vertices, 32-bit indices) as a game would build level geometry.
std::unique_ptr<btTriangleMesh> square_mesh(int n, double size) {
  auto mesh = std::make_unique<btTriangleMesh>();
  auto node = [&](int i, int j) { return btVector3(size * i / n, 0.0, size * j / n); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh->addTriangle(node(i, j), node(i, j + 1), node(i + 1, j), true);
      mesh->addTriangle(node(i + 1, j), node(i, j + 1), node(i + 1, j + 1), true);
    }
  }
  return mesh;
}

TEST(CoupledWorld, ReadsTheWorldsStaticTriangleMeshesInWorldCoordinates) {
  UserWorld user;
  EXPECT_TRUE(static_triangle_meshes(user.world).empty()) << "a dynamic sphere is no static mesh";
  const std::unique_ptr<btTriangleMesh> storage = square_mesh(4, 0.2);
  btBvhTriangleMeshShape shape(storage.get(), true);
  shape.setLocalScaling(btVector3(2.0, 1.0, 0.5));
  const btTransform placed(btQuaternion(btVector3(0, 1, 0), btScalar(0.5)), btVector3(0.1, 0.65, -0.3));
  btDefaultMotionState motion(placed);
  btRigidBody ground(0.0, &motion, &shape);
  user.world.addRigidBody(&ground);
  const std::vector<TriangleMesh> meshes = static_triangle_meshes(user.world);
  user.world.removeRigidBody(&ground);
  ASSERT_EQ(meshes.size(), 1u);
  EXPECT_EQ(meshes[0].triangles.size(), 32u);
  // btTriangleMesh shares a vertex among the faces that use it (removeDuplicateVertices = true).
  EXPECT_EQ(meshes[0].positions.size(), 25u);
  const double tolerance = bullet_tolerance(1e-15, 1.0, 16);
  for (const Vec3& x : meshes[0].positions) {
    // Undo the transform and the scaling: the point lies on the square's plane and inside it.
    const btVector3 back = placed.inverse() * to_bt(x);
    EXPECT_NEAR(back.y(), 0.0, tolerance);
    EXPECT_GE(back.x() / 2.0, -tolerance);
    EXPECT_LE(back.x() / 2.0, 0.2 + tolerance);
    EXPECT_GE(back.z() / 0.5, -tolerance);
    EXPECT_LE(back.z() / 0.5, 0.2 + tolerance);
  }
}

TEST(CoupledWorld, StaticTriangleMeshesOfTheWorldHoldTheFluid) {
  UserWorld user;
  // Level geometry between the nozzle (y = 0.8) and the cloth (y = 0.5): the jet lands on it first.
  const std::unique_ptr<btTriangleMesh> storage = square_mesh(10, 0.2);
  btBvhTriangleMeshShape shape(storage.get(), true);
  btDefaultMotionState motion(btTransform(btQuaternion::getIdentity(), btVector3(0.0, 0.65, -0.3)));
  btRigidBody ground(0.0, &motion, &shape);
  user.world.addRigidBody(&ground);
  {
    CoupledWorld coupled(user.world, *user.cloth, jet_scene(0.8));
    std::uint64_t leaks = 0, contacts = 0;
    for (int n = 0; n < 200; ++n) {
      const CoupledStepReport report = coupled.step();
      ASSERT_TRUE(report.ok()) << "step " << n;
      leaks += report.leak_stats.leaks;
      contacts += report.coupling_stats.contacts;
    }
    EXPECT_EQ(leaks, 0u);
    EXPECT_GT(contacts, 0u) << "the jet reached the static mesh";
    const std::vector<RigidSurface>& surfaces = coupled.rigid_surfaces();
    ASSERT_EQ(surfaces.size(), 2u) << "the ground and the user's sphere";
    EXPECT_EQ(surfaces[0].motion, RigidMotion::DYNAMIC) << "the sphere, added first";
    EXPECT_EQ(surfaces[1].motion, RigidMotion::STATIC);
    EXPECT_EQ(surfaces[1].triangles.size(), 200u);
    std::size_t on_top = 0;
    for (const Vec3& x : coupled.particles().positions) {
      if (x.x() > 0.0 && x.x() < 0.2 && x.z() > -0.3 && x.z() < -0.1) {
        EXPECT_GT(x.y(), 0.65 - coupled.scene().coupling.cloth_thickness);
        ++on_top;
      }
    }
    EXPECT_GT(on_top, 50u) << "the static mesh holds water";
  }
  user.world.removeRigidBody(&ground);
}

TEST(CoupledWorld, FluidIsBuiltAsTheSceneRunnerBuildsIt) {
  UserWorld user;
  const SceneConfig scene = jet_scene(0.8);
  CoupledWorld coupled(user.world, *user.cloth, scene);
  EXPECT_EQ(coupled.speed_of_sound(), automatic_speed_of_sound(scene));
  EXPECT_EQ(coupled.fluid().particle_mass(), 1000.0 * 0.01 * 0.01 * 0.01);

  SceneConfig fixed = jet_scene();
  fixed.fluid.wcsph.speed_of_sound = 42.0;
  fixed.cloth = patch_settings(5, 5);
  CoupledWorld chosen(fixed);
  EXPECT_EQ(chosen.speed_of_sound(), 42.0);
}

TEST(CoupledWorld, StagesTheSceneDoesNotListAreNotBuilt) {
  UserWorld user;
  SceneConfig scene = jet_scene();
  scene.effects = {};
  CoupledWorld coupled(user.world, *user.cloth, scene);
  EXPECT_EQ(coupled.coupler(), nullptr);
  for (int n = 0; n < 5; ++n) {
    const CoupledStepReport report = coupled.step();
    EXPECT_TRUE(report.ok());
    EXPECT_FALSE(report.coupled);
    EXPECT_EQ(report.leak_stats.seconds, 0.0);
  }
  CoupledWorld listed(user.world, *user.cloth, jet_scene());
  ASSERT_NE(listed.coupler(), nullptr);
  const CoupledStepReport report = listed.step();
  EXPECT_TRUE(report.coupled);
  EXPECT_GT(report.leak_stats.seconds, 0.0);
}

TEST(CoupledWorld, KillRegionsRemoveParticlesAtTheEndOfTheStep) {
  SceneConfig scene = jet_scene(0.8);
  KillRegionSettings floor;
  floor.kind = KillRegionSettings::Kind::PLANE;
  floor.point = Vec3(0, 0.75, 0);
  floor.normal = Vec3(0, 1, 0);
  scene.kill_regions.push_back(floor);
  scene.cloth = patch_settings(5, 5);
  CoupledWorld coupled(scene);
  std::size_t removed = 0;
  for (int n = 0; n < 60; ++n)
    removed += coupled.step().removed;
  EXPECT_GT(removed, 0u);
  EXPECT_EQ(static_cast<std::int64_t>(removed), coupled.removed());
  const ParticleSet& p = coupled.particles();
  EXPECT_EQ(p.positions_t0.size(), p.size());
  for (const Vec3& x : p.positions)
    EXPECT_GE(x.y(), 0.75);
}

TEST(CoupledWorld, NonFiniteClothIsReportedAndNotCoupled) {
  UserWorld user;
  CoupledWorld coupled(user.world, *user.cloth, jet_scene());
  coupled.step();
  user.cloth->m_nodes[100].m_v.setY(std::numeric_limits<double>::infinity());
  const CoupledStepReport report = coupled.step();
  EXPECT_FALSE(report.ok());
  EXPECT_FALSE(report.coupled);
  EXPECT_GE(report.non_finite_node, 0);
}

// Each CoupledWorld steps its Bullet world once a step: two on one world, both stepped, stepped it twice a
// frame, and each one's cloth then started its steps where the other's step had left it (reported only
// later, as leaks). The one that steps after the other did is refused, changing nothing; a second one built
// to replace the first, or to inspect, is not.
TEST(CoupledWorld, TwoCoupledWorldsSteppingOneBulletWorldInTurnAreRefused) {
  UserWorld user;
  CoupledWorld first(user.world, *user.cloth, jet_scene());
  EXPECT_TRUE(first.step().ok());
  {
    CoupledWorld second(user.world, *user.cloth, jet_scene());
    EXPECT_TRUE(second.step().ok());
    EXPECT_EQ(user.steps, 2);
    const double time = first.time();
    EXPECT_TRUE(::drench::test::throws_containing<Error>(
        [&] { first.step(); }, {"another CoupledWorld stepped this Bullet world", "one CoupledWorld"}));
    EXPECT_EQ(first.time(), time);
    EXPECT_EQ(user.steps, 2) << "the refused step did not step the world";
    EXPECT_TRUE(second.step().ok()) << "the one that stepped last goes on";
  }
  CoupledWorld again(user.world, *user.cloth, jet_scene());  // built now, it may step
  EXPECT_TRUE(again.step().ok());
}

TEST(CoupledWorld, AttachRefusesASoftBodyGravityOtherThanTheScenes) {
  UserWorld user(btVector3(0, -10, 0));  // Bullet's default soft-body gravity
  expect_scene_error([&] { CoupledWorld(user.world, *user.cloth, jet_scene()); },
                     {"gravity (0, -9.81", "(test scene) differs", "getWorldInfo().m_gravity (0, -10, 0)"});
}

TEST(CoupledWorld, AttachRefusesAClothThatIsNotInTheWorld) {
  UserWorld user;
  btSoftBody* stray =
      btSoftBodyHelpers::CreatePatch(user.world.getWorldInfo(), btVector3(0, 0, 0), btVector3(1, 0, 0),
                                     btVector3(0, 0, 1), btVector3(1, 0, 1), 3, 3, 0, false);
  expect_scene_error([&] { CoupledWorld(user.world, *stray, jet_scene()); },
                     {"not in the Bullet world", "addSoftBody"});
  delete stray;
}

// A game passes its measured frame time to step_frame, which takes it in the scene's fixed steps as Bullet's
// stepSimulation(frame, max_steps, fixed step) does: frames of 1/60 s are four steps of 1/240 s each, a frame
// shorter than a step is carried to the next, and a hitch of a quarter second takes at most max_steps steps
// and drops the rest. Each step is one Bullet step of the game's world, whose falling sphere gains g dt per
// step and no more; passed to step(dt), the hitch would have been one step of 0.25 s, 60 times the scene's.
TEST(CoupledWorldFrames, AHitchIsTakenInFixedStepsAndTheRestDropped) {
  UserWorld user;
  SceneConfig scene = jet_scene();
  const double dt = 1.0 / 240.0;
  scene.time.dt = dt;
  CoupledWorld coupled(user.world, *user.cloth, scene);
  const auto expect_fallen_for = [&](int steps) {
    EXPECT_EQ(user.steps, steps);
    EXPECT_EQ(coupled.steps(), steps);
    EXPECT_NEAR(coupled.time(), steps * dt, 1e-12);
    EXPECT_NEAR(user.sphere.getLinearVelocity().y(), -9.81 * steps * dt,
                bullet_tolerance(1e-12, 9.81 * steps * steps * dt));
  };
  // Frames that add up to a step within rounding take it: (0.05 dt + 0.95 dt) / dt is 1 - 2e-16.
  EXPECT_EQ(coupled.step_frame(0.05 * dt, 4).steps.size(), 0u);
  CoupledFrameReport r = coupled.step_frame(0.95 * dt, 4);
  EXPECT_EQ(r.steps.size(), 1u);
  EXPECT_LT(r.carried_seconds, 1e-15);
  expect_fallen_for(1);
  for (int frame = 1; frame <= 3; ++frame) {
    r = coupled.step_frame(1.0 / 60.0, 4);
    EXPECT_EQ(r.steps.size(), 4u) << "frame " << frame;
    EXPECT_TRUE(r.ok());
    EXPECT_EQ(r.dropped_seconds, 0.0);
    EXPECT_LT(r.carried_seconds, 1e-12);
    expect_fallen_for(1 + 4 * frame);
  }
  // Two frames of 0.6 steps: the first takes none, the second one, carrying 0.2 of a step.
  r = coupled.step_frame(0.6 * dt, 4);
  EXPECT_EQ(r.steps.size(), 0u);
  EXPECT_NEAR(r.carried_seconds, 0.6 * dt, 1e-15);
  r = coupled.step_frame(0.6 * dt, 4);
  EXPECT_EQ(r.steps.size(), 1u);
  EXPECT_NEAR(r.carried_seconds, 0.2 * dt, 1e-15);
  expect_fallen_for(14);
  // The hitch: 60.2 steps owed, 4 taken, 56 dropped, 0.2 carried.
  r = coupled.step_frame(0.25, 4);
  EXPECT_EQ(r.steps.size(), 4u);
  EXPECT_TRUE(r.ok());
  EXPECT_NEAR(r.dropped_seconds, 56 * dt, 1e-12);
  EXPECT_NEAR(r.carried_seconds, 0.2 * dt, 1e-12);
  expect_fallen_for(18);
  // Bullet's default of one step a frame.
  r = coupled.step_frame(0.25, 1);
  EXPECT_EQ(r.steps.size(), 1u);
  EXPECT_NEAR(r.dropped_seconds, 59 * dt, 1e-12);
  expect_fallen_for(19);

  // Bad values are refused, naming them, and change nothing: not the steps, not the time carried.
  for (const double bad : {-0.001, std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(
        {
          try {
            coupled.step_frame(bad, 4);
          } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("frame_seconds must be >= 0 and finite"), std::string::npos)
                << e.what();
            throw;
          }
        },
        std::invalid_argument);
  }
  EXPECT_THROW(coupled.step_frame(1.0 / 60.0, 0), std::invalid_argument);
  EXPECT_THROW(coupled.step_frame(1.0 / 60.0, -3), std::invalid_argument);
  expect_fallen_for(19);
  r = coupled.step_frame(0.8 * dt, 4);
  EXPECT_EQ(r.steps.size(), 1u) << "the 0.2 step carried before the refused calls is still owed";
  expect_fallen_for(20);

  // A step that is not ok ends the frame, its steps left counted as dropped.
  user.cloth->m_nodes[100].m_v.setY(std::numeric_limits<double>::infinity());
  r = coupled.step_frame(1.0 / 60.0, 4);
  ASSERT_EQ(r.steps.size(), 1u);
  EXPECT_FALSE(r.ok());
  EXPECT_TRUE(r.failed());
  EXPECT_NEAR(r.dropped_seconds, 3 * dt, 1e-12);
  EXPECT_EQ(user.steps, 21);

  // The largest frame there is takes its step and drops a finite time.
  r = coupled.step_frame(std::numeric_limits<double>::max(), 1);
  EXPECT_EQ(r.steps.size(), 1u);
  EXPECT_TRUE(std::isfinite(r.dropped_seconds)) << r.dropped_seconds;
  EXPECT_GE(r.carried_seconds, 0.0);
  EXPECT_LT(r.carried_seconds, dt);
}

TEST(CoupledWorld, BadSceneTimeStepIsRefused) {
  SceneConfig scene = jet_scene();
  scene.time.dt = 0.0;
  scene.cloth = patch_settings(5, 5);
  expect_scene_error([&] { CoupledWorld{scene}; }, {"time.dt must be > 0", "got 0", "test scene"});
  UserWorld user;
  expect_scene_error([&] { CoupledWorld(user.world, *user.cloth, scene); }, {"time.dt"});
}

TEST(CoupledWorld, OwnedWorldNeedsTheScenesCloth) {
  expect_scene_error([&] { CoupledWorld{jet_scene()}; }, {"cloth: the scene has none", "test scene"});
  SceneConfig scene = jet_scene();
  scene.cloth = patch_settings(5, 5);
  scene.cloth->area_density = -1;
  expect_scene_error([&] { CoupledWorld{scene}; }, {"cloth.area_density must be > 0", "got -1 (test scene)"});
}

// A game sets drench's thread count through the world it uses: the count drench's loops use, refused
// outside [1, 1024] with the value named.
TEST(CoupledWorld, SetsDrenchsThreadCountAndRefusesBadCounts) {
  const int before = CoupledWorld::thread_count();
  CoupledWorld::set_thread_count(1);
  EXPECT_EQ(drench::thread_count(), 1);
  CoupledWorld::set_thread_count(2);
  EXPECT_EQ(CoupledWorld::thread_count(), 2);
  try {
    CoupledWorld::set_thread_count(0);
    ADD_FAILURE() << "set_thread_count(0) did not throw";
  } catch (const drench::Error& e) {
    EXPECT_STREQ(e.what(), "thread count must be in [1, 1024], got 0");
  }
  EXPECT_EQ(CoupledWorld::thread_count(), 2);
  CoupledWorld::set_thread_count(before);
}

}  // namespace
}  // namespace drench::bullet
