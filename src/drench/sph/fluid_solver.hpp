#pragma once
/// The SPH fluid: neighbor search, density, non-pressure forces, pressure solve and symplectic Euler
/// integration, sub-stepped under a CFL limit inside the scene's step.

#include <cstdint>
#include <memory>
#include <string>

#include <drench/common/effect_counter.hpp>
#include <drench/sph/boundary_sampling.hpp>
#include <drench/sph/boundary_settings.hpp>
#include <drench/sph/cubic_spline_kernel.hpp>
#include <drench/sph/fluid_settings.hpp>
#include <drench/sph/forces/surface_tension.hpp>
#include <drench/sph/forces/viscosity.hpp>
#include <drench/sph/particle_set.hpp>
#include <drench/sph/pressure/pressure_pbf.hpp>
#include <drench/sph/pressure/pressure_solver.hpp>
#include <drench/sph/verlet_neighbor_lists.hpp>

namespace drench {

/// A particle denser than this many times the rest density is packed past anything water reaches; more than
/// half of the fluid so packed in a sub-step has collapsed (StepStatus::FLUID_COLLAPSED). The hydrostatic
/// tank at time.dt 0.2 s packs all of it (tests/hostile/test_hostile_physics.cpp); a particle caught in a
/// body's shell is packed alone (CaughtParticle), and the largest mean density error of any run in
/// bench/results is 0.54 (PBF's 59K dam break at 2 sub-steps of 1/60 s).
inline constexpr double kCollapsedDensity = 2.0;

/// Outcome of a step. Numerical trouble inside a step is reported here, never thrown.
struct StepStatus {
  enum Flag : std::uint32_t {
    /// A particle's position or velocity became NaN or infinite; `non_finite_particle` names its id. The
    /// state is no longer meaningful: lower dt or the CFL factor, or check the scene's stiffness.
    NON_FINITE_STATE = 1u << 0,
    /// PCISPH or DFSPH stopped at max_iterations with the density error above eta (or DFSPH's divergence
    /// solve at max_divergence_iterations above eta_divergence) in some sub-step. The step is still usable;
    /// raise the iteration limit or lower dt if it persists.
    PRESSURE_NOT_CONVERGED = 1u << 1,
    /// A cloth node's position became NaN or infinite after the cloth's own step; `non_finite_node` names it
    /// and the coupling was skipped. Lower dt, raise the cloth's position iterations, check its masses.
    NON_FINITE_CLOTH = 1u << 2,
    /// A particle moved faster than fluid.max_speed at the start of a sub-step or, in a Simulation, at the
    /// end of a step (speed_check); `runaway_particle` names its id and `runaway_speed` its speed. The run
    /// has blown up: lower dt or the CFL factor.
    RUNAWAY_PARTICLE = 1u << 3,
    /// A particle ended the step on the other side of a cloth or obstacle face than it started (the leak
    /// audit's transversal crossing), or the continuous handling could not rule one out; `leaked_particle`
    /// and `leaked_triangle` name the first. The run goes on (the crossing is counted in `leaks`), but its
    /// result breaks the paper's promise: turn `coupling.continuous` on, lower time.dt.
    LEAKED = 1u << 4,
    /// A cloth node moved faster than cloth.max_speed at the end of a step; `runaway_node` names it and
    /// `runaway_node_speed` gives its speed. The cloth has blown up: lower time.dt, raise cloth.substeps.
    RUNAWAY_NODE = 1u << 5,
    /// A cloth edge was stretched beyond cloth.max_strain of its length when the simulation was built;
    /// `overstretched_edge` names its nodes and `edge_strain` its strain. The cloth has torn apart
    /// numerically: lower time.dt, raise cloth.substeps or cloth.position_iterations.
    CLOTH_OVERSTRETCHED = 1u << 6,
    /// After a sub-step's pressure solve more than half of the particles were denser than kCollapsedDensity
    /// times the rest density; `collapsed_particles` of `particle_count` were. No flow of water packs it so:
    /// the step is too large for the pressure solve and the fluid has collapsed. Lower time.dt or fluid.cfl
    /// (PBF: raise fluid.pbf.substeps).
    FLUID_COLLAPSED = 1u << 7,
  };
  std::uint32_t flags = 0;
  std::int64_t non_finite_particle = -1;  ///< id of the first non-finite particle, or -1
  std::int64_t non_finite_node = -1;      ///< index of the first non-finite cloth node, or -1
  std::int64_t runaway_particle = -1;     ///< id of the fastest particle over fluid.max_speed, or -1
  double runaway_speed = 0.0;             ///< its speed (unit: m/s)
  std::int64_t leaked_particle = -1;      ///< id of the first particle that crossed a face, or -1
  std::int64_t leaked_triangle = -1;      ///< the face it crossed (index in the contact mesh), or -1
  std::int64_t runaway_node = -1;         ///< index of the fastest cloth node over cloth.max_speed, or -1
  double runaway_node_speed = 0.0;        ///< its speed (unit: m/s)
  std::int64_t overstretched_edge[2] = {-1, -1};  ///< the nodes of the most stretched edge, or -1
  double edge_strain = 0.0;  ///< its strain, (length - rest length) / rest length (dimensionless)
  std::int64_t collapsed_particles = -1;  ///< the particles packed past kCollapsedDensity, or -1
  std::int64_t particle_count = 0;        ///< of how many

