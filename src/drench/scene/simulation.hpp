#pragma once
/// A scene brought to life: fluid, boundaries, emitters and kill regions built from a SceneConfig, stepped at
/// the scene's dt.

#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <drench/coupling/carried_water.hpp>
#include <drench/coupling/cloth_engine.hpp>
#include <drench/coupling/cloth_obstacle.hpp>
#include <drench/coupling/coupler.hpp>
#include <drench/coupling/leak_audit.hpp>
#include <drench/coupling/rigid_boundary.hpp>
#include <drench/coupling/static_obstacles.hpp>
#include <drench/scene/effect_counters.hpp>
#include <drench/scene/effect_registry.hpp>
#include <drench/scene/scene_config.hpp>
#include <drench/sph/emitters.hpp>
#include <drench/sph/fluid_solver.hpp>
#include <drench/wetting/cloth_wetting.hpp>

namespace drench {

/// Builds and steps everything a SceneConfig names. Only effects listed in `effects` are constructed, each
/// by its entry in the effect registry (effect_registry.hpp).
class Simulation {
 public:
  /// @throws SceneError when the scene cannot be built: it has a cloth but no cloth_factory; it fails any
  ///         check its scene file would (check_scene_built_in_code: a scene built in code is refused as that
  ///         file, naming the JSON path and config.source); an obstacle is
  ///         not a valid mesh (an OBJ scaled to points); or a cloth node, obstacle node, particle or nozzle
  ///         lies beyond kMaxCoordinate, or with the "surface" effect beyond its grid's int32 cells
  ///         (kMaxSurfaceGridCells x surface cell size). Each message names the scene's source.
  ///         A scene whose emitters never create a particle is fine.
  /// @param cloth_factory  builds the scene's cloth (the Bullet adapter's cloth_engine_factory()); required
  ///        when the scene has a `cloth`, else SceneError
  explicit Simulation(const SceneConfig& config, const ClothEngineFactory& cloth_factory = {});

  /// With a cloth engine built by the caller (e.g. attached to a Bullet world the caller owns); config.cloth
  /// then builds nothing, but when present its max_speed and max_strain limit the cloth and its
  /// area_density weighs it for wetting (absent: the defaults' limits and the engine's dry_node_masses).
  /// `cloth` may be null for a simulation without cloth. `more_obstacles` are static
  /// meshes besides the scene's `obstacles` (e.g. a Bullet world's static triangle meshes), coupled the same
  /// way. `bodies` (borrowed, or null) are the moving rigid bodies of the world the cloth is in, read at
  /// every step (coupling/rigid_bodies.hpp); without a cloth, they step their world themselves.
  /// @throws SceneError as the other constructor
  Simulation(const SceneConfig& config, std::unique_ptr<ClothEngine> cloth,
             std::vector<TriangleMesh> more_obstacles = {}, RigidBodySource* bodies = nullptr);

  /// One step of the scene's dt, in the paper's pipeline order (sec. 5): the cloth records its start
  /// positions; nozzles emit; the fluid advances alone (sub-stepping as it must); the cloth advances alone
  /// (with "carried_water", carrying the water near it and handing its share back); the coupling corrects
  /// the particles and, per coupling.scheme, the cloth now or at its next step (repulsion, friction,
  /// continuous handling); the leak audit checks the final motion; the cloth takes its corrections; kill
  /// regions remove the particles that left. Stages of effects the scene does not list are never built.
  /// A cloth torn, cut or refined since the last step (more nodes, other faces: ClothEngine::pieces) is
  /// followed: what the run keeps per node and face moves with it (cloth_layout.hpp).
  /// @throws Error when the engine's cloth lost nodes, or has a new node without a positive dry mass for
  ///         the wetting; the nozzles of this step have emitted then (CoupledWorld refuses a cloth that
  ///         lost nodes before it steps)
  StepStatus step() { return step(next_dt()); }
  /// The same with a step other than the scene's (unit: s, > 0).
  StepStatus step(Scalar dt);

