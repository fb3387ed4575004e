#pragma once
/// Surface tension, a non-pressure force built only when the scene's `effects` names "surface_tension".

#include <drench/sph/fluid_context.hpp>
#include <drench/sph/fluid_settings.hpp>
#include <drench/sph/forces/viscosity.hpp>

#include <memory>
#include <vector>

namespace drench {

/// A surface tension model: a force on the fluid's particles (SurfaceTensionSettings::model chooses one).
class SurfaceTension : public NonPressureForce {
 public:
  /// The last call's virial pressure of each particle's pair forces, (rho_i / 6) sum_j x_ij . a_ij (unit: Pa,
  /// negative where they pull): what the mechanical pressure adds to the solver's pressure (Irving &
  /// Kirkwood 1950), each pair shared between its particles. N values, 0 for a model without pair forces.
  virtual const ScalarArray& virial_pressures() const = 0;
};

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
/// It turns a 1 cm cube into a sphere within 50 ms with every pressure solver
/// (tests/sph/test_surface_tension.cpp) and holds droplets of any size together, but resting droplets hold 94
/// and 73 Pa at R = 4.5 and 8.5 mm against 2 sigma / R = 32 and 17 Pa. SurfaceTensionCsf, the default, uses
/// it in droplets too small for a continuum curvature, and its cohesion term alone beside the continuum
/// force.
class SurfaceTensionAkinci final : public SurfaceTension {
 public:
  /// Which of their two terms act.
  enum class Terms {
    COHESION_AND_CURVATURE,  ///< as published
    COHESION                 ///< the cohesion alone, a pair force that holds what the CSF cannot resolve
  };
  /// @param sigma  (unit: N/m), >= 0: the surface energy the cohesion is calibrated to;
  /// @param particle_spacing  (unit: m), > 0;  @param rest_density  (unit: kg/m^3), > 0
  SurfaceTensionAkinci(Scalar sigma, Scalar particle_spacing, Scalar rest_density,
                       Terms terms = Terms::COHESION_AND_CURVATURE);
  void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const override;
  /// As add_accelerations, on the particles i with mask[i] only (N flags), or all when null. Momentum is
  /// conserved where every pair within the support has both flags or neither (whole droplets).
  void add_pair_accelerations(const FluidContext& ctx, const std::vector<char>* mask,
                              Vec3Array& accelerations) const;
  /// Their gamma (unit: N m^3 / kg^2 in the cohesion term).
  Scalar gamma() const { return m_gamma; }
  const ScalarArray& virial_pressures() const override { return m_virial_pressures; }

 private:
  /// C(r) (unit: 1/m^3), Akinci et al. 2013 eq. 2, for the support radius m_support.
  Scalar cohesion_kernel(Scalar r) const;