  /// False when the state is no longer worth stepping: non-finite, a particle over fluid.max_speed, a
  /// collapsed fluid, a node over cloth.max_speed or an edge beyond cloth.max_strain.
  bool ok() const {
    return (flags & (NON_FINITE_STATE | NON_FINITE_CLOTH | RUNAWAY_PARTICLE | FLUID_COLLAPSED | RUNAWAY_NODE |
                     CLOTH_OVERSTRETCHED)) == 0;
  }
  /// True when the result cannot be trusted: !ok(), or a particle LEAKED through the cloth. A run with such a
  /// status never ends as a success (`drench run` exits 2). PRESSURE_NOT_CONVERGED alone is a warning.
  bool failed() const { return !ok() || (flags & LEAKED) != 0; }
  StepStatus& operator|=(const StepStatus& other);
  /// One line naming each raised flag (and the particle id), empty when no flag is raised.
  std::string describe() const;
};

/// Counters and timers over the fluid's whole life, the source of the summary's fluid keys.
struct FluidStatistics {
  std::int64_t steps = 0;
  std::int64_t substeps = 0;
  int max_substeps_per_step = 0;
  /// Sub-steps redone at half their length after a pressure solve that diverged
  /// (FluidSettings::substep_halvings). Their pressure iterations count in pressure_iterations; they are not
  /// in `substeps` nor in the density errors.
  std::int64_t substeps_halved = 0;
  std::int64_t pressure_iterations = 0;    ///< summed over sub-steps
  int max_pressure_iterations = 0;         ///< in one sub-step
  std::int64_t divergence_iterations = 0;  ///< DFSPH's divergence-free iterations, summed over sub-steps
  int max_divergence_iterations = 0;       ///< in one sub-step
  Scalar density_error_sum = 0;            ///< sum over sub-steps of the average density error
  Scalar density_error_max = 0;            ///< largest average density error of a sub-step
  Scalar particle_density_error_max = 0;   ///< largest density error of any particle in any sub-step
  std::int64_t boundary_guards = 0;        ///< particles put back by enforce_boundary, over all sub-steps
  std::int64_t neighbor_searches = 0;      ///< sub-steps whose neighbor lists came from a grid search (the
                                           ///< others reused the last search's candidates)
  struct Timings {
    double total = 0, neighbors = 0, density = 0, forces = 0, pressure = 0, integrate = 0;
  } timings_s;  ///< wall time per stage (unit: s); pressure includes DFSPH's divergence-free solve
};

/// An SPH fluid with static boundary particles.
/// A constraint applied at the end of every fluid sub-step, after integration: the coupling uses it to let
/// the fluid see the cloth inside its sub-steps (coupling/cloth_obstacle.hpp). The fluid solver knows nothing
/// else about it.
class SubstepConstraint {
 public:
  virtual ~SubstepConstraint() = default;
  /// @param positions_before  N particle positions at the start of the sub-step (unit: m)
  /// @param particles  after integration; positions and velocities may be changed
  /// @param dt  the sub-step (unit: s)
  virtual void apply(const Vec3Array& positions_before, ParticleSet& particles, Scalar dt) = 0;
};

/// Throws SceneError naming the first field of `settings` outside its range, as "fluid.<field> must be
/// <range>, got <value>": the ranges docs/scenes.md gives and the scene loader holds a file to, for settings
/// built in code (a game's SceneConfig), which would otherwise divide by a zero spacing or loop without end.
void check_fluid_settings(const FluidSettings& settings);

class FluidSolver {
 public:
  /// @param gravity  (unit: m/s^2)
  /// @param boundary  boundary particles, e.g. from sample_box_container
  /// @param guards  the analytic boundaries behind those particles, enforced by enforce_boundary
  /// @param with_viscosity  builds the viscosity of settings.viscosity (the "viscosity" effect)
  /// @param speed_of_sound  WCSPH's c and the artificial viscosity's c (unit: m/s), > 0
  /// @param surface_tension  builds the surface tension force with these settings (the "surface_tension"
  ///        effect); nullptr: none, and no pass for it
  /// @throws SceneError when `settings` are out of range (check_fluid_settings), before anything is built;
  ///         std::invalid_argument when surface_tension->sigma is negative or not finite
  FluidSolver(const FluidSettings& settings, const Vec3& gravity, BoundaryParticles boundary,
              std::vector<BoundarySettings> guards, bool with_viscosity, Scalar speed_of_sound,
              const SurfaceTensionSettings* surface_tension = nullptr);

