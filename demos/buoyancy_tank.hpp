#pragma once
// Issue 40's buoyancy scene: a ball of 5 cm radius let down onto water 0.1 m deep in a tank 0.2 m square, and
// its settled draft against the water's surface. Shared by the test
// RigidBodies.ABallOfHalfTheWatersDensityFloatsHalfSubmergedAtTwoSpacings
// (tests/bullet_adapter/test_rigid_bodies.cpp) and bench/bench_buoyancy.cpp (run by bench/buoyancy.py), so
// that the benchmark measures the very scene the test asserts.
//
// Seen from the front (unit: m; +y up, the tank's floor at y = 0):
//
//     |                    |  walls 0.3 m high (the scene's boundary, open at the top)
//     |       .-"-.        |
//     |~~~~~~(  o  )~~~~~~~|  water 0.1 m deep; the ball starts 2 mm above it, at the tank's centre
//     |       `-.-'        |
//     |____________________|  floor: the scene's boundary, and a static box in Bullet (a sinking ball lands)
//     0                   0.2

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <drench/bullet/bullet_conversions.hpp>
#include <drench/bullet/coupled_world.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/sph/cubic_spline_kernel.hpp>

namespace buoyancy {

constexpr double kGravity = -9.81;   ///< along y (unit: m/s^2)
constexpr double kRadius = 0.05;     ///< the ball's (unit: m)
constexpr double kTank = 0.2;        ///< the tank's side, x and z (unit: m)
constexpr double kDepth = 0.1;       ///< the water's depth before the ball enters (unit: m)
constexpr double kWallHeight = 0.3;  ///< the tank's walls (unit: m)
constexpr double kDt = 1e-3;         ///< the step (unit: s)
constexpr int kSteps = 1200;         ///< 1.2 s: the ball has settled by 0.9 s at every spacing measured
constexpr int kFirstSample = 900;    ///< the draft is averaged over the steps after this one...
constexpr int kSampleEvery = 30;     ///< ... every this many steps (10 samples)
constexpr double kFacetEdge =
    0.01;  ///< the ball's facets (unit: m): its volume is within 0.3% of the sphere's
constexpr double kPi = 3.14159265358979323846;

/// Water `depth` deep (unit: m) in an open tank of side `tank` and walls `wall_height` high, its floor at
/// y = 0, at `spacing` (unit: m, > 0); steps of kDt with the coupling and the leak audit.
inline drench::SceneConfig tank_scene(double spacing, double tank = kTank, double depth = kDepth,
                                      double wall_height = kWallHeight) {
  drench::SceneConfig scene;
  scene.source = "buoyancy tank";
  scene.gravity = drench::Vec3(0, kGravity, 0);
  scene.fluid.particle_spacing = spacing;
  scene.time.dt = kDt;
  scene.effects = {"coupling", "leak_audit"};
  drench::BoundarySettings walls;
  walls.min = drench::Vec3::Zero();
  walls.max = drench::Vec3(tank, wall_height, tank);
  walls.open_top = true;
  scene.boundaries.push_back(walls);
  drench::EmitterSettings water;
  water.kind = drench::EmitterSettings::Kind::BOX;
  water.box.min = drench::Vec3::Zero();
  water.box.max = drench::Vec3(tank, depth, tank);
  scene.emitters.push_back(water);
  return scene;
}

/// The game's side of the tank: a Bullet world with the tank's floor as a static box under y = 0, a ball,
/// and a small pinned cloth far above everything (CoupledWorld couples at least one cloth; this one never
/// meets the water).
class TankWorld {
 public:
  /// @param density  the ball's (unit: kg/m^3), > 0
  /// @param radius  the ball's (unit: m), > 0
  /// @param drop  the height of the ball's lowest point above the water at the start (unit: m)
  explicit TankWorld(double density, double radius = kRadius, double drop = 0.002, double tank = kTank,
                     double depth = kDepth) {
    const btVector3 gravity(0, kGravity, 0);
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;  // soft bodies ignore setGravity
    cloth = btSoftBodyHelpers::CreatePatch(world.getWorldInfo(), btVector3(10, 10, 10),
                                           btVector3(10.1, 10, 10), btVector3(10, 10, 10.1),
                                           btVector3(10.1, 10, 10.1), 3, 3, 1 + 2 + 4 + 8, true);
    cloth->setTotalMass(0.01);
    world.addSoftBody(cloth);
    add(std::make_unique<btBoxShape>(btVector3(0.2, 0.05, 0.2)), 0.0,
        btVector3(0.5 * tank, -0.05, 0.5 * tank));
    const double mass = density * 4.0 / 3.0 * kPi * radius * radius * radius;
    ball = &add(std::make_unique<btSphereShape>(static_cast<btScalar>(radius)), mass,
                btVector3(0.5 * tank, depth + radius + drop, 0.5 * tank));
  }
  ~TankWorld() {
    for (const auto& body : m_bodies)
      world.removeRigidBody(body.get());
    world.removeSoftBody(cloth);
    delete cloth;
  }
  TankWorld(const TankWorld&) = delete;
  TankWorld& operator=(const TankWorld&) = delete;

