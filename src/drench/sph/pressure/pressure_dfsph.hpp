#pragma once

#include <cstdint>
#include <vector>

#include <drench/sph/pressure/pressure_solver.hpp>

namespace drench {

/// Divergence-free SPH, Bender & Koschier 2017 ("Divergence-free SPH for incompressible and viscous fluids",
/// TVCG; first as SCA 2015). Per sub-step, at the positions of its start:
/// - correct_divergence(): the factors alpha_i (eq. 11, with Akinci's boundary particles in the gradient
/// sum),
///   then the divergence-free solve (Algorithm 2): kappa^v_i = (1/dt) max(D rho_i / Dt, 0) alpha_i,
///   velocities v_i -= dt sum_j m_j (kappa^v_i / rho_i + kappa^v_j / rho_j) grad W_ij - dt Psi_b kappa^v_i /
///   rho_i grad W_ib, until the mean of max(D rho / Dt, 0) / rho0 is below DfsphSettings::eta_divergence. A
///   particle with fewer than 20 neighbors (fluid and boundary) is left out, as SPlisHSPlasH does: its
///   density deficit is no divergence to undo. The paper runs it after the positions move; here it starts the
///   next sub-step, where SPlisHSPlasH runs it too (the same order of operations).
/// - solve(): the constant-density solve (Algorithm 3) from the advected velocities: rho*_i = rho_i + dt D
///   rho_i / Dt, kappa_i = max(rho*_i - rho0, 0) / dt^2 alpha_i, the same velocity update, until the mean of
///   max(rho* - rho0, 0) / rho0 is below DfsphSettings::eta after at least min_iterations. With
///   DfsphSettings::max_relief_per_substep set (the default, a drench addition as PCISPH's), a particle that
///   enters a sub-step compressed by more than that is driven to (its density - max_relief), or to its first
///   prediction if lower, instead of rho0, and the stopping rule measures the error against that target.
/// With DfsphSettings::warm_start, both solves start from half the last sub-step's kappas of the particles
/// that need correcting (the warm start of SPlisHSPlasH), following each particle by id through re-sorts,
/// emission and removal. The kappas are kept as they were, pressures, where SPlisHSPlasH keeps kappa dt^2 and
/// kappa^v dt and divides by the new step's: a steady pressure (a resting tank) does not change with the
/// step, and after a step cut short to land on a frame (65 us after 2 ms steps) kappa dt^2 made the warm
/// start 1,000 times the last step's pressure. The pressure reported per particle is rho_i^2 times the sum of
/// both solves' kappa_i / rho_i: the pressure whose acceleration over the sub-step is the velocity change
/// both solves made.
class PressureDfsph final : public PressureSolver {
 public:
  explicit PressureDfsph(const FluidSettings& settings);

  DivergenceStats correct_divergence(const FluidContext& ctx, Scalar dt) override;
  PressureStats solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                      Vec3Array& accelerations) override;
  void boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const override;

 private:
  /// Brings the warm-start arrays and the factors into the order of `particles` (by id) when it changed.
  void follow_particles(const ParticleSet& particles);
  /// m_points, m_inv_denominator and the iterations' records for the current positions; decides m_single.
  void compute_factors(const FluidContext& ctx);
  /// m_velocities (and in single precision m_velocities_float) from N velocities (unit: m/s).
  void set_velocities(const Vec3Array& velocities);
  /// This iteration's kappa_i / rho_i of particle i (unit: m^5/(kg s^2)), in the records the iterations read.
  Scalar kappa(std::size_t i) const { return m_single ? m_kappa_points_float[i].w : m_kappa_points[i].w; }
  void set_kappa(std::size_t i, Scalar value) {
    if (m_single) {
      m_kappa_points_float[i].w = static_cast<float>(value);
    } else {
      m_kappa_points[i].w = value;
    }
  }
  /// Errors of one chunk of particles: the sum and the largest of the per-particle errors.
  struct ChunkErrors {
    Scalar sum = 0.0, max = 0.0;
    Scalar sum_to_target = 0.0;  ///< density solve: the sum of max(rho*_i - target_i, 0)
  };
  enum class Measure {
    DIVERGENCE,     ///< the divergence solve's errors
    FIRST_DENSITY,  ///< the density solve's, fixing each particle's target density (max_relief_per_substep)
    DENSITY         ///< the density solve's, against the targets fixed
  };
  /// Each particle's error at m_velocities: max(rho*_i - rho0, 0) (unit: kg/m^3) for the density solve,
  /// max(D rho_i / Dt, 0) (unit: kg/(m^3 s), 0 for a particle short of neighbors) for the divergence solve.
  /// Into m_error the error the solve corrects (the density solve's against m_target), and into
  /// m_kappa_points' w the kappa_i / rho_i that corrects it. Returns the sums over particles, summed per
  /// chunk and then in chunk order (the same bits for any thread count), and the largest error.
  ChunkErrors measure(const FluidContext& ctx, Scalar dt, Measure what);
  /// One Jacobi velocity update: m_velocities[i] += dt a_i with a_i the symmetric pressure acceleration of
  /// w = m_kappa_points[i].w (unit: m^5/(kg s^2)); adds a_i to `accelerations` and w to `totals` when given.
  void update_velocities(const FluidContext& ctx, Scalar dt, Vec3Array* accelerations, ScalarArray* totals);
  /// Sets w = scale warm[i] for the particles with an error (0 for the others) and adds it to totals; false,
  /// changing nothing, when that is 0 for all.
  bool apply_warm_start(const ScalarArray& warm, Scalar scale, ScalarArray& totals);