  ParticleSet& particles() { return m_particles; }
  const ParticleSet& particles() const { return m_particles; }
  const Vec3Array& boundary_positions() const { return m_neighbors.boundary_points(); }
  const FluidSettings& settings() const { return m_settings; }
  const CubicSplineKernel& kernel() const { return m_kernel; }
  const FluidStatistics& statistics() const { return m_stats; }
  /// The "viscosity" effect's counts: constructed 1 when built (with_viscosity), a pass per sub-step's force
  /// pass.
  const EffectCounter& viscosity_counter() const { return m_viscosity_counter; }
  /// The "surface_tension" effect's counts: constructed 1 when built, a pass per sub-step's force pass.
  const EffectCounter& surface_tension_counter() const { return m_surface_tension_counter; }
  /// The surface tension force, or nullptr when it was not built.
  const SurfaceTension* surface_tension() const { return m_surface_tension.get(); }
  /// Mass of one particle, rest_density * spacing^3 (unit: kg).
  Scalar particle_mass() const;

  /// Advances the fluid by dt (unit: s, > 0), in as many equal-ish sub-steps as the CFL limit asks, or
  /// shorter after a pressure solve that diverged (FluidSettings::substep_halvings; PBF: in
  /// settings().pbf.substeps equal ones). Stops before a sub-step with RUNAWAY_PARTICLE when a particle is
  /// faster than settings().max_speed.
  /// @param constraint  optional, applied after every sub-step (must outlive the call)
  StepStatus step(Scalar dt, SubstepConstraint* constraint = nullptr);

  /// Boundary particles of moving bodies (Akinci et al. 2012, as the static ones), after the static ones and
  /// replacing the last call's: where the bodies are for the next step(). Each pushes the fluid only along
  /// its face's normal (the part of Akinci's force along the face is taken back from the fluid in the same
  /// sub-step): pressure acts normal to a surface, and the part along a body's side faces, which the vertical
  /// pressure gradient makes, lifts a floating body as if its sides were thicker than they are. The reaction
  /// is summed per particle over that step (moving_boundary_impulses), so a body takes exactly the momentum
  /// its boundary gives the fluid.
  /// @param positions  B points (unit: m, finite); empty removes them
  /// @param volumes  B volumes V_b (unit: m^3), > 0; Psi_b = rest density V_b
  /// @param normals  B unit normals of the faces the points stand for, outward from the body
  /// @throws std::invalid_argument when the sizes differ
  void set_moving_boundary(const Vec3Array& positions, const ScalarArray& volumes, const Vec3Array& normals);
  /// set_moving_boundary with its last call's points, volumes and normals (bodies at rest), without
  /// rebuilding their grid. The next step() still searches its neighbors afresh, as after
  /// set_moving_boundary: the neighbor lists' order follows their rebuilds, so a run is the same bits whether
  /// its bodies rest or not.
  void keep_moving_boundary();
  /// B impulses the fluid's pressure gave the moving boundary particles in the last step() (unit: N s),
  /// sum over sub-steps and particles i of m_i dt w_i Psi_b grad W_ib (PressureSolver::
  /// boundary_pressure_factors; PBF's over its iterations, PressurePbf::boundary_pushes): the opposite of
  /// what they gave the fluid.
  const Vec3Array& moving_boundary_impulses() const { return m_moving_impulses; }

  /// Fastest particle speed (unit: m/s); NaN when a velocity is NaN.
  Scalar max_speed() const;
  /// RUNAWAY_PARTICLE, naming the fastest particle, when one is faster than settings().max_speed now (the
  /// test step() makes before each sub-step); else ok. For a caller that changes velocities after step()
  /// (the coupling's impulses, a body's push), so that the step that threw a particle says so: the last
  /// step of a run would otherwise end ok.
  StepStatus speed_check() const;
  /// speed_check() with the fastest speed known: `speed` = max_speed() now (unit: m/s).
  StepStatus speed_check(Scalar speed) const;
  /// The longest step the CFL limit allows now, cfl spacing / max(max_speed() + signal speed, gravity wave
  /// speed) (unit: s; FluidSettings::cfl): step() takes one sub-step for any dt up to it. Infinite when
  /// nothing moves and the particles have no extent along gravity (or there is none), and for PBF, whose
  /// sub-steps are fixed.
  Scalar cfl_step() const { return cfl_limit(max_speed()); }

