#pragma once

/// What pressure solvers and forces see of the fluid during one sub-step.

#include <cstddef>
#include <vector>

#include <drench/common/types.hpp>
#include <drench/sph/cubic_spline_kernel.hpp>
#include <drench/sph/neighbor_search.hpp>
#include <drench/sph/particle_set.hpp>

namespace drench {

/// A point and one scalar that the pair loops read with it (w: a mass, Akinci's Psi_b, or p / rho^2), in one
/// aligned 32-byte record: a neighbor is one vector load instead of four gathered scalars, and four or eight
/// neighbors are transposed into x, y, z and w vectors in registers. PCISPH's pressure solve runs about 1.6x
/// faster over these than over gathered N x 3 coordinates (bench_dam_break pcisph_59k).
struct alignas(4 * sizeof(Scalar)) PackedPoint {
  Scalar x, y, z;  ///< (unit: m)
  Scalar w;        ///< unit of the loop that reads it
};
/// The record of the point x (unit: m) with the scalar w.
inline PackedPoint packed(const Vec3& x, Scalar w) {
  return {x.x(), x.y(), x.z(), w};
}
/// N packed points, one per particle or boundary point.
using PackedPointArray = std::vector<PackedPoint>;

/// A PackedPoint in single precision (16 bytes): PCISPH's iterations read these (sph/float_lanes.hpp has
/// why).
struct alignas(4 * sizeof(float)) PackedPointF {
  float x, y, z;  ///< (unit: m)
  float w;        ///< unit of the loop that reads it
};
/// The record of the point x (unit: m) with the scalar w, each rounded to float.
inline PackedPointF packed_float(const Vec3& x, Scalar w) {
  return {static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z()),
          static_cast<float>(w)};
}
/// N single-precision packed points.
using PackedPointFArray = std::vector<PackedPointF>;

/// Read access to the particles, their neighborhoods and the static boundary during one fluid sub-step.
/// Neighbor lists are valid for the current particle order and positions.
struct FluidContext {
  const CubicSplineKernel& kernel;
  ParticleSet& particles;
  const NeighborList& fluid_neighbors;     ///< fluid -> fluid, self excluded
  const NeighborList& boundary_neighbors;  ///< fluid -> boundary particles
  /// Boundary particles: x_b (unit: m) and w = Akinci's Psi_b = rho0 V_b (unit: kg)
  const PackedPointArray& boundary;
  Scalar rest_density;      ///< (unit: kg/m^3)
  Scalar particle_spacing;  ///< (unit: m)
  /// For every entry of fluid_neighbors.indices, f with grad W(x_i - x_j) = f (x_i - x_j) at the current
  /// positions (unit: 1/m^5), in float (GradientFactorArray). One number instead of a 3-vector per pair:
  /// PCISPH's pressure loop streams these every iteration and was memory-bound on 3-vectors, a third of its
  /// sub-step (bench_pair_loops pcisph_solve).
  const GradientFactorArray& fluid_gradient_factors;
  /// The same for every entry of boundary_neighbors.indices, with x_b in place of x_j (unit: 1/m^5)
  const GradientFactorArray& boundary_gradient_factors;
  /// The mass every particle has (unit: kg), or 0 when masses differ (ParticleSet::common_mass). Every
  /// emitter makes rho0 spacing^3; the pair loops then leave out a gather per pair (PCISPH runs them every
  /// iteration).
  Scalar uniform_mass = 0.0;
};

/// SPH densities of the particles [begin, end) (unit: kg/m^3): out[k] for particle begin + k is
/// sum_j m_j W_ij over its fluid neighbors and itself, plus sum_b Psi_b W_ib over its boundary neighbors
/// (Akinci et al. 2012 eq. 6).
/// @param x_mass  N particles: positions (unit: m) and w = mass (unit: kg)
/// Precondition: begin <= end <= N, out holds end - begin values. Compiled per CPU (DRENCH_SIMD_CLONES); call
/// it per chunk (for_each_chunk). The sums run over eight neighbors at a time in a fixed order (the last
/// group padded with lanes left out of the sum), so every copy and every thread count gives the same bits.
void sph_densities(const FluidContext& ctx, const PackedPointArray& x_mass, std::size_t begin,
                   std::size_t end, Scalar* out);

/// Symmetric SPH pressure accelerations of the particles [begin, end) (unit: m/s^2), out[k] for particle
/// begin + k: -sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad W_ij - sum_b Psi_b p_i / rho_i^2 grad W_ib
/// (Akinci et al. 2012 eq. 10), with the gradients of ctx's gradient factors (the current positions).
/// @param x_p_over_rho2  N particles: current positions (unit: m) and w = p / rho^2 (unit: m^5/(kg s^2))
/// The boundary term is the negative gradient of the internal energy that the boundary's density contribution
/// adds, so it conserves energy; pressure mirroring (2 p_i, as some codes use) made a closed tank gain
/// kinetic energy without bound, and a hydrostatic extrapolation of p_b (Adami et al. 2012) drove corner
/// particles up at 1 m/s with PCISPH's noisy pressures (both tried and rejected; test_dam_break bounds the
/// energy). Compiled as sph_densities; the sums run over four neighbors at a time in a fixed order, then the
/// last (count mod 4) one by one.
void pressure_accelerations(const FluidContext& ctx, const PackedPointArray& x_p_over_rho2, std::size_t begin,
                            std::size_t end, Vec3* out);

/// sph_densities in single precision, for PCISPH's iterations (fluid.pcisph.precision "single"): each sum
/// over neighbors is taken in float, sixteen neighbors at a time, and converted to double; the self term (the
/// particle's mass, as rounded in x_mass, times W(0)) is added in double. Rounding a position to float moves
/// it by up to 2^-24 of its magnitude, so callers give positions relative to an origin near the fluid
/// (PCISPH: its bounding-box centre); for points within 0.06 m of it the result is within 1e-5 of
/// sph_densities' (tests/sph/test_fluid_context.cpp).
/// @param x_mass  N particles: positions relative to the origin (unit: m) and w = mass (unit: kg)
/// @param boundary  ctx.boundary relative to the same origin (x_b in m, Psi_b in kg)
/// Precondition: as sph_densities. Every copy and thread count gives the same bits.
void sph_densities_float(const FluidContext& ctx, const PackedPointFArray& x_mass,
                         const PackedPointFArray& boundary, std::size_t begin, std::size_t end, Scalar* out);

/// pressure_accelerations in single precision, for PCISPH's iterations: the sums over neighbors in float,
/// sixteen at a time, converted to double.
/// @param x_p_over_rho2  N particles: current positions relative to an origin near the fluid (unit: m) and
///                       w = p / rho^2 (unit: m^5/(kg s^2))
/// @param boundary  ctx.boundary relative to the same origin (x_b in m, Psi_b in kg)
/// Precondition: as pressure_accelerations, and ctx.uniform_mass > 0 (one mass for every particle).
void pressure_accelerations_float(const FluidContext& ctx, const PackedPointFArray& x_p_over_rho2,
                                  const PackedPointFArray& boundary, std::size_t begin, std::size_t end,
                                  Vec3* out);

}  // namespace drench