  /// True once the simulated time has reached the scene's duration (within a thousandth of a step).
  bool finished() const;
  /// The step step() takes next (unit: s): time.dt, or with time.adaptive the fluid's CFL step within
  /// [dt_min, dt], cut to land on the next frame's time and on the duration.
  Scalar next_dt() const;
  /// Steps the scene's duration takes, round(duration / dt); with time.adaptive, the most it can take
  /// (every step at dt_min, or cut short by a frame).
  std::int64_t total_steps() const { return m_total_steps; }
  /// Smallest, summed and largest step taken (unit: s); min is infinite before the first step.
  Scalar min_dt() const { return m_min_dt; }
  Scalar sum_dt() const { return m_sum_dt; }
  Scalar max_dt() const { return m_max_dt; }
  std::int64_t steps_done() const { return m_steps; }
  Scalar time() const { return m_time; }

  const SceneConfig& config() const { return m_config; }
  FluidSolver& fluid() { return *m_fluid; }
  const FluidSolver& fluid() const { return *m_fluid; }
  const ParticleSet& particles() const { return m_fluid->particles(); }
  /// Particles removed by kill regions so far.
  std::int64_t removed() const { return m_removed; }
  /// Particles ever created.
  std::int64_t created() const { return m_next_id; }
  /// The effects that were constructed (the scene's `effects`, in its order).
  const std::vector<std::string>& effects() const { return m_config.effects; }
  /// How often each optional effect was built and ran so far (the surface's stays zero: the run loop
  /// reconstructs it, run_scene counts it). An effect the scene does not list has every count 0.
  EffectCounters effect_counters() const;
  /// The speed of sound in use (unit: m/s): the scene's, or the automatic one.
  Scalar speed_of_sound() const { return m_speed_of_sound; }
  /// Wall time spent emitting and removing particles (unit: s).
  double emit_seconds() const { return m_emit_seconds; }

  /// The coupler, or nullptr when the scene does not list "coupling" (or has no cloth).
  Coupler* coupler() { return m_effects.coupler.get(); }
  /// The cloth, or nullptr for a scene without one.
  ClothEngine* cloth() { return m_cloth.get(); }
  const ClothEngine* cloth() const { return m_cloth.get(); }
  /// The cloth with the obstacles and rigid bodies as the coupling sees them; null without obstacles and
  /// bodies (the engine is the cloth itself then).
  const ClothWithObstacles* cloth_with_obstacles() const { return m_with_obstacles.get(); }
  /// The static obstacles (the scene's, then the constructor's `more_obstacles`); empty without.
  const std::vector<TriangleMesh>& obstacles() const;
  /// The cloth and the obstacles as the coupling and the leak audit see them: the cloth's nodes first, then
  /// the obstacles' of inverse mass 0; nullptr when the scene has neither.
  const ClothMesh* contact_mesh() const { return m_engine ? &m_engine->mesh() : nullptr; }
  /// Coupling figures summed over all steps (zero without the "coupling" effect).
  const CouplingStepStats& coupling_stats() const { return m_coupling_stats; }
  /// What holding the cloth off the obstacles did, summed over steps (zero without both a cloth and
  /// obstacles; ClothWithObstacles::cloth_contact_stats).
  CouplingStepStats cloth_obstacle_stats() const {
    return m_with_obstacles ? m_with_obstacles->cloth_contact_stats() : CouplingStepStats{};
  }
  /// Leak audit figures summed over all steps (zero without the "leak_audit" effect).
  const LeakAuditStats& leak_stats() const { return m_leak_stats; }
  /// Wall time of the cloth's own steps and of the whole coupling stage (unit: s), without the rigid
  /// bodies' own work (rigid_seconds).
  double cloth_seconds() const { return m_cloth_seconds; }
  double coupling_seconds() const { return m_coupling_seconds; }
  /// Wall time of the rigid bodies' own work (unit: s): reading them from their engine at the start and the
  /// end of each step, placing their boundary particles, handing them the water's impulses and pressure;
  /// 0 without bodies. The coupler sees the cloth's and the bodies' faces as one mesh, so its pass
  /// (repulsion, CCD, friction) and the leak audit stay in coupling_seconds for both; the boundary
  /// particles' share of the fluid's step stays in the fluid's time.
  double rigid_seconds() const;
  /// COUPLING_* flags raised so far.
  std::uint32_t coupling_status() const { return m_coupling_status; }
  /// COUPLING_* flags of the last step.
  std::uint32_t last_coupling_status() const { return m_last_coupling_status; }
  /// The coupler ran in the last step: the scene lists "coupling", and the fluid and the cloth were finite
  /// and ok when it would (a check after it, as the end-of-step speed limit, does not undo it).
  bool last_step_coupled() const { return m_last_coupled; }
  /// Index of the first cloth node that was not finite after the cloth's own last step, or -1; the coupling
  /// was then skipped and the step reports NON_FINITE_STATE.
  std::int64_t non_finite_cloth_node() const { return m_non_finite_node; }
  /// Impulses the last step owes the cloth, given at the start of its next step (unit: N s), M entries
  /// (CouplingScheme::CARRIED_WATER; zero otherwise). Part of the total momentum between steps.
  const Vec3Array& pending_cloth_impulses() const { return m_pending_cloth_impulses; }

