#pragma once

/// What pressure solvers and forces see of the fluid during one sub-step.

#include <cmath>
#include <cstdint>

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
  /// The mass every particle has (unit: kg), or 0 when masses differ (ParticleSet::common_mass). Every
  /// emitter makes rho0 spacing^3; the pair loops then leave out a gather per pair (PCISPH runs them every
  /// iteration).
  Scalar uniform_mass = 0.0;
};

namespace detail {

/// m_j for the pair loops: the context's uniform mass, or the particle's own.
template <bool kUniformMass>
inline Scalar mass_of(const Scalar* masses, Scalar uniform_mass, Index j) {
  if constexpr (kUniformMass) {
    return uniform_mass;
  } else {
    return masses[j];
  }
}

/// sum over the neighbors j of i in `list` of weight(j) W(|x_i - x_j|), with x_j read from `sources` (N x 3
/// doubles). Vectorized over neighbors (`omp simd` over raw coordinate arrays): the pairs are independent,
/// and evaluating several at once hides the square root's latency. The vector reduction fixes its own
/// summation order, so results still do not depend on the thread count.
template <class Weight>
inline Scalar kernel_sum(const CubicSplineKernel& k, const NeighborList& list, std::size_t i,
                         const Scalar* xi, const Scalar* sources, Weight weight) {
  Scalar sum = 0.0;
  const Index* js = list.indices.data();
#pragma omp simd reduction(+ : sum)
  for (std::uint32_t n = list.offsets[i]; n < list.offsets[i + 1]; ++n) {
    const std::size_t j = 3 * std::size_t{js[n]};
    const Scalar dx = xi[0] - sources[j], dy = xi[1] - sources[j + 1], dz = xi[2] - sources[j + 2];
    sum += weight(js[n]) * k.value(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return sum;
}

template <bool kUniformMass>
inline Scalar sph_density(const FluidContext& ctx, const Vec3Array& x, std::size_t i) {
  const Scalar* xs = coordinates(x);
  const Scalar* m = ctx.particles.masses.data();
  const Scalar m_uniform = ctx.uniform_mass;
  const Scalar* psi = ctx.boundary_psi.data();
  const Scalar* xi = xs + 3 * i;
  const Scalar fluid = kernel_sum(ctx.kernel, ctx.fluid_neighbors, i, xi, xs,
                                  [=](Index j) { return mass_of<kUniformMass>(m, m_uniform, j); });
  const Scalar boundary = kernel_sum(ctx.kernel, ctx.boundary_neighbors, i, xi,
                                     coordinates(ctx.boundary_positions), [=](Index b) { return psi[b]; });
  return fluid + boundary + m[i] * ctx.kernel.value(0.0);
}

}  // namespace detail

/// SPH density of particle i at positions `x` (N, unit: m): sum_j m_j W_ij over fluid neighbors and itself,
/// plus sum_b Psi_b W_ib over boundary neighbors (Akinci et al. 2012 eq. 6). Unit: kg/m^3.
inline Scalar sph_density(const FluidContext& ctx, const Vec3Array& x, std::size_t i) {
  return ctx.uniform_mass > 0.0 ? detail::sph_density<true>(ctx, x, i)
                                : detail::sph_density<false>(ctx, x, i);
}

namespace detail {

template <bool kUniformMass>
inline Vec3 pressure_acceleration(const FluidContext& ctx, const ScalarArray& p_over_rho2, std::size_t i) {
  // Vectorized over neighbors as sph_density is.
  const Scalar pi = p_over_rho2[i];
  const Scalar* pj = p_over_rho2.data();
  const Scalar* xs = coordinates(ctx.particles.positions);
  const Scalar* m = ctx.particles.masses.data();
  const Scalar m_uniform = ctx.uniform_mass;
  const Scalar* f = ctx.fluid_gradient_factors.data();
  const Scalar xi = xs[3 * i], yi = xs[3 * i + 1], zi = xs[3 * i + 2];
  Scalar ax = 0.0, ay = 0.0, az = 0.0;
  const auto& fn = ctx.fluid_neighbors;
  const Index* fj = fn.indices.data();
#pragma omp simd reduction(+ : ax, ay, az)
  for (std::uint32_t n = fn.offsets[i]; n < fn.offsets[i + 1]; ++n) {
    const Index j = fj[n];
    const std::size_t j3 = 3 * std::size_t{j};
    const Scalar s = mass_of<kUniformMass>(m, m_uniform, j) * (pi + pj[j]) * f[n];
    ax -= s * (xi - xs[j3]);
    ay -= s * (yi - xs[j3 + 1]);
    az -= s * (zi - xs[j3 + 2]);
  }
  if (pi != 0.0) {
    const Scalar* bs = coordinates(ctx.boundary_positions);
    const Scalar* psi = ctx.boundary_psi.data();
    const Scalar* fb = ctx.boundary_gradient_factors.data();
    const auto& bn = ctx.boundary_neighbors;
    const Index* bb = bn.indices.data();
#pragma omp simd reduction(+ : ax, ay, az)
    for (std::uint32_t n = bn.offsets[i]; n < bn.offsets[i + 1]; ++n) {
      const Index b = bb[n];
      const std::size_t b3 = 3 * std::size_t{b};
      const Scalar s = psi[b] * pi * fb[n];
      ax -= s * (xi - bs[b3]);
      ay -= s * (yi - bs[b3 + 1]);
      az -= s * (zi - bs[b3 + 2]);
    }
  }
  return Vec3(ax, ay, az);
}

}  // namespace detail

/// Symmetric SPH pressure acceleration of particle i (unit: m/s^2):
/// -sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad W_ij - sum_b Psi_b p_i / rho_i^2 grad W_ib
/// (Akinci et al. 2012 eq. 10). `p_over_rho2` holds p / rho^2 per particle. The boundary term is the negative
/// gradient of the internal energy that the boundary's density contribution adds, so it conserves energy;
/// pressure mirroring (2 p_i, as some codes use) made a closed tank gain kinetic energy without bound, and a
/// hydrostatic extrapolation of p_b (Adami et al. 2012) drove corner particles up at 1 m/s with PCISPH's
/// noisy pressures (both measured).
inline Vec3 pressure_acceleration(const FluidContext& ctx, const ScalarArray& p_over_rho2, std::size_t i) {
  return ctx.uniform_mass > 0.0 ? detail::pressure_acceleration<true>(ctx, p_over_rho2, i)
                                : detail::pressure_acceleration<false>(ctx, p_over_rho2, i);
}

}  // namespace drench
