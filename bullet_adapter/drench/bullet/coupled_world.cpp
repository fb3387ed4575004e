#include <drench/bullet/coupled_world.hpp>

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>

#include <drench/bullet/shape_mesh.hpp>
#include <drench/common/error.hpp>
#include <drench/common/stopwatch.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/sph/boundary_sampling.hpp>

namespace drench::bullet {

namespace {

void check_scene(const SceneConfig& scene) {
  if (!(scene.time.dt > 0.0) || !std::isfinite(scene.time.dt)) {
    throw SceneError("time.dt must be > 0 and finite, got " + format_number(scene.time.dt) + " (" +
                     scene.source + ")");
  }
  if (!scene.gravity.allFinite()) {
    throw SceneError("gravity must be finite, got " + format_vec3(scene.gravity) + " (" + scene.source + ")");
  }
}

/// Rounding a gravity may carry after passing through btScalar: the double build compares to 1e-12, a
/// single-precision one to a few floats' units (relative to max(1, |g|)).
double gravity_tolerance(const Vec3& g) {
  return std::max(1e-12, 4.0 * std::numeric_limits<btScalar>::epsilon()) * std::max(1.0, g.norm());
}

/// Empty when the world's soft-body gravity is the scene's and its rigid-body gravity is its soft-body
/// gravity; else what differs, for a message.
std::string gravity_problem(const btSoftRigidDynamicsWorld& world, const SceneConfig& scene) {
  const Vec3 soft_gravity = to_vec3(world.getWorldInfo().m_gravity);
  const Vec3 rigid_gravity = to_vec3(world.getGravity());
  // Soft bodies fall with worldInfo.m_gravity, which world.setGravity does not touch (Bullet's default is
  // (0, -10, 0)); rigid bodies with getGravity(). A fluid, a cloth and a body under different gravity would
  // drift apart at rest. Compared as Bullet stores it: a single-precision world holds the scene's gravity
  // rounded to float.
  const Vec3 scene_gravity_in_bullet = to_vec3(to_bt(scene.gravity));
  // Written as "not within": a NaN gravity in the world passed a "differs by more than" test.
  if (!((soft_gravity - scene_gravity_in_bullet).norm() <= gravity_tolerance(scene.gravity))) {
    return "gravity " + format_vec3(scene.gravity) + " (" + scene.source +
           ") differs from the Bullet world's soft-body gravity getWorldInfo().m_gravity " +
           format_vec3(soft_gravity) + "; set world.getWorldInfo().m_gravity to the scene's gravity";
  }
  if (!((rigid_gravity - soft_gravity).norm() <= gravity_tolerance(soft_gravity))) {
    return "the Bullet world's rigid-body gravity world.getGravity() " + format_vec3(rigid_gravity) +
           " differs from its soft-body gravity getWorldInfo().m_gravity " + format_vec3(soft_gravity) +
           "; set world.setGravity to the scene's gravity " + format_vec3(scene.gravity) + " (" +
           scene.source + ")";
  }
  return {};
}

std::unique_ptr<BulletClothSet> attach(btSoftRigidDynamicsWorld& world,
                                       const std::vector<btSoftBody*>& cloths, const SceneConfig& scene) {
  check_scene(scene);
  const std::string problem = gravity_problem(world, scene);
  if (!problem.empty()) throw SceneError(problem);
  return std::make_unique<BulletClothSet>(world, cloths);
}

std::vector<btSoftBody*> every_soft_body(const btSoftRigidDynamicsWorld& world, const SceneConfig& scene) {
  const btSoftBodyArray& bodies = world.getSoftBodyArray();
  if (bodies.size() == 0)
    throw SceneError("the Bullet world has no soft body to couple with (" + scene.source + ")");
  std::vector<btSoftBody*> list;
  for (int i = 0; i < bodies.size(); ++i)
    list.push_back(bodies[i]);
  return list;
}

std::unique_ptr<BulletClothSet> own(const SceneConfig& scene) {
  check_scene(scene);
  if (!scene.cloth) {
    throw SceneError("cloth: the scene has none, and no Bullet cloth was given to couple with (" +
                     scene.source + ")");
  }
  try {
    return std::make_unique<BulletClothSet>(std::make_unique<BulletCloth>(*scene.cloth, scene.gravity));
  } catch (const SceneError& e) {
    throw SceneError(std::string(e.what()) + " (" + scene.source + ")");
  }
}

/// a - b for the per-step figures of a report, from the simulation's running sums.
CouplingStepStats difference(const CouplingStepStats& a, const CouplingStepStats& b) {
  CouplingStepStats d;
  d.contacts = a.contacts - b.contacts;
  d.ccd_impacts = a.ccd_impacts - b.ccd_impacts;
  d.ccd_iterations = a.ccd_iterations - b.ccd_iterations;
  d.failsafe_activations = a.failsafe_activations - b.failsafe_activations;
  d.obstacle_stops = a.obstacle_stops - b.obstacle_stops;
  d.stopped_particles = a.stopped_particles - b.stopped_particles;
  d.stopped_nodes = a.stopped_nodes - b.stopped_nodes;
  d.carried_by_zones = a.carried_by_zones - b.carried_by_zones;
  d.last_resort_impulse = a.last_resort_impulse - b.last_resort_impulse;
  d.zone_cloth_momentum = a.zone_cloth_momentum - b.zone_cloth_momentum;
  d.zone_ignored_shift = a.zone_ignored_shift - b.zone_ignored_shift;
  d.squeezed_out = a.squeezed_out - b.squeezed_out;
  d.squeezed_out_mass = a.squeezed_out_mass - b.squeezed_out_mass;
  d.squeezed_out_momentum = a.squeezed_out_momentum - b.squeezed_out_momentum;
  d.released_from_bodies = a.released_from_bodies - b.released_from_bodies;
  d.displaced_by_bodies = a.displaced_by_bodies - b.displaced_by_bodies;
  d.displaced_mass = a.displaced_mass - b.displaced_mass;
  d.displaced_momentum = a.displaced_momentum - b.displaced_momentum;
  d.slip_sum_mps = a.slip_sum_mps - b.slip_sum_mps;
  d.vertical_impulse_on_cloth = a.vertical_impulse_on_cloth - b.vertical_impulse_on_cloth;
  d.seconds_repulsion = a.seconds_repulsion - b.seconds_repulsion;
  d.seconds_ccd = a.seconds_ccd - b.seconds_ccd;
  return d;
}

LeakAuditStats difference(const LeakAuditStats& a, const LeakAuditStats& b) {
  LeakAuditStats d;
  d.leaks = a.leaks - b.leaks;
  d.jump_leaks = a.jump_leaks - b.jump_leaks;
  d.pairs = a.pairs - b.pairs;
  d.exact_checks = a.exact_checks - b.exact_checks;
  d.seconds = a.seconds - b.seconds;
  if (d.leaks > 0) {
    d.leak_particle = a.leak_particle;
    d.leak_triangle = a.leak_triangle;
  }
  return d;
}

/// Water put inside a solid body is trapped there, unseen and unreported: a nozzle whose centre is inside one
/// (a fountain inside its collision box), or a box of water overlapping a wall or a floor, particle by
/// particle (those within the emitter's box). Refused naming the emitter and the body.
void check_water_outside_solids(const SceneConfig& scene, const Vec3Array& particles,
                                const BulletRigidBodies& bodies) {
  const double depth = scene.fluid.particle_spacing;
  for (std::size_t i = 0; i < scene.emitters.size(); ++i) {
    const EmitterSettings& e = scene.emitters[i];
    std::string what;  // what of the emitter lies inside which body, or ""
    if (e.kind == EmitterSettings::Kind::NOZZLE) {
      const std::string holder = bodies.solid_holding(e.nozzle.center, depth);
      if (!holder.empty())
        what = "the nozzle's centre " + format_vec3(e.nozzle.center) + " lies inside " + holder;
    } else {
      std::size_t inside = 0;
      for (const Vec3& x : particles) {
        if ((x.array() < e.box.min.array()).any() || (x.array() > e.box.max.array()).any()) continue;
        const std::string holder = bodies.solid_holding(x, depth);
        if (holder.empty()) continue;
        if (inside++ == 0) what = "the first at " + format_vec3(x) + " inside " + holder;
      }
      if (inside > 0) what = std::to_string(inside) + " of its particles lie inside a solid body, " + what;
    }
    if (!what.empty()) {
      throw SceneError("emitters[" + std::to_string(i) + "]: " + what +
                       ", where its water would be trapped; move it out of the body, or let the water pass "
                       "the object (RigidBodyOptions::water_mask) (" +
                       scene.source + ")");
    }
  }
}

}  // namespace

/// Who stepped each game world: every CoupledWorld steps its world once a step, so when two couple one world
/// and both step, each one's cloth starts its next step where the other's step left it (reported only later,
/// as leaks). Several may exist (one built to replace another, one built to inspect); the one that steps
/// after another stepped the world since its own last step is refused (test
/// CoupledWorld.TwoCoupledWorldsSteppingOneBulletWorldInTurnAreRefused).
struct CoupledWorld::WorldSteps {
  explicit WorldSteps(const btSoftRigidDynamicsWorld& stepped) : world(&stepped) {
    const std::lock_guard<std::mutex> lock(mutex());
    Entry& entry = entries()[world];
    ++entry.users;
    seen = entry.steps;
  }
  ~WorldSteps() {
    const std::lock_guard<std::mutex> lock(mutex());
    const auto it = entries().find(world);
    if (--it->second.users == 0) entries().erase(it);
  }
  WorldSteps(const WorldSteps&) = delete;
  WorldSteps& operator=(const WorldSteps&) = delete;

