#pragma once
/// A Bullet world, a drench fluid and the cloth-fluid coupling, stepped together (Huber et al. 2013 sec. 5:
/// each engine advances alone, then the coupler corrects both from their start and end positions).
///
/// Every cloth of the coupling is one engine to the step (BulletClothSet: the cloths' nodes and faces in one
/// mesh), so the stages below run once per step whatever the number of cloths. One coupled step of dt is
/// the checks of CoupledWorld::step, then one Simulation::step (scene/simulation.hpp, the same stages
/// `drench run` steps):
///   1. nozzles emit          layers due in (t, t + dt], placed for the start of the step
///   2. cloth.begin_step()    node positions at the start of the step (positions_t0)
///   3. fluid.step(dt)        SPH alone; records positions_t0; with "coupling" the start-of-step cloth stops
///                            particles inside its sub-steps (coupling/cloth_obstacle.hpp)
///   4. carried water         coupling.scheme "carried_water" (the default): the water in contact becomes
///                            node mass for Bullet's step (BulletCloth::set_carried_masses)
///   5. cloth.apply_impulses  into m_v before Bullet's step, so that Bullet's links carry the load within the
///                            step: what the last step's coupling owes the cloth, and the obstacle's impulses
///   6. world stepSimulation  once, stepSimulation(dt, 0), for every cloth (an owned world: dt / substeps,
///                            ClothSettings::substeps times): the cloths (and the user's rigid bodies) alone;
///                            then the node end positions, the masses restored, and the carried water's share
///                            of the velocity change handed back
///   7. coupler.step(...)     effect "coupling": repulsion (eq. 1-4), friction (eq. 7-8), continuous handling
///                            (eq. 5-6) correct the particles; the cloth's share is kept for step 5 of the
///                            next step ("carried_water") or moves the node end positions ("impulses")
///   8. audit_leaks(...)      effect "leak_audit": particles that crossed a cloth in the final motion
///   9. cloth.end_step(dt)    corrected node positions into m_x, velocity changes into m_v
///  10. wetting               effect "wetting": each cloth absorbs, spreads and drips water, and Bullet
///  weighs
///                            each node with its water (BulletCloth::set_water_masses)
///  11. kill regions          particles that left the region of interest are removed
///
/// Call CoupledWorld::step instead of world->stepSimulation. The coupling needs the cloths' start and end of
/// exactly the step the fluid took: stepSimulation(dt) with its default fixed sub-step of 1/60 s would take
/// zero, one or several Bullet steps per call, and a step taken outside this class has no fluid step beside
/// it. Bullet's rigid bodies in the same world are stepped by stage 6 as usual.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <drench/bullet/bullet_cloth.hpp>
#include <drench/bullet/bullet_cloth_set.hpp>
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

/// CoupledWorld::step refuses a dt shorter than the scene's time.dt over this: the coupling's position
/// corrections of the cloth do not shrink with the step, and Bullet makes velocities of them over it.
inline constexpr double kMinStepDivisor = 16.0;

