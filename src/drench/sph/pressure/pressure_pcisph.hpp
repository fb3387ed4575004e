#pragma once

#include <drench/sph/pressure/pressure_solver.hpp>

namespace drench {

/// Predictive-corrective incompressible SPH, Solenthaler & Pajarola 2009. Each iteration predicts positions
/// with the current pressure accelerations, evaluates the predicted density, raises pressures by
/// delta (rho* - rho0) (eq. 8, pressures clamped at 0 for free surfaces) and recomputes the pressure
/// accelerations, until the average compression is below eta (as SPlisHSPlasH's maxError) after at least
/// min_iterations, or max_iterations are spent. With PcisphSettings::max_compression_per_iteration set (the
/// default, a drench addition), one iteration raises a particle's pressure by at most delta times that
/// compression. With PcisphSettings::max_relief_per_substep set (the default, a drench addition), a
/// particle that enters a sub-step compressed by more than that fraction is driven to (its density -
/// max_relief), or to its first prediction if lower, instead of the rest density, and the stopping rule
/// measures the error against that target. PcisphSettings::precision chooses the precision of the
/// iterations' pair sums (single by default).
class PressurePcisph final : public PressureSolver {
 public:
  explicit PressurePcisph(const FluidSettings& settings);

  PressureStats solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                      Vec3Array& accelerations) override;
  void boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const override;

 private:
  PcisphSettings m_settings;
  /// sum_j |grad W_ij|^2 + |sum_j grad W_ij|^2 over a prototype particle with a filled lattice neighborhood
  /// (Solenthaler & Pajarola eq. 8) (unit: 1/m^8)
  Scalar m_prototype_gradient_term;
  PackedPointArray m_predicted;  // N: predicted positions (unit: m), w = mass (unit: kg)
  ScalarArray m_density;         // N: predicted densities (unit: kg/m^3)
  /// Density errors of one chunk of particles (unit: kg/m^3): sums of max(rho - rho0, 0) and of
  /// max(rho - target, 0), and the largest max(rho - rho0, 0).
  struct ChunkErrors {
    Scalar sum = 0.0, max = 0.0, sum_to_target = 0.0;
  };
  std::vector<ChunkErrors> m_chunk_errors;
  ScalarArray m_target;  // N, the density each particle is driven to in this sub-step (unit: kg/m^3)
  PackedPointArray m_pressure_points;  // N: positions (unit: m), w = p / rho0^2
  // For IterationPrecision::SINGLE, in float, every point relative to the centre of the fluid's bounding box
  // at the solve's start (unit: m):
  PackedPointFArray m_predicted_float;        // N: predicted positions, w = mass (unit: kg)
  PackedPointFArray m_pressure_points_float;  // N: positions, w = p / rho0^2 (unit: m^5/(kg s^2))
  PackedPointFArray m_boundary_float;  // ctx.boundary, w = Psi_b (unit: kg); made at each solve (the context
                                       // may change)
};

}  // namespace drench