  /// @throws drench::Error when another CoupledWorld stepped the world since this one's last step
  void check() const {
    const std::lock_guard<std::mutex> lock(mutex());
    if (entries().at(world).steps != seen) {
      throw Error(
          "another CoupledWorld stepped this Bullet world since this one's last step: each steps the world "
          "once a step, so this one's cloths are no longer where its step left them; couple every cloth "
          "through one CoupledWorld (CoupledWorld(world, {cloth_a, cloth_b}, scene)), and step only that");
    }
  }
  void stepped() {
    const std::lock_guard<std::mutex> lock(mutex());
    seen = ++entries().at(world).steps;
  }

  struct Entry {
    std::uint64_t steps = 0;  // CoupledWorld steps of the world
    int users = 0;            // CoupledWorlds of the world alive
  };
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::unordered_map<const void*, Entry>& entries() {
    static std::unordered_map<const void*, Entry> worlds;
    return worlds;
  }
  const void* world;
  std::uint64_t seen = 0;  // the world's step count after this one's last step (or at its construction)
};

std::vector<TriangleMesh> static_triangle_meshes(const btCollisionWorld& world) {
  std::vector<TriangleMesh> meshes;
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject& body = *objects[i];
    if (!body.isStaticObject() || body.isKinematicObject()) continue;
    const btCollisionShape* shape = body.getCollisionShape();
    if (!shape || shape->getShapeType() != TRIANGLE_MESH_SHAPE_PROXYTYPE) continue;
    TriangleMesh mesh = shape_mesh(*shape);
    for (Vec3& x : mesh.positions)
      x = to_vec3(body.getWorldTransform() * to_bt(x));
    if (!mesh.triangles.empty()) meshes.push_back(std::move(mesh));
  }
  return meshes;
}

