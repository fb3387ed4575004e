#pragma once

/// What pressure solvers and forces see of the fluid during one sub-step.

#include "common/types.hpp"
#include "sph/cubic_spline_kernel.hpp"
#include "sph/neighbor_search.hpp"
#include "sph/particle_set.hpp"

namespace drench {

/// Read access to the particles, their neighborhoods and the static boundary during one fluid sub-step.
/// Neighbor lists are valid for the current particle order and positions.
struct FluidContext {
  const CubicSplineKernel& kernel;
  ParticleSet& particles;
  const NeighborList& fluid_neighbors;     ///< fluid -> fluid, self excluded
  const NeighborList& boundary_neighbors;  ///< fluid -> boundary particles
  const Vec3Array& boundary_positions;     ///< (unit: m)
  const ScalarArray& boundary_psi;         ///< Akinci's Psi_b = rho0 V_b (unit: kg)
  Scalar rest_density;                     ///< (unit: kg/m^3)
  Scalar particle_spacing;                 ///< (unit: m)
  /// For every entry of fluid_neighbors.indices, f with grad W(x_i - x_j) = f (x_i - x_j) at the current
  /// positions (unit: 1/m^5). One number instead of a 3-vector per pair: PCISPH's pressure loop streams these
  /// every iteration and was memory-bound on 3-vectors (34% of its sub-step, measured).
  const ScalarArray& fluid_gradient_factors;
  /// The same for every entry of boundary_neighbors.indices, with x_b in place of x_j (unit: 1/m^5)
  const ScalarArray& boundary_gradient_factors;
};

/// SPH density of particle i at positions `x` (N, unit: m): sum_j m_j W_ij over fluid neighbors and itself,
/// plus sum_b Psi_b W_ib over boundary neighbors (Akinci et al. 2012 eq. 6). Unit: kg/m^3.
inline Scalar sph_density(const FluidContext& ctx, const Vec3Array& x, std::size_t i) {
  const auto& k = ctx.kernel;
  Scalar rho = ctx.particles.masses[i] * k.value(0.0);
  for (const Index* j = ctx.fluid_neighbors.begin(i); j != ctx.fluid_neighbors.end(i); ++j) {
    rho += ctx.particles.masses[*j] * k.value((x[i] - x[*j]).norm());
  }
  for (const Index* b = ctx.boundary_neighbors.begin(i); b != ctx.boundary_neighbors.end(i); ++b) {
    rho += ctx.boundary_psi[*b] * k.value((x[i] - ctx.boundary_positions[*b]).norm());
  }
  return rho;
}

/// Symmetric SPH pressure acceleration of particle i (unit: m/s^2):
/// -sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad W_ij - sum_b Psi_b p_i / rho_i^2 grad W_ib
/// (Akinci et al. 2012 eq. 10). `p_over_rho2` holds p / rho^2 per particle. The boundary term is the negative
/// gradient of the internal energy that the boundary's density contribution adds, so it conserves energy;
/// pressure mirroring (2 p_i, as some codes use) made a closed tank gain kinetic energy without bound, and a
/// hydrostatic extrapolation of p_b (Adami et al. 2012) drove corner particles up at 1 m/s with PCISPH's
/// noisy pressures (both measured).
inline Vec3 pressure_acceleration(const FluidContext& ctx, const ScalarArray& p_over_rho2, std::size_t i) {
  const Scalar pi = p_over_rho2[i];
  const Vec3Array& x = ctx.particles.positions;
  Vec3 a = Vec3::Zero();
  const auto& fn = ctx.fluid_neighbors;
  for (std::uint32_t n = fn.offsets[i]; n < fn.offsets[i + 1]; ++n) {
    const Index j = fn.indices[n];
    const Vec3 gradient = ctx.fluid_gradient_factors[n] * (x[i] - x[j]);
    a -= ctx.particles.masses[j] * (pi + p_over_rho2[j]) * gradient;
  }
  if (pi != 0.0) {
    const auto& bn = ctx.boundary_neighbors;
    for (std::uint32_t n = bn.offsets[i]; n < bn.offsets[i + 1]; ++n) {
      const Index b = bn.indices[n];
      const Vec3 gradient = ctx.boundary_gradient_factors[n] * (x[i] - ctx.boundary_positions[b]);
      a -= ctx.boundary_psi[b] * pi * gradient;
    }
  }
  return a;
}

}  // namespace drench
