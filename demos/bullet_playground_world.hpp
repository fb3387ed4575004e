#pragma once
// The world of demos/bullet_playground.cpp, built as a game builds its level: plain Bullet calls for a ground
// plane, a table, a hammock, a curtain, two balls and a crate, and the fluid part of a drench scene (two
// jets, wetting) in code. Shared with its test, tests/bullet_adapter/test_bullet_playground.cpp, so that the
// test checks the very scene the demo shows and measures.
//
// The layout (unit: m; +y up, the ground at y = 0), seen from the front (+z, where the camera is):
//
//        jet 1 (down)                     +--curtain--+   pinned along its top (y = 1.0), in the plane
//             |                           |     o <------ jet 2, from the front (z = 0.3) towards -z
//    ball  light ball                     |           |   z = -0.12, over the back of the table
//   ====hammock====   y = 0.6, pinned     +-----------+   bottom at y = 0.55
//   all round                                  [crate]
//                                  [=======table=======]   top at y = 0.4, x in [0.25, 0.85]
//   ---------------------------------------------------------- ground (btStaticPlaneShape)

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <vector>

#include <drench/scene/scene_config.hpp>

namespace playground {

constexpr double kDt = 1.0 / 60.0;  ///< the game's fixed step (unit: s)
constexpr double kGravity = -9.81;  ///< along y (unit: m/s^2)

// The hammock: a patch in the plane y = kHammockY, x in [kHammockX0, kHammockX1], |z| <= kHammockHalfZ,
// pinned all round, a sling in a frame. Pinned along its short edges only, its long edges sagged as far as
// its middle and Bullet's contact jitter walked the balls over them within 3-6 s. Pinned along its long edges
// only, a trough open at both ends, the ball rolled out of an end in 4 of 5 runs of the 4.5 s test that
// differed only in the last bits of a jet's position; pinned all round it stayed in 14 of 14, in both
// precisions.
constexpr double kHammockY = 0.6, kHammockX0 = -0.85, kHammockX1 = -0.15, kHammockHalfZ = 0.25;
constexpr int kHammockNodesX = 21, kHammockNodesZ = 15;  // 3.5 cm apart
// Heavy canvas, as heavy as the ball (unit: kg): Bullet's soft-rigid contact (SDF_RS) pushes the nodes out of
// a body and gives it only their momentum, so a cloth much lighter than a body lets it through whatever the
// iterations (a 3 kg ball fell through 0.12-2 kg of hammock at 10-300 iterations; 3 and 5 kg with 100
// held it for 4 s in both precisions).
constexpr double kHammockMass = 3.0;
constexpr int kHammockIterations = 100;

// The curtain: a patch in the plane z = kCurtainZ, x in [kCurtainX0, kCurtainX1], pinned along its top edge.
constexpr double kCurtainZ = -0.12, kCurtainX0 = 0.35, kCurtainX1 = 0.75, kCurtainTop = 1.0,
                 kCurtainBottom = 0.55;
constexpr int kCurtainNodesX = 17, kCurtainNodesY = 19;  // 2.5 cm apart
constexpr double kCurtainMass = 0.036;                   // 0.2 kg/m^2, a light curtain (unit: kg)
constexpr int kCurtainIterations = 40;                   // 10 let it stretch under its own weight at 1/60 s

// The table: a static box whose top is at y = kTableTop.
constexpr double kTableTop = 0.4;
const btVector3 kTableHalf(0.3, 0.2, 0.25);
const btVector3 kTableCentre(0.55, 0.2, 0.0);

// The bodies dropped or set in the scene (unit: m, kg).
constexpr double kBallRadius = 0.1, kBallMass = 3.0;  // into the hammock
const btVector3 kBallStart(-0.62, 0.75, 0.0);
constexpr double kLightBallRadius = 0.06, kLightBallMass = 0.4;  // into the hammock too
const btVector3 kLightBallStart(-0.44, 0.8, 0.0);
const btVector3 kCrateHalf(0.04, 0.04, 0.04);  // on the table, before the curtain, where its water falls
constexpr double kCrateMass = 0.2;
const btVector3 kCrateStart(0.55, kTableTop + 0.04, -0.16);

/// The game's world: Bullet's objects, owned here, and the two cloths in the world's soft body array
/// (hammock first). With `bodies` false the balls and the crate are left out (the ground and the table stay):
/// the same scene without dynamic rigid bodies, to compare their cost.
class World {
 public:
  explicit World(bool bodies = true) {
    const btVector3 gravity(0, kGravity, 0);
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;  // soft bodies ignore setGravity
    // Bullet finds a cloth's contacts with a rigid body in a sampled distance field of its shape, 0.25 m
    // cells by default: far too coarse for a 10 cm ball, which then sank into the hammock and fell through.
    world.getWorldInfo().m_sparsesdf.setDefaultVoxelsz(0.02);
    world.getWorldInfo().m_sparsesdf.Reset();

    add_rigid(std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), 0), 0.0, btVector3(0, 0, 0));
    add_rigid(std::make_unique<btBoxShape>(kTableHalf), 0.0, kTableCentre);
    ground = rigid[0].body.get();
    table = rigid[1].body.get();

