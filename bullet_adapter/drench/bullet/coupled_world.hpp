#pragma once
/// A Bullet world, a drench fluid and the cloth-fluid coupling, stepped together (Huber et al. 2013 sec. 5:
/// each engine advances alone, then the coupler corrects both from their start and end positions).
///
/// One coupled step of dt is one Simulation::step (scene/simulation.hpp, the same stages `drench run` steps):
///   1. nozzles emit          layers due in (t, t + dt], placed for the start of the step
///   2. cloth.begin_step()    node positions at the start of the step (positions_t0)
///   3. fluid.step(dt)        SPH alone; records positions_t0; with "coupling" the start-of-step cloth stops
///                            particles inside its sub-steps (coupling/cloth_obstacle.hpp)
///   4. carried water         coupling.scheme "carried_water" (the default): the water in contact becomes
///                            node mass for Bullet's step (BulletCloth::set_carried_masses)
///   5. cloth.apply_impulses  into m_v before Bullet's step, so that Bullet's links carry the load within the
///                            step: what the last step's coupling owes the cloth, and the obstacle's impulses
///   6. world stepSimulation  dt / substeps, substeps times (ClothSettings::substeps, default 1): the cloth
///                            (and the user's rigid bodies) alone; then the node end positions, the masses
///                            restored, and the carried water's share of the velocity change handed back
///   7. coupler.step(...)     effect "coupling": repulsion (eq. 1-4), friction (eq. 7-8), continuous handling
///                            (eq. 5-6) correct the particles; the cloth's share is kept for step 5 of the
///                            next step ("carried_water") or moves the node end positions ("impulses")
///   8. audit_leaks(...)      effect "leak_audit": particles that crossed the cloth in the final motion
///   9. cloth.end_step(dt)    corrected node positions into m_x, velocity changes into m_v
///  10. kill regions          particles that left the region of interest are removed
///
/// Call CoupledWorld::step instead of world->stepSimulation. The coupling needs the cloth's start and end of
/// exactly the step the fluid took: stepSimulation(dt) with its default fixed sub-step of 1/60 s would take
/// zero, one or several Bullet steps per call, and a step taken outside this class has no fluid step beside
/// it. Bullet's rigid bodies in the same world are stepped by stage 5 as usual.

#include <cstdint>
#include <memory>
#include <vector>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/bullet/bullet_rigid_bodies.hpp>
#include <drench/common/parallel.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/leak_audit.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/scene/simulation.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>

class btCollisionWorld;
class btSoftBody;
class btSoftRigidDynamicsWorld;

namespace drench::bullet {

/// The triangle meshes of the world's static rigid bodies (a btBvhTriangleMeshShape on a body of mass 0, not
/// kinematic), in world coordinates with the shape's scaling, in the world's order; Huber et al. 2013 sec. 5
/// treats rigid objects as such meshes. Vertices keep the game's indexing (faces sharing an edge share its
/// nodes, so the coupling sees no crack); faces that repeat a vertex or have no area are dropped. Other
/// shapes (boxes, spheres, convex hulls) are not read: a scene's `boundaries` describe those for the fluid.
std::vector<TriangleMesh> static_triangle_meshes(const btCollisionWorld& world);

/// What one coupled step did.
struct CoupledStepReport {
  /// The step's flags: the fluid's (NON_FINITE_STATE names the particle), the cloth's blow-up checks
  /// (RUNAWAY_NODE, CLOTH_OVERSTRETCHED against the scene's cloth.max_speed and max_strain, defaults when
  /// the scene has no `cloth`) and LEAKED (a particle crossed a face)
  StepStatus fluid;
  std::uint32_t coupling = COUPLING_OK;  ///< COUPLING_* flags of coupler.step
  CouplingStepStats coupling_stats;      ///< contacts, impacts, impulses of this step
  LeakAuditStats leak_stats;             ///< crossings of the cloth in this step (effect "leak_audit")
  /// Index of the first cloth node with a non-finite position after Bullet's step, or -1. The coupling is
  /// then skipped (the state is no longer meaningful: lower dt, raise piterations, check stiffness and
  /// masses).
  std::int64_t non_finite_node = -1;
  /// The coupler ran: the scene lists "coupling" and neither the fluid nor the cloth went non-finite.
  bool coupled = false;
  std::size_t emitted = 0;  ///< particles the nozzles added
  std::size_t removed = 0;  ///< particles the kill regions removed
  struct Seconds {
    double emit = 0, fluid = 0, cloth = 0, coupling = 0, total = 0;
  } seconds;  ///< wall time per stage (unit: s); coupling includes the leak audit

