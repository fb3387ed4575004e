#include <drench/sph/fluid_context.hpp>

#include <cassert>
#include <cmath>
#include <cstdint>

#include <drench/common/parallel.hpp>
#include <drench/sph/float_lanes.hpp>
#include <drench/sph/packed_lanes.hpp>

namespace drench {
namespace {

/// Subtracts sum_n c_n f_n (x_i - x_n) over the entries [n, end) of a neighbor list from (sx, sy, sz), with
/// c_n = a(j_n) (alpha + w_n): the symmetric pressure term m_j (p_i / rho_i^2 + p_j / rho_j^2) for fluid
/// neighbors, and Psi_b p_i / rho_i^2 (alpha = 0, a = p_i / rho_i^2) for boundary ones. `factors` are the
/// gradient factors f of the entries.
template <class Coefficient>
[[gnu::always_inline]] inline void subtract_gradient_sum(const PackedPoint& xi, Scalar alpha,
                                                         const PackedPoint* points, const Index* js,
                                                         const float* factors, std::uint32_t n,
                                                         std::uint32_t end, Coefficient a, Scalar& sx,
                                                         Scalar& sy, Scalar& sz) {
  Lanes ax = {}, ay = {}, az = {};
  for (; n + kLanes <= end; n += kLanes) {
    FourPoints p;
    load_four(points, js + n, p);
    FloatLanes stored;
    std::memcpy(&stored, factors + n, sizeof(FloatLanes));
    const Lanes factor = __builtin_convertvector(stored, Lanes);
    Lanes a_lanes;
    for (std::uint32_t l = 0; l < kLanes; ++l)
      a_lanes[l] = a(js[n + l]);
    const Lanes s = a_lanes * (alpha + p.w) * factor;
    ax -= s * (xi.x - p.x);
    ay -= s * (xi.y - p.y);
    az -= s * (xi.z - p.z);
  }
  sx += lane_sum(ax);
  sy += lane_sum(ay);
  sz += lane_sum(az);
  for (; n < end; ++n) {
    const PackedPoint& p = points[js[n]];
    const Scalar s = a(js[n]) * (alpha + p.w) * Scalar{factors[n]};
    sx -= s * (xi.x - p.x);
    sy -= s * (xi.y - p.y);
    sz -= s * (xi.z - p.z);
  }
}

template <bool kUniformMass>
[[gnu::always_inline]] inline Vec3 pressure_acceleration(const FluidContext& ctx, const PackedPoint* points,
                                                         std::size_t i) {
  const PackedPoint& pi = points[i];
  const Scalar* m = ctx.particles.masses.data();
  const Scalar m_uniform = ctx.uniform_mass;
  const NeighborList& fn = ctx.fluid_neighbors;
  Scalar sx = 0.0, sy = 0.0, sz = 0.0;
  subtract_gradient_sum(
      pi, pi.w, points, fn.indices.data(), ctx.fluid_gradient_factors.data(), fn.offsets[i],
      fn.offsets[i + 1], [=](Index j) { return kUniformMass ? m_uniform : m[j]; }, sx, sy, sz);
  if (pi.w != 0.0) {
    const NeighborList& bn = ctx.boundary_neighbors;
    subtract_gradient_sum(
        pi, 0.0, ctx.boundary.data(), bn.indices.data(), ctx.boundary_gradient_factors.data(), bn.offsets[i],
        bn.offsets[i + 1], [w = pi.w](Index) { return w; }, sx, sy, sz);
  }
  return Vec3(sx, sy, sz);
}

}  // namespace

DRENCH_SIMD_CLONES void sph_densities(const FluidContext& ctx, const PackedPointArray& x_mass,
                                      std::size_t begin, std::size_t end, Scalar* out) {
  const PackedPoint* xs = x_mass.data();
  const PackedPoint* bs = ctx.boundary.data();
  const Scalar self = ctx.kernel.value(0.0);
  with_group_of_copy<HalvesGroup, WideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPoint& xi = xs[i];
      out[i - begin] = kernel_sum<Group>(ctx.kernel, ctx.fluid_neighbors, i, xi, xs) +
                       kernel_sum<Group>(ctx.kernel, ctx.boundary_neighbors, i, xi, bs) + xi.w * self;
    }
  });
}

DRENCH_SIMD_CLONES void pressure_accelerations(const FluidContext& ctx, const PackedPointArray& x_p_over_rho2,
                                               std::size_t begin, std::size_t end, Vec3* out) {
  const PackedPoint* points = x_p_over_rho2.data();
  if (ctx.uniform_mass > 0.0) {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = pressure_acceleration<true>(ctx, points, i);
  } else {
    for (std::size_t i = begin; i < end; ++i)
      out[i - begin] = pressure_acceleration<false>(ctx, points, i);
  }
}

DRENCH_SIMD_CLONES void sph_densities_float(const FluidContext& ctx, const PackedPointFArray& x_mass,
                                            const PackedPointFArray& boundary, std::size_t begin,
                                            std::size_t end, Scalar* out) {
  const PackedPointF* xs = x_mass.data();
  const PackedPointF* bs = boundary.data();
  const FloatKernel kernel(ctx.kernel);
  const Scalar self = ctx.kernel.value(0.0);
  with_group_of_copy<FloatHalvesGroup, FloatWideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPointF& xi = xs[i];
      out[i - begin] = Scalar{kernel_sum<Group>(kernel, ctx.fluid_neighbors, i, xi, xs)} +
                       Scalar{kernel_sum<Group>(kernel, ctx.boundary_neighbors, i, xi, bs)} +
                       Scalar{xi.w} * self;
    }
  });
}

DRENCH_SIMD_CLONES void pressure_accelerations_float(const FluidContext& ctx,
                                                     const PackedPointFArray& x_p_over_rho2,
                                                     const PackedPointFArray& boundary, std::size_t begin,
                                                     std::size_t end, Vec3* out) {
  assert(ctx.uniform_mass > 0.0);
  const PackedPointF* points = x_p_over_rho2.data();
  const float mass = static_cast<float>(ctx.uniform_mass);
  with_group_of_copy<FloatHalvesGroup, FloatWideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPointF& pi = points[i];
      float sx = 0.0f, sy = 0.0f, sz = 0.0f;
      float_subtract_gradient_sum<Group>(pi, pi.w, mass, points, ctx.fluid_neighbors, i,
                                         ctx.fluid_gradient_factors.data(), sx, sy, sz);
      if (pi.w != 0.0f) {
        float_subtract_gradient_sum<Group>(pi, 0.0f, pi.w, boundary.data(), ctx.boundary_neighbors, i,
                                           ctx.boundary_gradient_factors.data(), sx, sy, sz);
      }
      out[i - begin] = Vec3(sx, sy, sz);
    }
  });
}

}  // namespace drench