    // The hammock hangs in a frame: every node of its four edges is pinned.
    hammock = btSoftBodyHelpers::CreatePatch(
        world.getWorldInfo(), btVector3(kHammockX0, kHammockY, -kHammockHalfZ),
        btVector3(kHammockX1, kHammockY, -kHammockHalfZ), btVector3(kHammockX0, kHammockY, kHammockHalfZ),
        btVector3(kHammockX1, kHammockY, kHammockHalfZ), kHammockNodesX, kHammockNodesZ, 0, true);
    hammock->setTotalMass(kHammockMass);
    for (int i = 0; i < kHammockNodesX; ++i) {
      hammock->setMass(i, 0);
      hammock->setMass((kHammockNodesZ - 1) * kHammockNodesX + i, 0);
    }
    for (int j = 0; j < kHammockNodesZ; ++j) {
      hammock->setMass(j * kHammockNodesX, 0);
      hammock->setMass(j * kHammockNodesX + kHammockNodesX - 1, 0);
    }
    set_up_cloth(*hammock, kHammockIterations);

    // The curtain hangs from a rail: its top row of nodes is pinned.
    curtain = btSoftBodyHelpers::CreatePatch(
        world.getWorldInfo(), btVector3(kCurtainX0, kCurtainTop, kCurtainZ),
        btVector3(kCurtainX1, kCurtainTop, kCurtainZ), btVector3(kCurtainX0, kCurtainBottom, kCurtainZ),
        btVector3(kCurtainX1, kCurtainBottom, kCurtainZ), kCurtainNodesX, kCurtainNodesY, 0, true);
    curtain->setTotalMass(kCurtainMass);
    for (int i = 0; i < kCurtainNodesX; ++i)
      curtain->setMass(i, 0);
    set_up_cloth(*curtain, kCurtainIterations);

