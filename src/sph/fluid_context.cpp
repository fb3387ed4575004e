#include "sph/fluid_context.hpp"

#include <cmath>
#include <cstdint>

#include "common/parallel.hpp"

namespace drench {
namespace {

/// m_j for the pair loops: the context's uniform mass, or the particle's own.
template <bool kUniformMass>
[[gnu::always_inline]] inline Scalar mass_of(const Scalar* masses, Scalar uniform_mass, Index j) {
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
[[gnu::always_inline]] inline Scalar kernel_sum(const CubicSplineKernel& k, const NeighborList& list,
                                                std::size_t i, const Scalar* xi, const Scalar* sources,
                                                Weight weight) {
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
[[gnu::always_inline]] inline Scalar sph_density(const FluidContext& ctx, const Vec3Array& x, std::size_t i) {
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

template <bool kUniformMass>
[[gnu::always_inline]] inline Vec3 pressure_acceleration(const FluidContext& ctx,
                                                         const ScalarArray& p_over_rho2, std::size_t i) {
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

}  // namespace

DRENCH_SIMD_CLONES void sph_densities(const FluidContext& ctx, const Vec3Array& x, std::size_t begin,
                                      std::size_t end, Scalar* out) {
  if (ctx.uniform_mass > 0.0) {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = sph_density<true>(ctx, x, i);
  } else {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = sph_density<false>(ctx, x, i);
  }
}

DRENCH_SIMD_CLONES void pressure_accelerations(const FluidContext& ctx, const ScalarArray& p_over_rho2,
                                               std::size_t begin, std::size_t end, Vec3* out) {
  if (ctx.uniform_mass > 0.0) {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = pressure_acceleration<true>(ctx, p_over_rho2, i);
  } else {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = pressure_acceleration<false>(ctx, p_over_rho2, i);
  }
}

}  // namespace drench
