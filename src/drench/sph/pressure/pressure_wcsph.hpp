#pragma once

#include <drench/sph/pressure/pressure_solver.hpp>

namespace drench {

/// Weakly compressible SPH, Becker & Teschner 2007: Tait equation p = B ((rho / rho0)^gamma - 1) with
/// B = rho0 c^2 / gamma, clamped at 0 so that a free surface does not pull particles together, and rho / rho0
/// at most 1 + WcsphSettings::max_compression when that is set.
class PressureWcsph final : public PressureSolver {
 public:
  /// @param speed_of_sound  c (unit: m/s), > 0
  PressureWcsph(const FluidSettings& settings, Scalar speed_of_sound);

  PressureStats solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                      Vec3Array& accelerations) override;
  void boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const override;
  Scalar signal_speed() const override { return m_speed_of_sound; }

 private:
  Scalar m_speed_of_sound;
  Scalar m_exponent;
  Scalar m_stiffness;                  // B (unit: Pa)
  Scalar m_max_ratio;                  // the largest rho / rho0 turned into pressure (infinity: no limit)
  PackedPointArray m_pressure_points;  // N: positions (unit: m), w = p / rho^2
};

}  // namespace drench