  Terms m_terms;
  Scalar m_gamma;
  Scalar m_support;  // H (unit: m)
  Scalar m_rest_density;
  Scalar m_cohesion_scale;      // 32 / (pi H^9) (unit: 1/m^9)
  Scalar m_cohesion_offset;     // H^6 / 64 (unit: m^6)
  mutable Vec3Array m_normals;  // n_i (dimensionless), scratch kept between sub-steps
  mutable ScalarArray m_virial_pressures;
};

/// Continuum surface force (Brackbill, Kothe & Zemach 1992; for SPH Morris 2000): a_i = sigma kappa_i g_i /
/// (D rho0), with g_i = sum_j V_j grad W_ij (V_j = m_j / rho0) the gradient of the colour (1 in the fluid, 0
/// outside; it points inwards and is the surface's delta function) and kappa_i = div m the curvature of the
/// outward normals m. D = spacing sum_k |g_k| over a column of a flat cubic lattice's face (0.51 for the
/// cubic spline), so that the force per unit area of a face is sigma kappa: the interior of a droplet then
/// holds the pressure sigma kappa = 2 sigma / R. Not a pair force: the forces on a closed surface sum to zero
/// only as far as kappa is uniform. The curvature follows Morris 2000 in taking it only where the colour
/// gradient is reliable: on the surface layer, |g| spacing > 0.1 and |g smoothed| spacing > 0.16 (disorder
/// alone gives the first inside, rarely the second); other particles get no force. Two changes make it right
/// on a lattice, where plain colour-gradient normals gave 5-7 / R: the normals are of g smoothed twice with W
/// (a 4-spacing support, which irons out the lattice's steps), and the divergence is the renormalised one
/// (Bonet & Lok 1999) restricted to the tangent plane, trace(M^-1 G) with M = m m^T + sum_j (P w_j)(P
/// x_ji)^T, G = sum_j (P w_j)(m_j - m_i)^T, w_j = V_j grad W_ij, P = I - m_i m_i^T, over surface neighbours:
/// the surface layer is one particle thick, so the full M is singular there, and m's derivative along itself
/// is 0 anyway. kappa is then averaged over the surface neighbours with weights V_j W_ij and held within +-2
/// / spacing (a droplet of one spacing); a particle whose tangent plane holds too few surface neighbours (det
/// M < 0.01) gets kappa 0. Last, the particles' centres lie half a spacing inside the surface that bounds
/// their volumes, whose curvature is kappa / (1 + kappa spacing / 4) (a sphere's parallel surface). Beside it
/// acts Akinci et al. 2013's cohesion alone (SurfaceTensionAkinci::Terms::COHESION) with a share of sigma's
/// surface energy (3%; the continuum force takes the other 97%): a pair force that needs no curvature, so it
/// holds what the kernel cannot resolve. Without it, a 1 cm cube ringing as it rounds overshoots to an
/// octahedron whose tips are 2 x 2 particles, where the smoothed curvature reads 560 / m against about 1000
/// / m on a column 4 mm wide: the sides squeeze it more than its cap pulls it back, and with PCISPH the tips
/// pinched off and flew away (24 particles at 0.11 m/s; sphericity 0.943 at 50 ms). Shares of 0.02-0.04 hold
/// them (0.01 does not); the cohesion's mechanical tension is not its energy (alone, at the full share,
/// droplets hold 28 and 40 Pa where 2 sigma / R is 32 and 17), so the share is kept small.
/// Measured (tests/sph/test_surface_tension.cpp): on lattice droplets of R = 4.5, 8.5, 12.5 spacings kappa
/// reads 1.03, 1.06, 1.09 times 2 / R (weighted by |g|); a resting droplet under WCSPH holds 35.2 Pa at R =
/// 4.5 mm (2 sigma / R: 31.8) and 18.0 Pa at 8.5 mm (17.0) over 0.05-0.1 s (34.4 and 17.6 without the
/// cohesion), where Akinci's model holds 94 and 73 Pa. A 1 cm cube becomes a sphere in 50 ms with every
/// solver: sphericity 0.968 (DFSPH), 0.961 (PCISPH), 0.995 (WCSPH), 0.986 (PBF). Cost: five neighbour passes
/// for the continuum force, one with a 3 x 3 inverse per particle of the surface, and one for the cohesion.
/// Droplets (sets of particles joined by pairs within the support) smaller than a ball of kMinResolvedRadius
/// = 4 spacings (268 particles) take Akinci's full pair forces (SurfaceTensionAkinci, the other 97%) in place
/// of the continuum force: its normals are smoothed over 4 spacings, so it has no curvature to act on in
/// them. The adhesion's droplets of 3 and 3.5 spacings (tests/coupling/test_adhesion.cpp) failed without
/// this: one under a wetted plate left its top layer on the plate and fell, one on a water-repellent plate
/// spread into a film one particle thick (contact angle 9 degrees); a cohesion share of 1 mended neither.
/// With it their contact angles read 60 degrees on cotton, 122 water-repellent, 157 without adhesion (48, 118
/// and 150 with Akinci's model throughout). Choosing per particle instead (Akinci's forces on the pairs of
/// particles the continuum force gave no force or a curvature above 2 / (3.5 spacings)) mixed the two inside
/// one droplet and churned the cube (0.5 m/s, sphericity 0.89 at 50 ms). The default model
/// (SurfaceTensionSettings::model): the one that passes the cube, the Laplace pressure and the adhesion
/// tests.
class SurfaceTensionCsf final : public SurfaceTension {
 public:
  /// The cohesion's part of sigma by default (dimensionless).
  static constexpr Scalar kCohesionShare = 0.03;
  /// Droplets smaller than a ball of this radius (unit: particle spacings) take Akinci's pair forces in
  /// place of the continuum force: its curvature is checked from 4.5 spacings up, its normals are smoothed
  /// over 4.
  static constexpr Scalar kMinResolvedRadius = 4.0;
  /// @param sigma  (unit: N/m), >= 0;  @param particle_spacing  (unit: m), > 0, the kernel's smoothing length
  /// @param rest_density  (unit: kg/m^3), > 0: the cohesion's calibration
  /// @param cohesion_share  the part of sigma's surface energy given to the cohesion, in [0, 1); the
  /// continuum force carries the rest
  SurfaceTensionCsf(Scalar sigma, Scalar particle_spacing, Scalar rest_density,
                    Scalar cohesion_share = kCohesionShare);
  void add_accelerations(const FluidContext& ctx, Scalar dt, Vec3Array& accelerations) const override;
  /// The pair forces' virial: the cohesion's, and Akinci's in small droplets (the continuum force is no pair
  /// force).
  const ScalarArray& virial_pressures() const override { return m_virial_pressures; }
  /// The last call's curvature of each particle (unit: 1/m, positive where the surface is convex, 2 / R on a
  /// sphere), 0 off the surface layer.
  const ScalarArray& curvatures() const { return m_curvatures; }
  /// The last call's colour gradient g_i of each particle (unit: 1/m), pointing into the fluid.
  const Vec3Array& colour_gradients() const { return m_colour_gradients; }
  /// Whether each particle was, at the last call, in a droplet too small for the continuum force (N flags).
  const std::vector<char>& unresolved() const { return m_unresolved; }
  /// D (dimensionless): the flat lattice face's column sum of spacing |g|.
  Scalar delta_normalisation() const { return m_delta_normalisation; }