 private:
  /// @param max_displacement  how far the fastest particle may move in the coming sub-step (unit: m): decides
  ///        the skin of a new grid search
  void update_neighbors(Scalar max_displacement);
  /// One sub-step. With `may_redo`, a pressure solve that diverged (PressureStats::diverged) leaves the state
  /// as the sub-step found it (but for the neighbor lists, the densities and the pressures) and sets `redo`.
  StepStatus substep(Scalar dt, Scalar max_speed, SubstepConstraint* constraint, bool may_redo, bool& redo);
  /// PBF's sub-step (Macklin & Mueller 2013, Algorithm 1): predicts positions with gravity, searches
  /// neighbors there, projects them (PressurePbf::project), takes v = (x* - x) / dt, then the viscosity
  /// (XSPH after the solve, as theirs) and the guards.
  StepStatus substep_pbf(Scalar dt, Scalar max_speed, SubstepConstraint* constraint);
  /// Re-sorts the particles along the z-order curve every settings().sort_interval sub-steps.
  void sort_particles();
  /// The densities (into particles().densities) at the current positions, with their neighbor lists.
  void compute_densities(const FluidContext& ctx);
  /// The end of a sub-step: with `integrate`, v = v_adv + dt a_pressure and x += dt v (else the positions
  /// moved already, from m_positions_before); then the guards, the non-finite and collapse checks
  /// (NON_FINITE_STATE, FLUID_COLLAPSED) and the constraint.
  StepStatus finish_substep(Scalar dt, SubstepConstraint* constraint, bool integrate);
  /// Adds a pressure solve's iterations and errors to the statistics.
  void record(const PressureStats& pressure);
  /// The solvers' view of this sub-step, with the neighbor lists of the last update.
  FluidContext context();
  /// Adds to m_moving_impulses what the sub-step's pressure gave the moving boundary points along their
  /// normals, and takes the rest of their push on the fluid back from m_pressure_accelerations.
  /// @param positions  N particle positions at which the neighbor lists' gradient factors were computed
  void add_moving_boundary_reactions(Scalar dt, const Vec3Array& positions);
  /// add_moving_boundary_reactions for PBF, from the pushes its projection summed over its iterations
  /// (PressurePbf::boundary_pushes).
  void add_pbf_boundary_reactions(Scalar dt);
  /// Books moving boundary point b's push on a particle (unit: N s): the body takes its part along b's face
  /// normal (m_moving_impulses); returns the rest, which the particle keeps.
  Vec3 book_boundary_push(Index b, const Vec3& push);
  /// Index of the fastest particle (the first of equals); 0 when there are none.
  std::size_t fastest_particle() const;
  /// The CFL sub-step for the fastest particle moving at `max_speed` (unit: s), no longer than the
  /// particles' surface waves allow (gravity_wave_speed); infinite when neither moves.
  Scalar cfl_limit(Scalar max_speed) const;
  /// sqrt(|g| H), H the particles' extent along gravity (unit: m/s): the fastest surface wave in water that
  /// deep (shallow water); 0 without gravity or particles.
  Scalar gravity_wave_speed() const;

  FluidSettings m_settings;
  Vec3 m_gravity;
  CubicSplineKernel m_kernel;
  ParticleSet m_particles;
  std::vector<BoundarySettings> m_guards;
  PackedPointArray m_boundary_packed;  // x_b (unit: m), w = Akinci's Psi_b = rho0 V_b (unit: kg)
  std::size_t m_static_boundary = 0;   // the first of m_boundary_packed's points that move
  Vec3Array m_moving_impulses;         // per moving boundary point, over the last step (unit: N s)
  Vec3Array m_moving_normals;          // per moving boundary point, its face's outward unit normal
  ScalarArray m_boundary_factors;      // scratch: the pressure solver's w_i
  VerletNeighborLists m_neighbors;
  PackedPointArray m_positions_mass;  // positions (unit: m), w = mass (unit: kg), for the densities
  Vec3Array m_positions_before;       // sub-step start positions, kept only for a SubstepConstraint (and PBF)
  std::unique_ptr<PressureSolver> m_pressure;
  PressurePbf* m_pbf = nullptr;  // m_pressure when the scene's solver is PBF
  std::unique_ptr<NonPressureForce> m_viscosity;
  EffectCounter m_viscosity_counter;
  std::unique_ptr<SurfaceTension> m_surface_tension;
  EffectCounter m_surface_tension_counter;
  Vec3Array m_accelerations;
  Vec3Array m_velocities_adv;
  Vec3Array m_pressure_accelerations;
  Vec3Array m_velocities_start;  // a sub-step's start velocities, kept while it may be redone (DFSPH)
  /// The longest sub-step since a pressure solve diverged at twice it (unit: s); infinite when none
  Scalar m_substep_cap = std::numeric_limits<Scalar>::infinity();
  FluidStatistics m_stats;
};

}  // namespace drench