  /// False when the fluid or the cloth became non-finite or blew up (a particle or node over its speed
  /// limit, an edge over its strain limit): the state is no longer worth stepping.
  bool ok() const { return fluid.ok() && non_finite_node < 0; }
  /// True when the step cannot be trusted: !ok(), or a particle LEAKED through the cloth.
  bool failed() const { return !ok() || fluid.failed(); }
};

class CoupledWorld {
 public:
  /// Couples a world and a cloth the caller owns (and keeps alive, and no longer steps itself). Every other
  /// collision object of the world holds the fluid too (BulletRigidBodies, read at every step: bodies added,
  /// removed or moved later are followed): static ones as the scene's `obstacles` are, kinematic ones moved
  /// by the game sweep it, dynamic ones are pushed and turned by it. A level is described once, in Bullet.
  /// @param world  the caller's world, holding `cloth`; its soft-body gravity (getWorldInfo().m_gravity)
  ///        must be the scene's gravity
  /// @param cloth  the caller's soft body; its settings (margin, piterations, masses, pins) are left alone
  /// @param bodies  which objects hold the water (Bullet's collision filter) and how finely shapes become
  ///        triangles
  /// @param scene  everything else, as a scene file gives it (docs/scenes.md) and Simulation reads it:
  ///        gravity, fluid, emitters (boxes are filled now, nozzles emit per step), static boundaries, kill
  ///        regions, time.dt (the dt of step()), coupling settings and effects ("viscosity", "coupling",
  ///        "friction", "leak_audit"; a stage the scene does not list is not built). The speed of sound is
  ///        the scene's or automatic_speed_of_sound(scene). Of scene.cloth only the blow-up limits
  ///        (max_speed, max_strain) are read: the cloth is the caller's.
  /// @throws drench::Error naming the object when an object the water sees has a shape drench cannot use
  ///         (BulletRigidBodies)
  /// @throws SceneError when the world's soft-body gravity differs from the scene's, the cloth is not in the
  ///         world, the scene's dt or gravity is not finite or dt <= 0, or the coupling settings are out of
  ///         range; drench::Error when the cloth's mesh is invalid (ClothMesh::validate) or a static mesh has
  ///         no face of non-zero area
  CoupledWorld(btSoftRigidDynamicsWorld& world, btSoftBody& cloth, const SceneConfig& scene,
               const RigidBodyOptions& bodies = {});

  /// Owns its Bullet world and the cloth of scene.cloth in it (BulletCloth(*scene.cloth, scene.gravity)).
  /// @throws SceneError as above, when the scene has no cloth, and as BulletCloth(settings, gravity)
  explicit CoupledWorld(const SceneConfig& scene);

  ~CoupledWorld();
  CoupledWorld(const CoupledWorld&) = delete;
  CoupledWorld& operator=(const CoupledWorld&) = delete;

  /// One coupled step of dt (unit: s, > 0), in the order of this file's header. Never throws for numerical
  /// trouble: see the report.
  CoupledStepReport step(double dt);
  /// One coupled step of the scene's time.dt.
  CoupledStepReport step() { return step(m_simulation->config().time.dt); }

  const ParticleSet& particles() const { return m_simulation->particles(); }
  FluidSolver& fluid() { return m_simulation->fluid(); }
  BulletCloth& cloth() { return *m_cloth; }
  const BulletCloth& cloth() const { return *m_cloth; }
  /// The cloth as the coupling saw it in the last step (positions_t1 are the corrected end positions).
  const ClothMesh& cloth_mesh() const { return m_cloth->mesh(); }
  btSoftRigidDynamicsWorld& world() { return *m_cloth->world(); }
  /// The world's rigid bodies as the water sees them, or nullptr for the world this class owns.
  BulletRigidBodies* rigid_bodies() { return m_bodies.get(); }
  /// Every rigid body's surface in the last step (world coordinates), with its motion.
  const std::vector<RigidSurface>& rigid_surfaces() const;
  /// The coupler, or nullptr when the scene does not list "coupling".
  Coupler* coupler() { return m_simulation->coupler(); }
  /// The simulation behind this world: the same pipeline `drench run` steps (scene/simulation.hpp).
  Simulation& simulation() { return *m_simulation; }
  const SceneConfig& scene() const { return m_simulation->config(); }

  /// The speed of sound in use (unit: m/s): the scene's, or the automatic one.
  Scalar speed_of_sound() const { return m_simulation->speed_of_sound(); }
  /// Simulated time (unit: s): the sum of the dt of every step.
  double time() const { return m_simulation->time(); }
  std::int64_t steps() const { return m_simulation->steps_done(); }
  /// Particles ever created and ever removed.
  std::int64_t created() const { return m_simulation->created(); }
  std::int64_t removed() const { return m_simulation->removed(); }

  /// Sets the number of threads drench's fluid and coupling loops use, the calling thread included
  /// (drench::set_thread_count): for the whole process, every CoupledWorld and every drench loop, from the
  /// next loop on. A game that keeps cores for its own threads gives drench the rest; results are the same
  /// bits for any count. Bullet's own step is not affected.
  /// @param n  threads, in [1, kMaxThreadCount]
  /// @throws drench::Error naming n when it is outside that range
  static void set_thread_count(int n) { drench::set_thread_count(n); }
  /// The number of threads drench's loops use (drench::thread_count): by default the CPUs this process may
  /// run on, or OMP_NUM_THREADS.
  static int thread_count() { return drench::thread_count(); }

 private:
  CoupledWorld(std::unique_ptr<BulletCloth> cloth, const SceneConfig& scene, btSoftRigidDynamicsWorld* world,
               const RigidBodyOptions* bodies);

  BulletCloth* m_cloth;                         // owned by m_simulation
  std::unique_ptr<BulletRigidBodies> m_bodies;  // null for the owned world; outlives m_simulation
  std::unique_ptr<Simulation> m_simulation;
};

}  // namespace drench::bullet