CoupledWorld::CoupledWorld(btSoftRigidDynamicsWorld& world, const std::vector<btSoftBody*>& cloths,
                           const SceneConfig& scene, const RigidBodyOptions& bodies)
    : CoupledWorld(attach(world, cloths, scene), scene, &world, &bodies) {}

CoupledWorld::CoupledWorld(btSoftRigidDynamicsWorld& world, btSoftBody& cloth, const SceneConfig& scene,
                           const RigidBodyOptions& bodies)
    : CoupledWorld(world, std::vector<btSoftBody*>{&cloth}, scene, bodies) {}

CoupledWorld::CoupledWorld(btSoftRigidDynamicsWorld& world, const SceneConfig& scene,
                           const RigidBodyOptions& bodies)
    : CoupledWorld(world, every_soft_body(world, scene), scene, bodies) {
  m_every_soft_body = true;
}

CoupledWorld::CoupledWorld(const SceneConfig& scene) : CoupledWorld(own(scene), scene, nullptr, nullptr) {}

CoupledWorld::CoupledWorld(std::unique_ptr<BulletClothSet> cloths, const SceneConfig& scene,
                           btSoftRigidDynamicsWorld* world, const RigidBodyOptions* bodies)
    : m_world_steps(world ? std::make_unique<WorldSteps>(*world) : nullptr), m_cloths(cloths.get()) {
  for (std::size_t i = 0; i < m_cloths->cloth_count(); ++i)
    m_bodies.push_back({&m_cloths->cloth(i).body()});
  // After the cloths' checks, so that a wrong gravity or a missing cloth is named before any shape.
  if (world) m_rigid = std::make_unique<BulletRigidBodies>(*world, *bodies);
  m_simulation =
      std::make_unique<Simulation>(scene, std::move(cloths), std::vector<TriangleMesh>{}, m_rigid.get());
  // After the Simulation's checks of the scene (a NaN nozzle, a spacing of 0) and before the first step; the
  // broad phase's boxes first, for bodies the game placed after adding them (Bullet's own step does this).
  if (m_rigid) {
    world->updateAabbs();
    check_water_outside_solids(scene, m_simulation->particles().positions, *m_rigid);
  }
}

