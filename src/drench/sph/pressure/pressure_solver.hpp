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
  bool converged = true;             ///< false when PCISPH stopped at max_iterations above eta
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

}  // namespace drench