/// The triangle meshes of the world's static rigid bodies (a btBvhTriangleMeshShape on a body of mass 0, not
/// kinematic), in world coordinates with the shape's scaling, in the world's order; Huber et al. 2013 sec. 5
/// treats rigid objects as such meshes. Vertices keep the game's indexing (faces sharing an edge share its
/// nodes, so the coupling sees no crack); faces that repeat a vertex or have no area are dropped
/// (shape_mesh). A snapshot for a caller's own use: CoupledWorld reads every shape itself, at every step
/// (BulletRigidBodies).
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
  /// Index of the first cloth node with a non-finite position after Bullet's step, or -1, in cloth_mesh()
  /// (non_finite_cloth_node: which cloth's, and its index in its body). The coupling is then skipped (the
  /// state is no longer meaningful: lower dt, raise piterations, check stiffness and masses).
  std::int64_t non_finite_node = -1;
  ClothElement non_finite_cloth_node;
  /// With LEAKED: the cloth whose face the particle fluid.leaked_particle crossed and the face's index in
  /// its body's m_faces; cloth -1 when the face is a static mesh's (fluid.leaked_triangle, in the contact
  /// mesh, where the static meshes' faces follow the cloths').
  ClothElement leaked_cloth_face;
  /// The coupler ran: the scene lists "coupling" and neither the fluid nor the cloth had failed before it
  /// (Simulation::last_step_coupled).
  bool coupled = false;
  std::size_t emitted = 0;  ///< particles the nozzles added
  std::size_t removed = 0;  ///< particles the kill regions removed
  /// Wall time per stage (unit: s), no stage inside another; total is the whole Simulation::step, so total
  /// less the stages is what none names (the cloths' start positions, the carried water, wetting, the
  /// blow-up checks).
  /// - emit: nozzles and kill regions; fluid: the SPH step with its sub-steps;
  /// - cloth: Bullet's world step (the cloths, and Bullet's own rigid-body dynamics and contacts) and the
  ///   corrected node positions written back to the cloths;
  /// - rigid: the rigid bodies' own work: reading them from the world at the start and the end of the step,
  ///   placing their boundary particles, handing them the water's impulses and pressure
  ///   (Simulation::rigid_seconds). The coupler sees the cloths' and the bodies' faces as one mesh, so its
  ///   pass over the bodies is in coupling, and their boundary particles' share of SPH is in fluid;
  /// - coupling: the coupler (repulsion, friction, CCD, for cloths and bodies together) and the leak audit.
  struct Seconds {
    double emit = 0, fluid = 0, cloth = 0, rigid = 0, coupling = 0, total = 0;
  } seconds;

  /// A dynamic body the step threw faster than water can (BulletRigidBodies::thrown_body: named, with its
  /// speeds), or empty.
  std::string thrown_body;

  /// False when the fluid or the cloth became non-finite or blew up (a particle or node over its speed
  /// limit, an edge over its strain limit), or the water threw a body (thrown_body): the state is no longer
  /// worth stepping.
  bool ok() const { return fluid.ok() && non_finite_node < 0 && thrown_body.empty(); }
  /// True when the step cannot be trusted: !ok(), or a particle LEAKED through the cloth.
  bool failed() const { return !ok() || fluid.failed(); }
};

/// What one frame of a game did (CoupledWorld::step_frame).
struct CoupledFrameReport {
  /// The coupled steps the frame took, in order, each of the scene's time.dt; a step that is not ok() is the
  /// frame's last, so that the game sees it before more steps build on it (what to do then is the game's).
  std::vector<CoupledStepReport> steps;
  /// Time the frame owed beyond its max_steps steps, or after a step that was not ok, and did not simulate
  /// (unit: s): the world runs behind the game's clock by it, as Bullet's stepSimulation drops it.
  double dropped_seconds = 0;
  /// Time owed that is less than one step, carried to the next frame (unit: s, in [0, time.dt)); divided by
  /// time.dt, how far past the last step the game's clock is. Bullet interpolates its motion states by it;
  /// drench leaves the water and the cloths at the last step, for the game to interpolate what it draws.
  double carried_seconds = 0;
  /// Every step ok (true for a frame that took none).
  bool ok() const {
    return std::all_of(steps.begin(), steps.end(), [](const CoupledStepReport& r) { return r.ok(); });
  }
  /// Some step failed (CoupledStepReport::failed: not ok, or a particle leaked).
  bool failed() const {
    return std::any_of(steps.begin(), steps.end(), [](const CoupledStepReport& r) { return r.failed(); });
  }
};

class CoupledWorld {
 public:
  /// Couples a world and the cloths the caller owns (and keeps alive, and no longer steps itself): one
  /// fluid, every cloth in one mesh (BulletClothSet), one world step per step(). Every other collision
  /// object of the world holds the fluid too (BulletRigidBodies, read at every step: bodies added, removed
  /// or moved later are followed): static ones as the scene's `obstacles` are, kinematic ones moved by the
  /// game sweep it, dynamic ones are pushed, turned and floated by it. A level is described once, in
  /// Bullet.
  ///
  /// What is read of `scene` (docs/scenes.md; the rest is not read):
  /// - gravity: must be the world's soft-body gravity (getWorldInfo().m_gravity) and its rigid-body gravity
  ///   (getGravity()), here and at every step;
  /// - fluid, emitters (boxes are filled now, nozzles emit per step), boundaries, kill_regions, obstacles,
  ///   coupling, wetting, effects ("viscosity", "coupling", "friction", "leak_audit", "wetting"; a stage the
  ///   scene does not list is not built), time.dt (the dt of step()), source (in messages). The speed of
  ///   sound is fluid.wcsph's or automatic_speed_of_sound(scene). Not read: time's other fields (the caller
  ///   decides when to stop), surface, camera;
  /// - cloth: the cloths are the caller's, so its mesh, placement, pins, iterations, stiffnesses and
  ///   substeps are not read. Absent (the default): the blow-up limits are ClothSettings' defaults and the
  ///   wetting weighs each node with its own Bullet mass (BulletCloth::dry_node_masses: 1 / m_im, a pinned
  ///   node from its faces' area at its cloth's mean area density). Present: its max_speed and max_strain
  ///   are the limits, and its area_density weighs every cloth's nodes for wetting instead (a third of each
  ///   face's area to each node), as for a scene's own cloth: giving `cloth` is how a scene sets the area
  ///   density explicitly. (A patch `cloth`'s extent also enters the automatic speed of sound.)
  /// @param world  the caller's world, holding every cloth
  /// @param cloths  soft bodies with faces, each once; their settings (margin, piterations, masses, pins)
  ///        are left alone, and wetting changes their node masses (BulletCloth::set_water_masses)
  /// @param bodies  which rigid objects hold the water (Bullet's collision filter) and how finely their
  ///        shapes become triangles
  /// @throws SceneError when the scene's dt or gravity is not finite or dt <= 0, the world's soft-body
  ///         gravity differs from the scene's or its rigid-body gravity from its soft-body gravity, a cloth
  ///         is null, repeated, not in the world or has no faces (a rope; the message names its index in
  ///         `cloths`), the list is empty, or the fluid or coupling settings are out of range; drench::Error
  ///         when a cloth's mesh is invalid (ClothMesh::validate), or naming the object when an object the
  ///         water sees has a shape drench cannot use (BulletRigidBodies)
  CoupledWorld(btSoftRigidDynamicsWorld& world, const std::vector<btSoftBody*>& cloths,
               const SceneConfig& scene, const RigidBodyOptions& bodies = {});

