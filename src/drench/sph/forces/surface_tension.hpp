#pragma once
/// Surface tension, a non-pressure force built only when the scene's `effects` names "surface_tension".

#include <drench/sph/fluid_context.hpp>
#include <drench/sph/fluid_settings.hpp>
#include <drench/sph/forces/viscosity.hpp>

#include <memory>

namespace drench {

/// Akinci, Akinci & Teschner 2013 ("Versatile surface tension and adhesion for SPH fluids", eq. 1-4):
/// a_i = sum_j K_ij (-gamma m_j C(r_ij) x_ij / r_ij - gamma (n_i - n_j)), K_ij = 2 rho0 / (rho_i +
/// rho_j), n_i = H sum_j V_j grad W_ij (H the support radius), C their cohesion kernel (attracting for
/// r > H/2, repelling below, zero beyond H). A pair sum: momentum is conserved exactly.
/// Their gamma is not sigma; drench sets gamma = 2 sigma spacing^2 / (m^2 S), with S the sum over the pairs
/// of a cubic lattice that straddle a plane, per lattice column, of int_r^H C: the work per unit area of
/// pulling two half-spaces of the lattice apart by the cohesion is then 2 sigma (the definition of sigma).
/// That is its surface energy, not its mechanical tension (issue 43, tests/sph/test_surface_tension.cpp): on
/// a flat slab, periodic sideways and damped, int (p_N - p_T) dz of the pair forces' virial is 0.003-0.014
/// N/m at sigma 0.072 without the curvature term (the particles at rest are a lattice that holds shear
/// stress, so its surface stress need not equal its surface energy) and 0.014-0.152 N/m with it, which never
/// lets the fluid rest (it is not the gradient of an energy): resting droplets do not hold 2 sigma / R.
/// Chosen by measurement over a continuum surface force (Brackbill et al. 1992, Morris 2000), which is
/// calibrated to sigma by construction but needs the curvature: from colour-gradient normals, on a lattice
/// droplet of 4.5 and 8.5 spacings, it read 5-7 / R where 2 / R is right (2.1-2.3 / R with the exact
/// normals), and the droplets it drove did not come to rest. This one turns a cube into a sphere with every
/// pressure solver (tests/sph/test_surface_tension.cpp).
class SurfaceTensionAkinci final : public NonPressureForce {
 public:
  /// @param sigma  (unit: N/m), >= 0;  @param particle_spacing  (unit: m), > 0;
  /// @param rest_density  (unit: kg/m^3), > 0
  SurfaceTensionAkinci(Scalar sigma, Scalar particle_spacing, Scalar rest_density);
  void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const override;
  /// Their gamma (unit: N m^3 / kg^2 in the cohesion term).
  Scalar gamma() const { return m_gamma; }
  /// The last call's virial pressure of each particle's pair forces, (rho_i / 6) sum_j x_ij . a_ij (unit: Pa,
  /// negative where they pull): what the mechanical pressure adds to the solver's pressure (Irving &
  /// Kirkwood 1950), each pair shared between its particles.
  const ScalarArray& virial_pressures() const { return m_virial_pressures; }

 private:
  /// C(r) (unit: 1/m^3), Akinci et al. 2013 eq. 2, for the support radius m_support.
  Scalar cohesion_kernel(Scalar r) const;

  Scalar m_gamma;
  Scalar m_support;  // H (unit: m)
  Scalar m_rest_density;
  Scalar m_cohesion_scale;      // 32 / (pi H^9) (unit: 1/m^9)
  Scalar m_cohesion_offset;     // H^6 / 64 (unit: m^6)
  mutable Vec3Array m_normals;  // n_i (dimensionless), scratch kept between sub-steps
  mutable ScalarArray m_virial_pressures;
};

/// Builds the surface tension force of the settings.
/// @param particle_spacing  (unit: m), > 0;  @param rest_density  (unit: kg/m^3), > 0: Akinci's calibration
std::unique_ptr<SurfaceTensionAkinci> make_surface_tension(const SurfaceTensionSettings& settings,
                                                           Scalar particle_spacing, Scalar rest_density);

}  // namespace drench