  /// The water in the cloth, or nullptr when the scene does not list "wetting".
  const ClothWetting* wetting() const { return m_effects.wetting.get(); }
  /// Wetting figures summed over all steps (zero without the "wetting" effect).
  const WettingStepStats& wetting_stats() const { return m_wetting_stats; }
  /// Mass that entered the scene so far: the initial particles and every nozzle's (unit: kg).
  double emitted_mass() const { return m_emitted_mass; }
  /// Mass that kill regions removed so far (unit: kg).
  double killed_mass() const { return m_killed_mass; }

  /// The fastest particle and cloth node at the end of any step so far (unit: m/s), 0 before the first
  /// step: a run that stays finite but flings particles or nodes away is unstable all the same.
  Scalar max_particle_speed() const { return m_max_particle_speed; }
  Scalar max_node_speed() const { return m_max_node_speed; }
  /// The largest strain of a cloth edge at the end of any step so far, (length - rest length) / rest length
  /// with the rest length its length when the simulation was built (dimensionless); 0 before the first step
  /// or without a cloth.
  Scalar max_cloth_strain() const { return m_max_strain; }
  /// The fluid's mechanical energy now (unit: J): kinetic plus potential in gravity, the potential measured
  /// from the lowest particle at construction, so that a still column has energy > 0.
  double fluid_energy() const;
  /// fluid_energy() at construction (unit: J).
  double initial_fluid_energy() const { return m_initial_energy; }
  /// True when no fluid enters or leaves the scene (no nozzle, kill region or wetting): only then is a
  /// change of fluid_energy() the solver's drift and dissipation rather than mass coming and going.
  bool closed() const;

 private:
  /// The cloth's side of a step, after the fluid's: impulses, the engine's step, the coupling (sec. 3,
  /// 5), the leak audit, the corrections back into the engine.
  /// ClothWithObstacles::body_seconds, 0 without obstacles.
  double body_seconds() const;
  /// The dynamic bodies' boundary particles where the bodies start the step (RigidBoundary).
  void place_rigid_boundary();
  /// Gives the dynamic bodies what the fluid's pressure gave their boundary particles in its step.
  void push_rigid_bodies();
  /// Tells the rigid bodies where the particles and the cloth's nodes are and how far they may move in a
  /// step of dt (RigidBodySource::expect_points).
  void tell_bodies_the_points(Scalar dt);
  void step_cloth_and_couple(Scalar dt, StepStatus& status);
  /// The leak audit of the faces' move from where the last audited step ended them to where the engine
  /// starts them now (audit_face_jumps), after the engine's begin_step; sets LEAKED in `status` naming the
  /// particle and face when a face crossed one.
  /// (key, instance) of each rigid surface of the step, in order: which bodies the mesh's faces belong to.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> rigid_body_instances() const;
  void audit_face_jumps_since_last_step(StepStatus& status);
  /// After the engine's begin_step: when a cloth was torn, cut or refined since the last step (more nodes,
  /// other faces), moves what the run keeps per node and face to the new layout (cloth_layout.hpp): the
  /// impulses owed to the cloth and the particles that gave them, the strain limit's edges, the jump
  /// audit's end positions, the adhesion's works and the wetting's water.
  /// @throws Error naming the cloth when one has fewer nodes than before
  void follow_cloth_layout();
  void remove_killed();
  /// The cloth's blow-up checks after a step: the fastest node against cloth.max_speed (RUNAWAY_NODE), the
  /// most stretched edge against cloth.max_strain (CLOTH_OVERSTRETCHED); also keeps the run's largest.
  void check_cloth(StepStatus& status);
  /// The cloth takes water from the particles touching it, spreads it and drips it (Fig. 9), then weighs
  /// its nodes with it for the next step.
  void wet_cloth(Scalar dt);