const std::vector<RigidSurface>& CoupledWorld::rigid_surfaces() const {
  static const std::vector<RigidSurface> none;
  const ClothWithObstacles* engine = m_simulation->cloth_with_obstacles();
  return engine ? engine->rigid_surfaces() : none;
}

CoupledWorld::~CoupledWorld() = default;

void CoupledWorld::check_world() const {
  const btSoftRigidDynamicsWorld& world = m_cloths->world();
  const btSoftBodyArray& in_world = world.getSoftBodyArray();
  for (std::size_t i = 0; i < m_bodies.size(); ++i) {
    // Found by its address before anything reads the body: a body the game removed (and maybe deleted) is
    // never dereferenced.
    const CoupledBody& coupled = m_bodies[i];
    if (in_world.findLinearSearch(const_cast<btSoftBody*>(coupled.body)) == in_world.size()) {
      throw Error("cloth " + std::to_string(i) +
                  " is no longer in the Bullet world (world.removeSoftBody): drench cannot step a cloth the "
                  "world does not; build a new CoupledWorld with the cloths that are left");
    }
    const btSoftBody& body = *coupled.body;
    // The set's count is the cloth's as of the last step's begin_step (or construction).
    if (static_cast<std::size_t>(body.m_nodes.size()) < m_cloths->node_count(i)) {
      throw Error("cloth " + std::to_string(i) + " has " + std::to_string(body.m_nodes.size()) +
                  " nodes, but had " + std::to_string(m_cloths->node_count(i)) +
                  " at the last step: drench follows nodes added to a cloth (torn, cut, refined), not "
                  "removed; build a new CoupledWorld");
    }
    if (body.m_faces.size() == 0) {
      throw Error("cloth " + std::to_string(i) +
                  " has no faces left: drench couples the water with faces (the water would pass through "
                  "it); build a new CoupledWorld without it");
    }
  }
  // Coupled as "every soft body of the world": one added since would let the water through it silently
  // (test CoupledCloths.ASoftBodyAddedAfterEveryOneWasCoupledIsRefused).
  if (m_every_soft_body && static_cast<std::size_t>(in_world.size()) != m_bodies.size()) {
    throw Error("the world has " + std::to_string(in_world.size()) + " soft bodies, " +
                std::to_string(m_bodies.size()) +
                " when this CoupledWorld coupled every one: drench does not couple a soft body added since "
                "(the water would pass through it); build a new CoupledWorld");
  }
  const std::string problem = gravity_problem(world, m_simulation->config());
  if (!problem.empty()) throw Error(problem + ", or build a new CoupledWorld for the new gravity");
  if (m_rigid) m_rigid->check_bodies();
}

double CoupledWorld::water_held(std::size_t i) const {
  const std::size_t first = m_cloths->first_node(i);
  const ClothWetting* wetting = m_simulation->wetting();
  if (!wetting) return 0.0;
  const ScalarArray& water = wetting->water();
  double held = 0.0;
  for (std::size_t k = first; k < first + m_cloths->node_count(i); ++k)
    held += water[k];
  return held;
}

