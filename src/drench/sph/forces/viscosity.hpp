#pragma once
/// Viscosity, a non-pressure force built only when the scene's `effects` names "viscosity".

#include <memory>

#include <drench/sph/fluid_context.hpp>
#include <drench/sph/fluid_settings.hpp>

namespace drench {

/// A force other than pressure, evaluated once per fluid sub-step before the pressure solve.
class NonPressureForce {
 public:
  virtual ~NonPressureForce() = default;
  /// Adds this force's accelerations (unit: m/s^2) to `accelerations` (N).
  /// Preconditions: ctx.particles.densities are current; dt (unit: s) > 0.
  virtual void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const = 0;
};

/// XSPH velocity smoothing (Monaghan 1989) written as an acceleration:
/// a_i = (c / dt) sum_j m_j / rho_j (v_j - v_i) W_ij, with c the dimensionless coefficient.
class ViscosityXsph final : public NonPressureForce {
 public:
  explicit ViscosityXsph(Scalar coefficient) : m_coefficient(coefficient) {}
  void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const override;

 private:
  Scalar m_coefficient;
  // Scratch of add_accelerations, kept between sub-steps: positions with m / rho (unit: m, m^3), velocities
  // (unit: m/s), packed for the pair loop.
  mutable PackedPointArray m_x_volume;
  mutable PackedPointArray m_velocities;
};

/// Monaghan 1992 artificial viscosity: a_i = -sum_j m_j Pi_ij grad W_ij with
/// Pi_ij = -alpha c h mu_ij / rho_ij, mu_ij = v_ij . x_ij / (|x_ij|^2 + 0.01 h^2) for approaching pairs
/// (v_ij . x_ij < 0), else 0; rho_ij the mean density, c the scene's speed of sound, h the smoothing length.
class ViscosityArtificial final : public NonPressureForce {
 public:
  /// @param alpha  dimensionless, >= 0;  @param speed_of_sound  (unit: m/s), > 0
  ViscosityArtificial(Scalar alpha, Scalar speed_of_sound)
      : m_alpha(alpha), m_speed_of_sound(speed_of_sound) {}
  void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const override;

 private:
  Scalar m_alpha;
  Scalar m_speed_of_sound;
};

/// Builds the viscosity the settings name.
std::unique_ptr<NonPressureForce> make_viscosity(const ViscositySettings& settings, Scalar speed_of_sound);

}  // namespace drench
