#pragma once
/// Pressure solvers behind one interface; a scene selects one by name (`fluid.pressure_solver`).

#include <memory>
#include <string>

#include <drench/sph/fluid_context.hpp>
#include <drench/sph/fluid_settings.hpp>

namespace drench {

/// What one pressure solve reports.
struct PressureStats {
  int iterations = 0;                ///< correction iterations (1 for WCSPH)
  Scalar average_density_error = 0;  ///< mean over particles of max(rho - rho0, 0) / rho0 after the solve
  Scalar max_density_error = 0;      ///< largest max(rho - rho0, 0) / rho0 of any particle after the solve
  bool converged = true;             ///< false when the solve stopped at its max_iterations above eta
  /// True when it stopped at its max_iterations with a larger error (against its targets) than its first
  /// prediction's, before any pressure: the iterations made the state worse than none would have.
  bool diverged = false;
};

/// What one divergence solve (PressureSolver::correct_divergence) reports.
struct DivergenceStats {
  int iterations = 0;  ///< divergence iterations (0 for solvers without one)
  /// Mean over particles of max(D rho / Dt, 0) / rho0 after the solve (unit: 1/s)
  Scalar average_divergence_error = 0;
  bool converged = true;  ///< false when it stopped at its iteration limit above its target
};

/// A pressure solver turns densities and advected velocities into pressure accelerations.
class PressureSolver {
 public:
  virtual ~PressureSolver() = default;

  /// Computes pressures (stored in ctx.particles.pressures) and pressure accelerations.
  /// @param velocities_adv  N velocities after non-pressure forces, v + dt a_nonpressure (unit: m/s)
  /// @param dt  sub-step (unit: s), > 0
  /// @param accelerations  out: N pressure accelerations (unit: m/s^2)
  /// Preconditions: ctx.particles.densities hold the SPH densities at the current positions.
  virtual PressureStats solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                              Vec3Array& accelerations) = 0;

  /// Called once per sub-step after the densities at the sub-step's start and before the non-pressure forces;
  /// may change ctx.particles.velocities. DFSPH makes the velocity field divergence-free here: Bender &
  /// Koschier 2017 (Algorithm 1) do it at the end of a step, after the positions moved, with fresh neighbors
  /// and densities; the start of the next sub-step is the same point of the sequence, where those are
  /// computed anyway (and where SPlisHSPlasH does it). The default does nothing.
  /// @param dt  the sub-step about to be taken (unit: s), > 0
  /// Preconditions: as solve(); solve() of the same sub-step follows.
  virtual DivergenceStats correct_divergence(const FluidContext& /*ctx*/, Scalar /*dt*/) { return {}; }

  /// For the last solve (and, for DFSPH, the divergence solve of the same sub-step): w_i with which the
  /// boundary particles b pushed particle i, a_i = -w_i sum_b Psi_b grad W_ib (Akinci et al. 2012 eq. 10),
  /// so that a moving boundary can take the opposite (unit: m^5/(kg s^2)); N entries into `out`.
  /// WCSPH p_i / rho_i^2, PCISPH p_i / rho0^2, DFSPH the sum of its kappas.
  virtual void boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const = 0;

  /// A speed the CFL condition must add to the fastest particle's (unit: m/s): the speed of sound for
  /// weakly compressible solvers, 0 for incompressible ones.
  virtual Scalar signal_speed() const { return 0.0; }
};

/// Builds the solver a scene names. `speed_of_sound` is WCSPH's c (unit: m/s) with the scene's auto default
/// already resolved.
std::unique_ptr<PressureSolver> make_pressure_solver(const FluidSettings& settings, Scalar speed_of_sound);

/// Shared by the solvers: mean and max of max(rho_i - rho0, 0) / rho0, summed in index order so that the
/// result does not depend on the thread count.
void density_error_stats(const ScalarArray& densities, Scalar rest_density, PressureStats& stats);

/// Whether a solver's iterations run their pair sums in single precision this sub-step, and the origin their
/// float records are relative to (unit: m): the centre of the finite particles' bounding box, so that the
/// rounding (2^-24 of a coordinate's magnitude) depends on the fluid's extent, not on where the scene sits in
/// the world (at x = 100 m a float is 7.6 um coarse, 3e-4 of a 25 mm spacing). True when `precision` asks
/// for it, every particle has one mass (ctx.uniform_mass > 0: the float pressure loop takes it as a
/// constant) and the fluid reaches at most about 1,680 spacings from that centre (beyond it a rounding would
/// exceed 1e-4 of a spacing: a particle flung far without a kill region). Shared by PCISPH, DFSPH and PBF;
/// the result is the same for any thread count.
/// @param origin  out: the origin, the zero vector when the result is false or no particle is finite
/// @param needs_uniform_mass  false for loops that carry each particle's mass in its record (PBF's): then
///        differing masses do not take the double loops
bool single_precision_origin(const FluidContext& ctx, IterationPrecision precision, Vec3& origin,
                             bool needs_uniform_mass = true);

}  // namespace drench