  SceneConfig m_config;
  Scalar m_speed_of_sound;
  std::unique_ptr<FluidSolver> m_fluid;
  std::vector<NozzleEmitter> m_nozzles;
  std::uint32_t m_next_id = 0;
  std::int64_t m_steps = 0;
  std::int64_t m_total_steps = 0;
  Scalar m_min_dt = std::numeric_limits<Scalar>::infinity(), m_sum_dt = 0.0, m_max_dt = 0.0;
  std::int64_t m_removed = 0;
  double m_emit_seconds = 0;
  std::unique_ptr<ClothEngine> m_cloth;
  std::unique_ptr<ClothWithObstacles> m_with_obstacles;  // only with obstacles or rigid bodies
  RigidBodySource* m_bodies = nullptr;                   // the world's rigid bodies, or none
  std::vector<std::uint8_t> m_displaced;                 // per particle, what a body that appeared displaced
  std::unique_ptr<RigidBoundary> m_rigid_boundary;       // only with rigid bodies and "coupling"
  ClothEngine* m_engine = nullptr;        // what the coupled step drives: m_with_obstacles, else m_cloth
  EffectParts m_effects;                  // what the scene's `effects` built (effect_registry.hpp)
  Vec3Array m_pending_cloth_impulses;     // M, owed to the cloth at its next step (unit: N s)
  std::size_t m_pending_cloth_nodes = 0;  // the cloth's node count when they were owed
  ImpulseLinks m_pending_links;           // the particles that gave them, carried in that step
  CouplingStepStats m_coupling_stats;
  LeakAuditStats m_leak_stats;
  LeakAudit m_leak_audit;                     // its grid of the mesh's faces kept from step to step
  Vec3Array m_audited_end;                    // the mesh's nodes where the last audited step ended them (m)
  std::vector<Triangle> m_audited_triangles;  // the mesh's triangles then
  std::vector<std::pair<std::uint64_t, std::uint64_t>> m_audited_bodies;  // (key, instance) of its bodies
  std::uint32_t m_coupling_status = 0;
  std::uint32_t m_last_coupling_status = 0;
  bool m_last_coupled = false;
  std::int64_t m_non_finite_node = -1;
  Scalar m_time = 0;
  double m_cloth_seconds = 0;
  double m_coupling_seconds = 0;
  double m_rigid_seconds =
      0;  // boundary particles placed and their pressure spread; the rest is the engine's
  WettingStepStats m_wetting_stats;
  double m_emitted_mass = 0;
  double m_killed_mass = 0;
  Scalar m_max_particle_speed = 0;
  Scalar m_max_node_speed = 0;
  Scalar m_last_node_speed = 0;      // the fastest cloth node at the end of the last step (unit: m/s)
  Scalar m_last_particle_speed = 0;  // the fastest particle then (unit: m/s)
  Scalar m_nozzle_speed = 0;         // the fastest nozzle's speed (unit: m/s)
  Scalar m_max_strain = 0;
  std::vector<ClothPiece> m_cloth_pieces;              // the cloth engine's pieces at the last step
  std::vector<std::pair<Index, Index>> m_cloth_edges;  // each edge of the cloth once, (lower, higher node)
  ScalarArray m_rest_lengths;  // their lengths at construction, or at the tear that made them (unit: m)
  double m_energy_floor = 0;   // -g.x of the lowest particle at construction, per kg (unit: J/kg)
  double m_initial_energy = 0;
};

/// The meshes of the scene's `obstacles`, in order: the built-in v_plane, or an OBJ file scaled and moved.
/// @throws SceneError naming `obstacles[i]` and the setting or file at fault (io/obj_reader.hpp)
std::vector<TriangleMesh> build_obstacles(const SceneConfig& config);

/// Speed of sound a scene gets when fluid.wcsph.speed_of_sound is unset: 10 (sqrt(2 |g| H) + v_emit) (unit:
/// m/s), H the scene's extent along gravity over its emitters, boundaries, patch cloth and v_plane obstacles
/// (not an OBJ cloth: its extent is unknown before the engine loads it), v_emit the fastest nozzle; at least
/// 1 m/s.
Scalar automatic_speed_of_sound(const SceneConfig& config);

}  // namespace drench