CoupledStepReport CoupledWorld::step(double dt) {
  check_time_step("CoupledWorld::step", dt);
  // The coupling's corrections of the cloth's positions are what the water needs, whatever the step, and
  // Bullet turns a position change into a velocity over the step, so a far shorter step flings the cloth
  // (test CoupledWorldChecks.ABadTimeStepIsRefusedAndChangesNothing).
  const double least = m_simulation->config().time.dt / kMinStepDivisor;
  if (dt < least) {
    throw std::invalid_argument(
        "CoupledWorld::step: dt " + format_number(dt) + " s is less than the scene's time.dt / " +
        format_number(kMinStepDivisor) + " = " + format_number(least) +
        " s: a step this short moves the cloth by the water's corrections in a sliver of the time; carry a "
        "frame's remainder over to the next frame (as btDiscreteDynamicsWorld::stepSimulation does)");
  }
  check_world();
  if (m_world_steps) m_world_steps->check();
  CoupledStepReport report;
  Simulation& sim = *m_simulation;
  const CouplingStepStats coupling_before = sim.coupling_stats();
  const LeakAuditStats leaks_before = sim.leak_stats();
  const std::int64_t created_before = sim.created();
  const std::int64_t removed_before = sim.removed();
  const double emit_before = sim.emit_seconds();
  const double fluid_before = sim.fluid().statistics().timings_s.total;
  const double cloth_before = sim.cloth_seconds();
  const double rigid_before = sim.rigid_seconds();
  const double coupling_before_s = sim.coupling_seconds() + leaks_before.seconds;
  // The water's fastest particle and the bodies' speeds before the step: what the water can throw a body to.
  double water_speed = 0.0;
  if (m_rigid) {
    m_rigid->note_speeds();
    water_speed = sim.fluid().max_speed();
  }
  {
    ScopedTimer total(report.seconds.total);
    report.fluid = sim.step(dt);
  }
  if (m_rigid) {
    water_speed = std::max(water_speed, static_cast<double>(sim.fluid().max_speed()));
    report.thrown_body =
        m_rigid->thrown_body(water_speed, sim.config().fluid.rest_density, sim.config().gravity, dt);
  }
  if (m_world_steps) m_world_steps->stepped();
  report.non_finite_node = sim.non_finite_cloth_node();
  report.non_finite_cloth_node = m_cloths->locate_node(report.non_finite_node);
  if (report.fluid.flags & StepStatus::LEAKED)
    report.leaked_cloth_face = m_cloths->locate_triangle(report.fluid.leaked_triangle);
  report.coupling = sim.last_coupling_status();
  report.coupling_stats = difference(sim.coupling_stats(), coupling_before);
  report.leak_stats = difference(sim.leak_stats(), leaks_before);
  report.coupled = sim.last_step_coupled();
  report.emitted = static_cast<std::size_t>(sim.created() - created_before);
  report.removed = static_cast<std::size_t>(sim.removed() - removed_before);
  report.seconds.emit = sim.emit_seconds() - emit_before;
  report.seconds.fluid = sim.fluid().statistics().timings_s.total - fluid_before;
  report.seconds.cloth = sim.cloth_seconds() - cloth_before;
  report.seconds.rigid = sim.rigid_seconds() - rigid_before;
  report.seconds.coupling = sim.coupling_seconds() + sim.leak_stats().seconds - coupling_before_s;
  return report;
}

CoupledFrameReport CoupledWorld::step_frame(double frame_seconds, int max_steps) {
  if (!(frame_seconds >= 0.0) || !std::isfinite(frame_seconds)) {
    throw std::invalid_argument("CoupledWorld::step_frame: frame_seconds must be >= 0 and finite, got " +
                                format_number(frame_seconds) + " s");
  }
  if (max_steps < 1) {
    throw std::invalid_argument("CoupledWorld::step_frame: max_steps must be >= 1, got " +
                                std::to_string(max_steps));
  }
  const double dt = m_simulation->config().time.dt;
  const double owed = m_owed_seconds + frame_seconds;
  // A frame of exactly k steps (1/60 s at a step of 1/240 s) divides to k within rounding, either side of
  // it: the tolerance takes the k steps, where Bullet's float division takes k - 1 in some frames and k + 1
  // in the next.
  const double whole = std::floor(owed / dt + 1e-9);
  const double taken = std::min(whole, static_cast<double>(max_steps));
  CoupledFrameReport report;
  // In [0, dt) whatever the rounding of a huge frame's owed - whole * dt.
  double carried = std::max(0.0, owed - whole * dt);
  if (!(carried < dt)) carried = 0.0;
  // From the owed time rather than the whole steps, which overflow to infinity for a frame near DBL_MAX.
  report.dropped_seconds = std::max(0.0, owed - taken * dt - carried);
  for (int n = 0; n < static_cast<int>(taken); ++n) {
    try {
      report.steps.push_back(step(dt));
    } catch (...) {
      if (n > 0) m_owed_seconds = carried;  // the steps before it were taken
      throw;
    }
    if (!report.steps.back().ok()) {
      report.dropped_seconds += (taken - static_cast<double>(n + 1)) * dt;
      break;
    }
  }
  m_owed_seconds = carried;
  report.carried_seconds = carried;
  return report;
}

}  // namespace drench::bullet