  /// One cloth: CoupledWorld(world, {&cloth}, scene, bodies).
  CoupledWorld(btSoftRigidDynamicsWorld& world, btSoftBody& cloth, const SceneConfig& scene,
               const RigidBodyOptions& bodies = {});

  /// Every soft body of the world, in the order of world.getSoftBodyArray() (cloth i is its element i): the
  /// list constructor with that list. A soft body without faces (a rope) is refused, naming its index in
  /// that array: pass the list of cloths to leave it out (the water then passes through it).
  /// @throws SceneError as the list constructor, and when the world has no soft body
  CoupledWorld(btSoftRigidDynamicsWorld& world, const SceneConfig& scene,
               const RigidBodyOptions& bodies = {});

  /// Owns its Bullet world and the cloth of scene.cloth in it (BulletCloth(*scene.cloth, scene.gravity)),
  /// stepped in cloth.substeps.
  /// @throws SceneError as above, when the scene has no cloth, and as BulletCloth(settings, gravity)
  explicit CoupledWorld(const SceneConfig& scene);

  ~CoupledWorld();
  CoupledWorld(const CoupledWorld&) = delete;
  CoupledWorld& operator=(const CoupledWorld&) = delete;

  /// One coupled step of dt (unit: s), in the order of this file's header. First checks the call and the
  /// world, and throws before anything changes (time, steps, particles, nodes, masses) when:
  /// - dt is not > 0 and finite: std::invalid_argument "CoupledWorld::step: dt must be > 0 and finite, got
  ///   <dt> s"; or dt is less than the scene's time.dt / kMinStepDivisor (std::invalid_argument naming both);
  /// - a cloth is no longer in the world's soft body array (the game called world.removeSoftBody, perhaps
  ///   to delete it) or has fewer nodes than at the last step (Bullet's own tearing, cutLink and refine,
  ///   only adds nodes: what drench keeps per node would no longer match): drench::Error naming the cloth's
  ///   index. A removed cloth is never dereferenced, so deleting it after removeSoftBody is safe; deleting
  ///   a body still in the world breaks Bullet's own next step, which no check here can see. A cloth with
  ///   more nodes or other faces (torn, cut, refined since the last step) is followed: the water it holds,
  ///   what it is owed and its strain limit's rest lengths stay with its nodes, a new node or edge starting
  ///   dry at its length now (cloth_layout.hpp);
  /// - built to couple every soft body of the world, the world now has another count of them (one added
  ///   since would not be coupled): drench::Error naming both counts;
  /// - the world's rigid-body or soft-body gravity is no longer the scene's (world.setGravity or
  ///   getWorldInfo().m_gravity changed since): drench::Error naming both values.
  /// Then never throws for numerical trouble: see the report.
  CoupledStepReport step(double dt);
  /// One coupled step of the scene's time.dt.
  CoupledStepReport step() { return step(m_simulation->config().time.dt); }
  /// A game's frame of `frame_seconds` at the scene's fixed time.dt, as
  /// btDiscreteDynamicsWorld::stepSimulation(frame_seconds, max_steps, time.dt) steps a world: the time owed
  /// (this frame's and what earlier frames carried) is taken in whole steps, at most max_steps of them (the
  /// rest dropped), and less than a step is carried to the next frame. A game that passes its measured frame
  /// time to step(dt) instead gets a step as long as its slowest frame: after a hitch, one step of a tenth of
  /// a second, longer than the cloth's and the fluid's stable steps (the test
  /// CoupledWorldFrames.AHitchIsTakenInFixedStepsAndTheRestDropped). The world's time (time()) advances by
  /// whole steps only.
  /// @param frame_seconds  the game's frame time (unit: s), >= 0 and finite
  /// @param max_steps  the most steps one frame takes, >= 1 (Bullet's maxSubSteps). No default: Bullet's 1
  ///        suits its fixed step of 1/60 s, but with a scene's time.dt of a millisecond it would take one
  ///        step of the 17 a 1/60 s frame owes, and the world would run 17 times slower than the game.
  ///        Frame time over max_steps * time.dt is dropped.
  /// @throws std::invalid_argument naming the value when frame_seconds or max_steps is out of range, before
  ///         anything changes; what step() throws: from the frame's first step before anything changes,
  ///         from a later one (a body the step before left at NaN) with the steps before it taken and the
  ///         frame's time counted as stepped
  CoupledFrameReport step_frame(double frame_seconds, int max_steps);