    if (bodies) {
      ball = &add_rigid(std::make_unique<btSphereShape>(kBallRadius), kBallMass, kBallStart);
      light_ball =
          &add_rigid(std::make_unique<btSphereShape>(kLightBallRadius), kLightBallMass, kLightBallStart);
      crate = &add_rigid(std::make_unique<btBoxShape>(kCrateHalf), kCrateMass, kCrateStart);
    }
  }

  ~World() {
    for (const Rigid& r : rigid)
      world.removeRigidBody(r.body.get());
    for (btSoftBody* cloth : {hammock, curtain}) {
      world.removeSoftBody(cloth);
      delete cloth;
    }
  }
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  std::vector<btSoftBody*> cloths() const { return {hammock, curtain}; }

 private:
  struct Rigid {
    std::unique_ptr<btCollisionShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
  };

  btRigidBody& add_rigid(std::unique_ptr<btCollisionShape> shape, double mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(static_cast<btScalar>(mass), inertia);
    auto motion = std::make_unique<btDefaultMotionState>(btTransform(btQuaternion::getIdentity(), at));
    btRigidBody::btRigidBodyConstructionInfo info(static_cast<btScalar>(mass), motion.get(), shape.get(),
                                                  inertia);
    info.m_friction = 0.8;
    info.m_rollingFriction = 0.05;  // a ball on a slope rolls, but comes to rest on the flat
    info.m_angularDamping = 0.3;    // nor does it roll for ever on the cloth, which has no rolling friction
    auto body = std::make_unique<btRigidBody>(info);
    world.addRigidBody(body.get());
    rigid.push_back({std::move(shape), std::move(motion), std::move(body)});
    return *rigid.back().body;
  }

  void set_up_cloth(btSoftBody& cloth, int iterations) {
    cloth.getCollisionShape()->setMargin(0.02);  // the default is 0.25 m
    cloth.m_cfg.piterations = iterations;        // at 1/60 s, few let the cloth stretch far
    cloth.m_cfg.kDF = 1.0;                       // friction with the balls
    cloth.m_cfg.kDP = 0.2;                       // damping: the ball in the hammock settles
    world.addSoftBody(&cloth);
  }

  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  std::vector<Rigid> rigid;  // removed from the world by ~World before they go

 public:
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &configuration};
  btSoftBody* hammock = nullptr;
  btSoftBody* curtain = nullptr;
  btRigidBody* ground = nullptr;
  btRigidBody* table = nullptr;
  btRigidBody* ball = nullptr;        ///< null without bodies
  btRigidBody* light_ball = nullptr;  ///< null without bodies
  btRigidBody* crate = nullptr;       ///< null without bodies
};

/// The fluid part of the scene (docs/scenes.md, here in code): 1 cm particles, jet 1 straight down onto the
/// hammock beside the balls, jet 2 level at the curtain above the table; wetting, the coupling and the leak
/// audit on; the game's step. Water that runs off the stage (3.2 x 2.4 m about the table and the hammock) is
/// removed: it would spread over the ground's whole square and cost without being seen.
/// @param duration  simulated time (unit: s), > 0, e.g. for a frame count
/// @param solver  the fluid's pressure solver (`fluid.pressure_solver`), the scenes' default unless given:
///                bench/bench_game_frame.cpp times the same level with each
inline drench::SceneConfig scene(
    double duration, drench::PressureSolverKind solver = drench::FluidSettings{}.pressure_solver) {
  drench::SceneConfig s;
  s.source = "bullet_playground";
  s.gravity = drench::Vec3(0, kGravity, 0);  // must equal the world's (checked by CoupledWorld)
  s.fluid.particle_spacing = 0.01;
  s.fluid.pressure_solver = solver;
  s.time.dt = kDt;
  s.time.duration = duration;
  drench::EmitterSettings jet;
  jet.kind = drench::EmitterSettings::Kind::NOZZLE;
  jet.nozzle.center = drench::Vec3(-0.3, 0.95, 0.0);
  jet.nozzle.direction = drench::Vec3(0, -1, 0);
  jet.nozzle.radius = 0.015;
  jet.nozzle.speed = 1.5;
  jet.nozzle.max_particles = 4000;
  s.emitters.push_back(jet);
  jet.nozzle.center = drench::Vec3(0.55, 0.9, 0.3);
  jet.nozzle.direction = drench::Vec3(0, 0, -1);
  jet.nozzle.speed = 2.0;
  s.emitters.push_back(jet);
  drench::KillRegionSettings stage;
  stage.kind = drench::KillRegionSettings::Kind::BOX;
  stage.min = drench::Vec3(-1.6, -0.5, -1.2);
  stage.max = drench::Vec3(1.6, 2.0, 1.2);
  s.kill_regions.push_back(stage);
  s.coupling.cloth_thickness = 0.002;  // the paper's h (unit: m)
  // Each node holds water up to this share of its Bullet mass: a tenth for the heavy, proofed canvas (the
  // hammock then takes up to 0.3 kg), and the light curtain saturates and drips.
  s.wetting.max_saturation = 0.1;
  s.effects = {"viscosity", "coupling", "leak_audit", "wetting"};
  return s;
}

}  // namespace playground
