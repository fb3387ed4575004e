#pragma once
/// Settings of the SPH fluid: rest state, pressure solver, viscosity, sub-stepping. Plain structs, kept apart
/// from the solver they configure (fluid_solver.hpp), filled from a scene's `fluid` section by the scene
/// loader or set in code. Every member states its unit and default; docs/scenes.md documents the same keys.

#include <optional>

#include <drench/common/types.hpp>

namespace drench {

/// Which pressure solver runs. Selected by name in the scene (`fluid.pressure_solver`).
enum class PressureSolverKind { WCSPH, PCISPH, DFSPH, PBF };

/// The name a scene gives `kind` ("wcsph", "pcisph", "dfsph", "pbf"), as summary.json reports it.
inline const char* pressure_solver_name(PressureSolverKind kind) {
  switch (kind) {
    case PressureSolverKind::WCSPH:
      return "wcsph";
    case PressureSolverKind::PCISPH:
      return "pcisph";
    case PressureSolverKind::DFSPH:
      return "dfsph";
    case PressureSolverKind::PBF:
      return "pbf";
  }
  return "";
}

/// The largest WcsphSettings::speed_of_sound (unit: m/s): above sound in water (1,480 m/s) and glycerol
/// (1,900 m/s). A WCSPH fluid stiffer than the liquid itself gains nothing, and its CFL sub-steps grow with
/// c: 1e5 m/s on the resting tank ran over 30 s for one step.
inline constexpr Scalar kMaxSpeedOfSound = 2000.0;

/// Weakly compressible SPH, Becker & Teschner 2007: Tait equation p = B ((rho / rho0)^gamma - 1).
struct WcsphSettings {
  /// Numerical speed of sound c (unit: m/s), B = rho0 c^2 / gamma. Unset: 10 x the scene's expected maximum
  /// speed (sqrt(2 g H) over the scene's height H plus the fastest emitter), i.e. Mach 0.1 and about 1%
  /// density variation (Monaghan 1994). At most kMaxSpeedOfSound.
  std::optional<Scalar> speed_of_sound;
  Scalar exponent = 7.0;  ///< gamma of the Tait equation (dimensionless), >= 1
  /// The largest compression (fraction of rest density, > 0) the Tait equation turns into pressure: a
  /// particle compressed further pushes as one compressed this much; unset = all of it, as published. A
  /// drench addition, as PcisphSettings::max_relief_per_substep and for the same reason: the coupling stacks
  /// particles against the cloth, and the seventh power throws them at several times the jet's speed. The
  /// flow's own compression at Mach 0.1 seldom reaches it (docs/accuracy.md, the largest step that holds).
  std::optional<Scalar> max_compression = 0.05;
};

/// Floating-point precision of PCISPH's, DFSPH's and PBF's iterations: the passes over neighbor pairs that
/// each iteration runs (fluid.pcisph.precision, fluid.dfsph.precision, fluid.pbf.precision). Pressures,
/// densities, velocities and positions are double either way.
enum class IterationPrecision {
  /// the pair sums in float (sph_densities_float, pressure_accelerations_float, density_change_float, PBF's
  /// pbf_constraint_float and pbf_moves_float)
  SINGLE,
  DOUBLE  ///< the pair sums in double (sph_densities, pressure_accelerations, density_change, pbf_constraint)
};

/// Predictive-corrective incompressible SPH, Solenthaler & Pajarola 2009.
struct PcisphSettings {
  Scalar eta = 0.001;      ///< target average density error (fraction of rest density), > 0
  int min_iterations = 3;  ///< at least this many correction iterations per sub-step, >= 1 (SPlisHSPlasH: 3)
  int max_iterations = 100;  ///< at most this many, >= min_iterations
  /// The largest compression (fraction of rest density, > 0) one iteration corrects for one particle; unset
  /// = none, as published. A drench addition: a compression made outside the fluid's forces (the
  /// coupling's position corrections, a hand-back, an emitter) is otherwise undone within one CFL sub-step,
  /// at a speed of about compression x spacing / sub-step that shrinks the next sub-step and feeds itself.
  /// With the limit it is undone over several iterations and sub-steps; a settled or smoothly moving fluid
  /// stays below it and is not changed. Without it the jet on a 5 mm cloth blows up (bench_jet_on_cloth
  /// table_thickness_5mm, docs/accuracy.md).
  std::optional<Scalar> max_compression_per_iteration = 0.05;
  /// The largest compression (fraction of rest density, > 0) one sub-step relieves for one particle; unset
  /// = all of it, as published. A drench addition: a particle that enters a sub-step compressed by more
  /// (its density at the sub-step's start) is driven to that density minus this limit instead of the rest
  /// density, the rest left to the next sub-steps; the compression its motion within the sub-step would
  /// add is resisted in full, as published. Stopping water against a moving cloth stacks particles between
  /// the fluid's steps, and undoing that inside one CFL sub-step throws them far faster than the flow;
  /// without the limit the jet on a cloth at dt 4 ms blows up (bench_jet_on_cloth leaks_continuous_dt_4ms,
  /// docs/accuracy.md).
  std::optional<Scalar> max_relief_per_substep = 0.05;
  /// Precision of the iterations' pair sums. Single (the default) agrees with double to about 1e-5 of a
  /// density and is faster (bench_dam_break's double rows, docs/performance.md). Double is also used,
  /// whatever this says, when particle masses differ.
  IterationPrecision precision = IterationPrecision::SINGLE;
};

/// Divergence-free SPH, Bender & Koschier 2015 and 2017 ("Divergence-free SPH for incompressible and viscous
/// fluids", TVCG 2017): a constant-density solve before integration and a divergence-free solve of the
/// velocity field, both Jacobi iterations with the factor alpha_i (eq. 11), warm-started from the last
/// sub-step.
struct DfsphSettings {
  /// Target average density error of the constant-density solve (fraction of rest density), in (0, 1): the
  /// mean over particles of max(rho*_i - rho0, 0) / rho0 at the velocities after the solve. 0.0005 is the
  /// maxError (0.05%) of SPlisHSPlasH's example scenes and of drench's runs beside it (docs/performance.md;
  /// its code's own default is 0.01%); Bender & Koschier 2015 ran their examples below 0.0001.
  Scalar eta = 0.0005;
  /// Target average divergence error of the divergence-free solve (unit: 1/s), > 0: the mean over particles
  /// of max(D rho_i / Dt, 0) / rho0. Bender & Koschier 2017 and SPlisHSPlasH (maxErrorV 0.1%) state it per
  /// step, 0.001 / dt; drench states it per second so that it does not change with the step: the default 0.4
  /// is their 0.1% at a step of 2.5 ms, the step bound of the 59K dam break (docs/performance.md).
  Scalar eta_divergence = 0.4;
  /// At least this many constant-density iterations per sub-step, >= 1 (SPlisHSPlasH: 2)
  int min_iterations = 2;
  int max_iterations = 100;  ///< at most this many, >= min_iterations (SPlisHSPlasH: 100)
  /// At most this many divergence-free iterations per sub-step, >= 1 (SPlisHSPlasH: 100)
  int max_divergence_iterations = 100;
  /// The largest compression (fraction of rest density, > 0) one sub-step relieves for one particle; unset =
  /// all of it, as published. A drench addition, as PcisphSettings::max_relief_per_substep and for the same
  /// reason: the coupling stacks particles against a moving cloth between the fluid's steps, and undoing that
  /// inside one CFL sub-step throws them far faster than the flow (the jet on a cloth at dt 4 ms: 168 m/s
  /// without it).
  std::optional<Scalar> max_relief_per_substep = 0.05;
  /// Start both solves from half the last sub-step's kappas of the particles they correct, as Bender &
  /// Koschier and SPlisHSPlasH do. Off by default, as PCISPH's warm start was rejected: on the dam break it
  /// saves a third of the density iterations (2.7 against 4.0 per sub-step), but a correction it carries over
  /// cannot be taken back (only compression is corrected), and the hydrostatic tank kept a particle moving at
  /// 0.14 m/s after 2 s (0.034 m/s without; test_hydrostatic_tank asks below 0.05).
  bool warm_start = false;
  /// Precision of the iterations' pair sums (the density change and the pressure acceleration), as
  /// PcisphSettings::precision: single is the default, for the same reason; double is also used, whatever
  /// this says, when particle masses differ.
  IterationPrecision precision = IterationPrecision::SINGLE;
};

/// The largest PbfSettings::scorr_n: 4 times the published 4.
inline constexpr int kMaxScorrExponent = 16;

/// Position Based Fluids, Macklin & Mueller 2013 (ACM TOG 32(4)): the density constraint
/// C_i = max(rho_i / rho0 - 1, 0) solved on positions by Jacobi iterations (their eq. 1-12), what games run
/// (NVIDIA FleX, PhysX 5 particles). A fixed count of sub-steps and iterations makes every frame cost the
/// same; its density error is larger than PCISPH's or DFSPH's at the same step, the price of that
/// (docs/accuracy.md).
struct PbfSettings {
  /// Fluid sub-steps per scene step, >= 1: fixed, not cut by the CFL limit, so that a game's frame costs the
  /// same every frame. Macklin & Mueller ran 2-4 sub-steps per 1/60 s frame. At 1/60 s the hydrostatic tank
  /// without viscosity (tests/sph/test_pbf.cpp) holds its interior within 1% of the rest density with 4 (at
  /// 4 iterations), not with 3 (1.04% over) or 2 (3.2%). docs/performance.md shows what fewer save in a
  /// game's frame.
  int substeps = 4;
  /// Jacobi iterations per sub-step, >= 1. Macklin & Mueller's examples ran 2-4 (their sec. 7). With 4
  /// sub-steps the resting tank holds within 1% with 3 or 4, but with 3 its fastest particle (0.22 m/s) is
  /// near the test's bound for settled water (0.24 m/s).
  int iterations = 4;
  /// The relaxation epsilon of their eq. 11 (constraint force mixing), as a fraction of sum_k |grad_k C|^2
  /// of a particle in a filled lattice (dimensionless), >= 0. They state epsilon in their scenes' units;
  /// relative to the lattice it means the same at every spacing. 1e-6 only keeps the division finite, as
  /// SPlisHSPlasH's epsilon does; larger values soften the constraint.
  Scalar relaxation = 1e-6;
  /// k of the artificial pressure s_corr = -k (W(r) / W(dq))^n (their eq. 13), in units of the constraint
  /// (a fraction of rest density, dimensionless), >= 0; 0 turns it off. Their k = 0.1 is in their scenes'
  /// units; here k = 0.1 pushes a pair at dq apart as a compression of 10% would.
  Scalar scorr_k = 0.1;
  /// The sub-step at which scorr_k holds as published (unit: s), > 0; nullopt: at every sub-step, as
  /// published. s_corr moves a particle by a distance per iteration that does not depend on the sub-step,
  /// and the sub-step's v = (x* - x) / dt turns it into a velocity growing as 1 / dt: at 4 iterations the
  /// resting tank's fastest particle after 0.1 s reached 0.58, 1.2, 6.2 and 26 m/s at sub-steps of 4.2, 1.0,
  /// 0.26 and 0.065 ms (0.61-0.77 m/s with scorr_k 0), and the dam break's reference (78 us sub-steps) threw
  /// water at 55 m/s (3.1 with scorr_k 0). On shorter sub-steps its move is scaled by (dt /
  /// scorr_substep)^2, as the move of the force it stands for (Monaghan 2000's artificial pressure, which
  /// their eq. 13 follows), so that it gives the same acceleration at every sub-step; on longer ones it
  /// stays as published. 1/240 s is 1/60 s in the default 4 sub-steps, the game's step their k was chosen
  /// for (2-4 sub-steps per 1/60 s frame, their sec. 7): the game's step is unchanged.
  std::optional<Scalar> scorr_substep = 1.0 / 240.0;
  /// The largest compression (fraction of rest density, > 0) one iteration corrects for one particle; unset =
  /// none, as published. A drench addition, as PcisphSettings::max_compression_per_iteration and for the
  /// same reason: a dynamic body moves its boundary particles several spacings into the water in one 1/60 s
  /// step, and projecting that compression away in one iteration turns it into a velocity of compression x
  /// spacing / sub-step; the game-like scene of demos/bullet_playground threw particles at 1,400 m/s without
  /// it. A resting or smoothly moving fluid stays below it.
  std::optional<Scalar> max_compression_per_iteration = 0.05;
  /// n of s_corr, in [1, kMaxScorrExponent] (theirs: 4). Each pair pays n - 1 multiplications in every
  /// iteration, and a ratio W(r) / W(dq) above 1 overflows for large n.
  int scorr_n = 4;
  Scalar scorr_dq =
      0.2;  ///< |dq| of s_corr as a fraction of the kernel support radius, in (0, 1) (theirs: 0.1-0.3)
  /// Precision of the iterations' pair sums (the constraint pass: densities, constraint gradients, s_corr;
  /// and the move pass), as PcisphSettings::precision; the moves are added to double positions. Unlike
  /// PCISPH's and DFSPH's, it serves differing masses too (each record carries its particle's): wetting makes
  /// them differ in the game-like level. Single (the default) agrees with double within 4e-6 of a density
  /// on a compressed block (tests/sph/test_uniform_mass.cpp), within 0.07% of rho0 on the resting tank's mean
  /// density after 0.5 s, and to the printed digits after 2 s (1005.66 kg/m^3, tests/sph/test_pbf.cpp); it
  /// cut the constraint pass of bench_game_frame's level from 2.03G to 1.72G instructions (AVX2 copy).
  IterationPrecision precision = IterationPrecision::SINGLE;
};

/// Viscosity method. Constructed only when the scene's `effects` lists "viscosity".
enum class ViscosityKind {
  XSPH,       ///< velocity smoothing v_i += c sum_j m_j / rho_j (v_j - v_i) W_ij (Monaghan 1989)
  ARTIFICIAL  ///< Monaghan's artificial viscosity Pi_ij with coefficient alpha (Monaghan 1992)
};

struct ViscositySettings {
  ViscosityKind method = ViscosityKind::XSPH;
  /// Dimensionless coefficient (XSPH c or artificial alpha), >= 0. 0.01 is SPlisHSPlasH's standard value.
  Scalar coefficient = 0.01;
};

/// Surface tension of the water against air (the scene's `surface_tension` section). Constructed only when
/// the scene's `effects` lists "surface_tension" (forces/surface_tension.hpp has the model and why).
/// The surface tension model (forces/surface_tension.hpp has each and the measurements behind the default).
enum class SurfaceTensionModel {
  CSF,  ///< continuum surface force (Brackbill et al. 1992, Morris 2000), a cohesion, Akinci's in small drops
  AKINCI  ///< cohesion and curvature pair forces (Akinci et al. 2013)
};

struct SurfaceTensionSettings {
  /// Coefficient sigma (unit: N/m), >= 0; water against air at 20 C: 0.072.
  Scalar sigma = 0.072;
  /// The continuum surface force by default: with its cohesion and Akinci's forces in small droplets it
  /// turns a cube into a sphere with every pressure solver, holds the Laplace pressure and the adhesion's
  /// droplets; Akinci's model alone fails the Laplace pressure (forces/surface_tension.hpp).
  SurfaceTensionModel model = SurfaceTensionModel::CSF;
};

/// The most FluidSettings::substep_halvings may be; no fluid sub-step is shorter than dt / 2^this, so that
/// one step takes at most about a million sub-steps whatever the CFL limit.
inline constexpr int kMaxSubstepHalvings = 20;

/// The fluid of a scene (`fluid` in docs/scenes.md).
struct FluidSettings {
  Scalar rest_density = 1000.0;    ///< rho0 (unit: kg/m^3), > 0
  Scalar particle_spacing = 0.05;  ///< rest spacing of the particle lattice (unit: m), > 0; particle mass is
                                   ///< rho0 spacing^3 and the kernel support radius is 2 spacing
  PressureSolverKind pressure_solver = PressureSolverKind::PCISPH;
  WcsphSettings wcsph;
  PcisphSettings pcisph;
  DfsphSettings dfsph;
  PbfSettings pbf;
  ViscositySettings viscosity;
  /// CFL factor lambda (dimensionless), in (0, 1]: a fluid sub-step never exceeds lambda spacing / v_max,
  /// with v_max the fastest particle (plus the speed of sound for WCSPH), and at least sqrt(|g| H), the
  /// speed of a surface wave in water as deep as the particles' extent H along gravity, so that water at
  /// rest is not stepped at the whole frame. PBF ignores it (PbfSettings::substeps).
  Scalar cfl = 0.4;
  /// A particle faster than this stops the run with RUNAWAY_PARTICLE (unit: m/s), > 0; nullopt: no limit.
  /// Far above any flow of water, so only a blow-up reaches it, which would otherwise crawl: the CFL limit
  /// cuts each step for that one particle.
  std::optional<Scalar> max_speed = 1000.0;
  /// How many times a sub-step whose pressure solve diverged (PressureStats::diverged: it ended above eta
  /// with a larger error than before its first iteration) is halved and redone from its start, >= 0 (PCISPH
  /// and DFSPH; PBF's iterations are fixed). The shortened sub-step stays for the following steps and grows
  /// back by 1.25x per step without a redo, as the adaptive time step of Ihmsen et al. 2010 ("Boundary
  /// handling and adaptive time-stepping for PCISPH", their shock handling) restores a state and retries. A
  /// solve that only stalls above eta is kept (a shorter sub-step would relieve an old compression faster:
  /// the CaughtParticle test), as is one that diverges at dt / 2^substep_halvings, with
  /// PRESSURE_NOT_CONVERGED. 0 keeps every solve. A narrow dam break's corners threw PCISPH's water at
  /// 81 m/s without it (the NarrowDamBreakPcisph test). At most kMaxSubstepHalvings.
  int substep_halvings = 4;
  /// Fluid sub-steps between re-sorting particles along a z-order curve for cache locality, >= 1.
  int sort_interval = 10;
};

}  // namespace drench