  const ParticleSet& particles() const { return m_simulation->particles(); }
  FluidSolver& fluid() { return m_simulation->fluid(); }
  /// The cloths, in the order given (or of the world's soft body array).
  std::size_t cloth_count() const { return m_cloths->cloth_count(); }
  /// Cloth i. @throws std::out_of_range naming i and the count
  BulletCloth& cloth(std::size_t i) { return m_cloths->cloth(i); }
  const BulletCloth& cloth(std::size_t i) const { return m_cloths->cloth(i); }
  /// Cloth 0 (the one cloth of the one-cloth constructors).
  BulletCloth& cloth() { return cloth(0); }
  const BulletCloth& cloth() const { return cloth(0); }
  /// All cloths as the one engine the coupling steps: which node or face of cloth_mesh() is whose
  /// (BulletClothSet::locate_node, locate_triangle, first_node).
  BulletClothSet& cloths() { return *m_cloths; }
  const BulletClothSet& cloths() const { return *m_cloths; }
  /// The cloths as the coupling saw them in the last step, cloth 0's nodes and faces first
  /// (positions_t1 are the corrected end positions); without the world's static meshes.
  const ClothMesh& cloth_mesh() const { return m_cloths->mesh(); }
  btSoftRigidDynamicsWorld& world() { return m_cloths->world(); }
  /// Water held by cloth i (unit: kg): the wetting's, summed over its nodes; 0 without "wetting".
  /// @throws std::out_of_range naming i and the count
  double water_held(std::size_t i) const;
  /// The world's rigid bodies as the water sees them, or nullptr for the world this class owns.
  BulletRigidBodies* rigid_bodies() { return m_rigid.get(); }
  /// Every rigid body's surface in the last step (world coordinates), with its motion.
  const std::vector<RigidSurface>& rigid_surfaces() const;
  /// The coupler, or nullptr when the scene does not list "coupling".
  Coupler* coupler() { return m_simulation->coupler(); }
  /// The simulation behind this world: the same pipeline `drench run` steps (scene/simulation.hpp).
  Simulation& simulation() { return *m_simulation; }
  const Simulation& simulation() const { return *m_simulation; }
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
  CoupledWorld(std::unique_ptr<BulletClothSet> cloths, const SceneConfig& scene,
               btSoftRigidDynamicsWorld* world, const RigidBodyOptions* bodies);
  /// Throws drench::Error when a cloth left the world or changed its counts, or a gravity changed.
  void check_world() const;

  /// Tells whether another CoupledWorld stepped the game's world since this one's last step
  /// (coupled_world.cpp).
  struct WorldSteps;
  std::unique_ptr<WorldSteps> m_world_steps;  // null for the world this class owns
  BulletClothSet* m_cloths;                   // owned by m_simulation
  struct CoupledBody {
    const btSoftBody* body;  // compared with the world's soft bodies before it is read
  };
  std::vector<CoupledBody> m_bodies;  // one per cloth
  bool m_every_soft_body = false;     // built by the constructor that couples every soft body of the world
  double m_owed_seconds = 0;          // frame time not yet stepped, < time.dt (step_frame)
  std::unique_ptr<BulletRigidBodies> m_rigid;  // null for the owned world; outlives m_simulation
  std::unique_ptr<Simulation> m_simulation;
};

}  // namespace drench::bullet