 private:
  /// Sets m_unresolved: the particles of droplets (sets joined by pairs within the support) smaller than
  /// m_min_resolved_particles.
  void mark_unresolved_droplets(const FluidContext& ctx) const;

  Scalar m_sigma;  // the continuum force's part of sigma (unit: N/m)
  Scalar m_spacing;
  Scalar m_delta_normalisation;
  SurfaceTensionAkinci m_cohesion;
  SurfaceTensionAkinci m_small_droplets;  // Akinci's full pair forces with the continuum force's share
  std::size_t m_min_resolved_particles;   // of a ball of kMinResolvedRadius spacings
  mutable std::vector<Index> m_droplet;   // union-find parents (a root is its own)
  mutable std::vector<std::size_t> m_droplet_sizes;
  mutable std::vector<char> m_unresolved;  // in a droplet below m_min_resolved_particles
  mutable std::size_t m_unresolved_count = 0;
  mutable ScalarArray m_virial_pressures;
  mutable Vec3Array m_colour_gradients;  // g_i (unit: 1/m)
  mutable Vec3Array m_smoothed;          // g smoothed (unit: 1/m), then the outward normals m_i
  mutable Vec3Array m_scratch;
  mutable std::vector<char> m_on_surface;
  mutable ScalarArray m_raw_curvatures;
  mutable ScalarArray m_curvatures;
};

/// Builds the surface tension force of the settings' model.
/// @param particle_spacing  (unit: m), > 0;  @param rest_density  (unit: kg/m^3), > 0: Akinci's calibration
std::unique_ptr<SurfaceTension> make_surface_tension(const SurfaceTensionSettings& settings,
                                                     Scalar particle_spacing, Scalar rest_density);

}  // namespace drench
