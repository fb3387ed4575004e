#include "sph/fluid_context.hpp"

#include <cmath>
#include <cstdint>

#include "common/parallel.hpp"
#include "sph/packed_lanes.hpp"

namespace drench {
namespace {

/// sum over the neighbors j of i in `list` of w_j W(|x_i - x_j|), for `sources` packed with their weights.
/// Four neighbors at a time in four lanes, then the last (count mod 4) one by one, in that order.
[[gnu::always_inline]] inline Scalar kernel_sum(const CubicSplineKernel& k, const NeighborList& list,
                                                std::size_t i, const PackedPoint& xi,
                                                const PackedPoint* sources) {
  const Index* js = list.indices.data();
  std::uint32_t n = list.offsets[i];
  const std::uint32_t end = list.offsets[i + 1];
  Lanes sum = {};
  for (; n + kLanes <= end; n += kLanes) {
    FourPoints p;
    load_four(sources, js + n, p);
    const Lanes dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
    const Lanes r2 = dx * dx + dy * dy + dz * dz;
    Lanes w;
    for (std::uint32_t l = 0; l < kLanes; ++l)
      w[l] = k.value(std::sqrt(r2[l]));
    sum += p.w * w;
  }
  Scalar total = lane_sum(sum);
  for (; n < end; ++n) {
    const PackedPoint& p = sources[js[n]];
    const Scalar dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
    total += p.w * k.value(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return total;
}

template <bool kUniformMass>
[[gnu::always_inline]] inline Vec3 pressure_acceleration(const FluidContext& ctx, const PackedPoint* points,
                                                         std::size_t i) {
  const PackedPoint& pi = points[i];
  const Scalar* m = ctx.particles.masses.data();
  const Scalar m_uniform = ctx.uniform_mass;
  const Scalar* f = ctx.fluid_gradient_factors.data();
  const NeighborList& fn = ctx.fluid_neighbors;
  const Index* js = fn.indices.data();
  std::uint32_t n = fn.offsets[i];
  const std::uint32_t end = fn.offsets[i + 1];
  Lanes ax = {}, ay = {}, az = {};
  for (; n + kLanes <= end; n += kLanes) {
    FourPoints p;
    load_four(points, js + n, p);
    Lanes factor, mass;
    std::memcpy(&factor, f + n, sizeof(Lanes));
    for (std::uint32_t l = 0; l < kLanes; ++l)
      mass[l] = kUniformMass ? m_uniform : m[js[n + l]];
    const Lanes s = mass * (pi.w + p.w) * factor;
    ax -= s * (pi.x - p.x);
    ay -= s * (pi.y - p.y);
    az -= s * (pi.z - p.z);
  }
  Scalar sx = lane_sum(ax), sy = lane_sum(ay), sz = lane_sum(az);
  for (; n < end; ++n) {
    const PackedPoint& p = points[js[n]];
    const Scalar s = (kUniformMass ? m_uniform : m[js[n]]) * (pi.w + p.w) * f[n];
    sx -= s * (pi.x - p.x);
    sy -= s * (pi.y - p.y);
    sz -= s * (pi.z - p.z);
  }
  if (pi.w != 0.0) {
    const PackedPoint* bs = ctx.boundary.data();
    const Scalar* fb = ctx.boundary_gradient_factors.data();
    const NeighborList& bn = ctx.boundary_neighbors;
    const Index* bb = bn.indices.data();
    std::uint32_t nb = bn.offsets[i];
    const std::uint32_t end_b = bn.offsets[i + 1];
    Lanes bx = {}, by = {}, bz = {};
    for (; nb + kLanes <= end_b; nb += kLanes) {
      FourPoints p;
      load_four(bs, bb + nb, p);
      Lanes factor;
      std::memcpy(&factor, fb + nb, sizeof(Lanes));
      const Lanes s = p.w * pi.w * factor;
      bx -= s * (pi.x - p.x);
      by -= s * (pi.y - p.y);
      bz -= s * (pi.z - p.z);
    }
    sx += lane_sum(bx);
    sy += lane_sum(by);
    sz += lane_sum(bz);
    for (; nb < end_b; ++nb) {
      const PackedPoint& p = bs[bb[nb]];
      const Scalar s = p.w * pi.w * fb[nb];
      sx -= s * (pi.x - p.x);
      sy -= s * (pi.y - p.y);
      sz -= s * (pi.z - p.z);
    }
  }
  return Vec3(sx, sy, sz);
}

}  // namespace

DRENCH_SIMD_CLONES void sph_densities(const FluidContext& ctx, const PackedPointArray& x_mass,
                                      std::size_t begin, std::size_t end, Scalar* out) {
  const PackedPoint* xs = x_mass.data();
  const PackedPoint* bs = ctx.boundary.data();
  const Scalar self = ctx.kernel.value(0.0);
  for (std::size_t i = begin; i < end; ++i) {
    const PackedPoint& xi = xs[i];
    out[i - begin] = kernel_sum(ctx.kernel, ctx.fluid_neighbors, i, xi, xs) +
                     kernel_sum(ctx.kernel, ctx.boundary_neighbors, i, xi, bs) + xi.w * self;
  }
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

}  // namespace drench