  DfsphSettings m_settings;
  /// The least denominator a particle's step is divided by (unit: kg^2/m^8): a tenth of a filled lattice
  /// neighborhood's, an under-relaxation of the particles whose gradients cancel (the constructor says why).
  Scalar m_min_denominator;
  PackedPointArray m_points;        // N: positions (unit: m), w = mass (unit: kg)
  PackedPointArray m_velocities;    // N: the velocities the solve corrects (unit: m/s), w unused
  PackedPointArray m_kappa_points;  // N: positions (unit: m), w = this iteration's kappa_i / rho_i
  /// Single precision (DfsphSettings::precision): the iterations' pair sums read these instead of m_points,
  /// m_velocities and m_kappa_points, positions relative to single_precision_origin()'s origin; N each, and
  /// the boundary's points. Empty in double precision.
  bool m_single = false;
  PackedPointFArray m_points_float, m_velocities_float, m_kappa_points_float, m_boundary_float;
  /// N: 1 / (|sum_j m_j grad W_ij + sum_b Psi_b grad W_ib|^2 + sum_j |m_j grad W_ij|^2) (unit: m^8/kg^2), so
  /// that kappa_i / rho_i = (density error) / (dt^2 denominator); the denominator at least m_min_denominator.
  ScalarArray m_inv_denominator;
  ScalarArray m_kappa;             // N: density solve's sum of kappa_i / rho_i (unit: m^5/(kg s^2))
  ScalarArray m_kappa_divergence;  // N: divergence solve's sum of kappa^v_i / rho_i (unit: m^5/(kg s^2))
  /// N, by particle: m_kappa and m_kappa_divergence of the last sub-step (unit: m^5/(kg s^2)), the warm
  /// starts; in the order of m_ids.
  ScalarArray m_warm, m_warm_divergence;
  std::vector<std::uint32_t> m_ids;  // the particle ids m_warm and m_warm_divergence follow
  /// True from correct_divergence() to the end of solve(): the factors are those of the current positions.
  bool m_factors_current = false;
  ScalarArray m_by_id;   // follow_particles(): scratch, two values per id
  ScalarArray m_error;   // N: measure()'s per-particle errors to correct
  ScalarArray m_target;  // N: the density each particle is driven to in this sub-step (unit: kg/m^3)
  std::vector<ChunkErrors> m_chunk_errors;
};

/// The denominators of DFSPH's factor alpha_i = rho_i / denominator_i (Bender & Koschier 2017 eq. 11) of the
/// particles [begin, end): out[k] for particle begin + k is |sum_j m_j grad W_ij + sum_b Psi_b grad W_ib|^2 +
/// sum_j |m_j grad W_ij|^2 (unit: kg^2/m^8), with the gradients of ctx's gradient factors. Boundary particles
/// do not move, so they add to the first sum only (as SPlisHSPlasH).
/// @param x_mass  N particles: positions (unit: m) and w = mass (unit: kg)
/// Precondition: begin <= end <= N, out holds end - begin values. Sums run in neighbor-list order.
void dfsph_denominators(const FluidContext& ctx, const PackedPointArray& x_mass, std::size_t begin,
                        std::size_t end, Scalar* out);

/// The SPH rate of density change D rho_i / Dt = sum_j m_j (v_i - v_j) . grad W_ij + sum_b Psi_b v_i . grad
/// W_ib (Bender & Koschier 2017 eq. 9; boundary particles at rest) of the particles [begin, end) (unit:
/// kg/(m^3 s)), out[k] for particle begin + k.
/// @param x_mass  N particles: positions (unit: m) and w = mass (unit: kg)
/// @param velocities  N particles: velocities (unit: m/s) in x, y, z; w is not read
/// Precondition: as dfsph_denominators. Sums run in neighbor-list order.
void density_change(const FluidContext& ctx, const PackedPointArray& x_mass,
                    const PackedPointArray& velocities, std::size_t begin, std::size_t end, Scalar* out);

/// density_change in single precision, for DFSPH's iterations (fluid.dfsph.precision "single"): the sums over
/// neighbors in float, sixteen at a time (sph/float_lanes.hpp), converted to double; within 1e-5 of the sum
/// of the terms' magnitudes of density_change's (tests/sph/test_fluid_context.cpp).
/// @param x_mass  N particles: positions relative to an origin near the fluid (unit: m); w is not read, the
///                mass is ctx.uniform_mass
/// @param velocities  N particles: velocities (unit: m/s) in x, y, z; w is not read
/// @param boundary  ctx.boundary relative to the same origin (x_b in m, Psi_b in kg)
/// Precondition: as density_change, and ctx.uniform_mass > 0. Every copy and thread count gives the same
/// bits.
void density_change_float(const FluidContext& ctx, const PackedPointFArray& x_mass,
                          const PackedPointFArray& velocities, const PackedPointFArray& boundary,
                          std::size_t begin, std::size_t end, Scalar* out);

}  // namespace drench