 private:
  btRigidBody& add(std::unique_ptr<btCollisionShape> shape, double mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0.0) shape->calculateLocalInertia(static_cast<btScalar>(mass), inertia);
    m_motions.push_back(std::make_unique<btDefaultMotionState>(btTransform(btQuaternion::getIdentity(), at)));
    m_bodies.push_back(std::make_unique<btRigidBody>(static_cast<btScalar>(mass), m_motions.back().get(),
                                                     shape.get(), inertia));
    m_shapes.push_back(std::move(shape));
    world.addRigidBody(m_bodies.back().get());
    return *m_bodies.back();
  }

  btSoftBodyRigidBodyCollisionConfiguration m_configuration;
  btCollisionDispatcher m_dispatcher{&m_configuration};
  btDbvtBroadphase m_broadphase;
  btSequentialImpulseConstraintSolver m_solver;
  std::vector<std::unique_ptr<btCollisionShape>> m_shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> m_motions;
  std::vector<std::unique_ptr<btRigidBody>> m_bodies;  // removed from the world by ~TankWorld before they go

 public:
  btSoftRigidDynamicsWorld world{&m_dispatcher, &m_broadphase, &m_solver, &m_configuration};
  btSoftBody* cloth = nullptr;
  btRigidBody* ball = nullptr;
};

/// The height where the water's SPH density, sum_j m_j W(x - x_j), falls to half the rest density above
/// (x, z): its surface as drench's reconstruction draws it (unit: m), found by bisection in [0, 1] m.
inline double water_surface(const drench::bullet::CoupledWorld& coupled, double x, double z) {
  const drench::CubicSplineKernel kernel(coupled.scene().fluid.particle_spacing);
  const drench::ParticleSet& p = coupled.particles();
  const auto density = [&](double y) {
    double sum = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      sum += p.masses[i] * kernel.value((p.positions[i] - drench::Vec3(x, y, z)).norm());
    return sum;
  };
  const double half = 0.5 * coupled.scene().fluid.rest_density;
  double below = 0.0, above = 1.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (below + above);
    (density(mid) > half ? below : above) = mid;
  }
  return below;
}

/// A settled draft and how it was measured.
struct Draft {
  double mean = 0.0;            ///< draft / the ball's height, averaged over the samples (dimensionless)
  double min = 0.0, max = 0.0;  ///< the lowest and highest sample: the ball's bobbing in the window
  int samples = 0;
  std::size_t particles = 0;  ///< the water's particles
  double rest_density = 0.0;  ///< the water's (unit: kg/m^3)
  int failed_step = 0;        ///< the first step whose report failed (CoupledStepReport::failed), or 0
  std::string failure;        ///< its description, empty when every step was fine
};

/// The draft of a ball of kRadius and `density` (unit: kg/m^3) settled in the tank at `spacing` (unit: m):
/// the water's surface (water_surface, midway between the ball and each of the four walls, where it is flat)
/// less the ball's lowest point, clamped to [0, height] and over the ball's height, sampled every
/// kSampleEvery steps after kFirstSample of kSteps. Archimedes says 0.5 for half the water's density (by
/// symmetry) and 1 for a ball that sinks. A ball, not a cube: a floating cube of half the water's density
/// turns onto an edge, and rocks there for longer than this runs. Stops at the first failed step
/// (Draft::failure; the mean is then NaN).
/// @param solver  the water's pressure solver
/// @param dt  the step (unit: s), > 0, at most 0.03 s; the samples are taken at the same times for any step
inline Draft settled_draft(double spacing, double density,
                           drench::PressureSolverKind solver = drench::PressureSolverKind::PCISPH,
                           double dt = kDt) {
  TankWorld game(density);
  drench::SceneConfig scene = tank_scene(spacing);
  scene.fluid.pressure_solver = solver;
  scene.time.dt = dt;
  const int steps = static_cast<int>(std::lround(kSteps * kDt / dt));
  const int first_sample = static_cast<int>(std::lround(kFirstSample * kDt / dt));
  const int sample_every = std::max(1, static_cast<int>(std::lround(kSampleEvery * kDt / dt)));
  drench::bullet::RigidBodyOptions options;
  options.mesh.max_edge = kFacetEdge;
  drench::bullet::CoupledWorld coupled(game.world, *game.cloth, scene, options);
  Draft draft;
  draft.rest_density = scene.fluid.rest_density;
  draft.min = 1.0;
  double sum = 0.0;
  for (int n = 1; n <= steps; ++n) {
    const drench::bullet::CoupledStepReport report = coupled.step();
    if (report.failed()) {
      draft.failed_step = n;
      draft.failure = report.fluid.describe();
      break;
    }
    if (n > first_sample && n % sample_every == 0) {
      const double gap = 0.25 * (kTank - 2.0 * kRadius);
      const double surface =
          0.25 *
          (water_surface(coupled, gap, 0.5 * kTank) + water_surface(coupled, kTank - gap, 0.5 * kTank) +
           water_surface(coupled, 0.5 * kTank, gap) + water_surface(coupled, 0.5 * kTank, kTank - gap));
      const double lowest = game.ball->getCenterOfMassPosition().y() - kRadius;
      const double sample = std::clamp(surface - lowest, 0.0, 2.0 * kRadius) / (2.0 * kRadius);
      sum += sample;
      draft.min = std::min(draft.min, sample);
      draft.max = std::max(draft.max, sample);
      ++draft.samples;
    }
  }
  draft.particles = coupled.particles().size();
  draft.mean = draft.failure.empty() && draft.samples > 0 ? sum / draft.samples : std::nan("");
  return draft;
}

}  // namespace buoyancy
