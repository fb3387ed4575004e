#include <drench/sph/pressure/pressure_pbf.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <drench/common/parallel.hpp>
#include <drench/sph/float_lanes.hpp>
#include <drench/sph/packed_lanes.hpp>

namespace drench {
namespace {

/// Calls body(js, n, active, count) for the neighbors of particle i in `list`, Group::kGroupLanes at a time,
/// as for_each_group (sph/packed_lanes.hpp), with n the list entry of the group's first lane (where the
/// group's gradient factors are kept) and count = (list end - n) > 0, which exceeds kGroupLanes in all but
/// the last group: `active` marks the first min(count, kGroupLanes) lanes. One loop of ceil(neighbors /
/// kGroupLanes) groups, each with its mask, rather than whole groups and then a remainder: the remainder's
/// two tests on the neighbor count were mispredicted for most particles (bench_game_frame's branch
/// simulation). Only the groups that would read past the list's last entry read copies of it instead.
template <class Group, class Body>
[[gnu::always_inline]] inline void for_each_entry_group(const NeighborList& list, std::size_t i,
                                                        Body&& body) {
  constexpr std::uint32_t lanes = Group::kGroupLanes;
  const Index* js = list.indices.data();
  const std::size_t size = list.indices.size();
  const std::uint32_t end = list.offsets[i + 1];
  typename Group::Mask active;
  for (std::uint32_t n = list.offsets[i]; n < end; n += lanes) {
    const std::uint32_t count = end - n;
    Group::first(count < lanes ? count : lanes, active);
    if (n + lanes <= size) {
      body(js + n, n, active, count);
    } else {
      Index padded[lanes];
      for (std::uint32_t l = 0; l < lanes; ++l)
        padded[l] = js[n + (l < count ? l : count - 1)];
      body(padded, n, active, count);
    }
  }
}

/// The kernel's value and gradient factor of every lane (CubicSplineKernel::value_and_gradient_factor_lanes),
/// for each eight-lane vector type: a HalvesGroup vector as its two halves.
[[gnu::always_inline]] inline void kernel_lanes(const CubicSplineKernel& k, const Wide& r2, Wide& w,
                                                Wide& f) {
  k.value_and_gradient_factor_lanes(r2, w, f);
}
[[gnu::always_inline]] inline void kernel_lanes(const CubicSplineKernel& k, const Halves& r2, Halves& w,
                                                Halves& f) {
  k.value_and_gradient_factor_lanes(r2.lo, w.lo, f.lo);
  k.value_and_gradient_factor_lanes(r2.hi, w.hi, f.hi);
}

/// Stores the lanes of f at out[0 .. kAll) when `whole`, else its first min(count, kAll) lanes only. The
/// lanes past i's neighbors are other particles' entries: a later particle of the same chunk overwrites
/// them with its own factors, but a next chunk's may be written by another thread at the same time, so
/// whole = (the group ends within the chunk's entries). Whole stores spare the lane-by-lane loop whose
/// exit was mispredicted for most particles (bench_game_frame's branch simulation). V is a whole vector of
/// T (Wide, Floats16); the LanePair overload stores per half, so that GCC keeps the halves in registers.
template <class V, class T>
[[gnu::always_inline]] inline void store_lanes(const V& f, bool whole, std::uint32_t count, T* out) {
  constexpr std::uint32_t kAll = sizeof(V) / sizeof(T);
  if (whole) {
    std::memcpy(out, &f, sizeof(V));
    return;
  }
  for (std::uint32_t l = 0; l < count && l < kAll; ++l)
    out[l] = f[l];
}
template <class V, class T>
[[gnu::always_inline]] inline void store_lanes(const LanePair<V>& f, bool whole, std::uint32_t count,
                                               T* out) {
  constexpr std::uint32_t kHalf = sizeof(V) / sizeof(T);
  if (whole) {
    std::memcpy(out, &f.lo, sizeof(V));
    std::memcpy(out + kHalf, &f.hi, sizeof(V));
    return;
  }
  for (std::uint32_t l = 0; l < count && l < 2 * kHalf; ++l)
    out[l] = l < kHalf ? f.lo[l] : f.hi[l - kHalf];
}

/// The eight factors at `factors`, as load_lanes' counterpart of store_lanes.
[[gnu::always_inline]] inline void load_lanes(const Scalar* factors, Wide& f) {
  std::memcpy(&f, factors, sizeof(Wide));
}
[[gnu::always_inline]] inline void load_lanes(const Scalar* factors, Halves& f) {
  std::memcpy(&f.lo, factors, sizeof(Lanes));
  std::memcpy(&f.hi, factors + kLanes, sizeof(Lanes));
}

/// Gradient factors of the padding past the last list entry: pbf_moves reads whole groups of them in place.
constexpr std::size_t kFactorPadding = 16;

/// For the particles [begin, end) at the positions of `x_mass` (w = mass), in one pass over their neighbors:
/// the density rho_i into `densities` (unit: kg/m^3), the same bits as sph_densities; sum_k |grad_k C_i|^2
/// of eq. 11 (unit: 1/m^2) into `denominators`; when `scorr_moves` is given, the artificial pressure's move
/// sum_j (m_j / rho0) s_corr_ij grad W_ij (eq. 13-14, unit: m) into it, with s_corr = -scorr_scale (W /
/// W(dq))^n; and each pair's kernel gradient factor (unit: 1/m^5) at its list entry in `fluid_factors` and
/// `boundary_factors`, for pbf_moves at the same positions, writing no entry of another chunk's particles
/// (store_lanes). One pass: the density, the gradients and the move of an iteration read the same neighbors
/// at the same positions, and the three passes that each took their own square roots and gradients were a
/// quarter of the game-like level's frame (issue 41). Compiled per CPU as the other pair loops
/// (sph/packed_lanes.hpp), eight neighbors at a time in a fixed order.
DRENCH_SIMD_CLONES void pbf_constraint(const FluidContext& ctx, const PackedPointArray& x_mass,
                                       Scalar inv_rho0, Scalar scorr_scale, Scalar inv_w_dq, int scorr_n,
                                       std::size_t begin, std::size_t end, Scalar* densities,
                                       Scalar* denominators, Vec3* scorr_moves, Scalar* fluid_factors,
                                       Scalar* boundary_factors) {
  const CubicSplineKernel& kernel = ctx.kernel;
  const Scalar self = kernel.value(0.0);
  // The first entries of the next chunk's particles (store_lanes).
  const std::uint32_t fluid_limit = ctx.fluid_neighbors.offsets[end];
  const std::uint32_t boundary_limit = ctx.boundary_neighbors.offsets[end];
  // The artificial pressure's sums exist only in the loop that takes them: eight more accumulators in every
  // iteration's loop made GCC spill the others.
  const auto rows = [&](auto lanes, auto with_scorr) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    using V = typename Group::Vec;
    constexpr bool kScorr = decltype(with_scorr)::value;
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPoint& xi = x_mass[i];
      V rho = {}, gx = {}, gy = {}, gz = {}, squares = {}, sx = {}, sy = {}, sz = {};
      for_each_entry_group<Group>(
          ctx.fluid_neighbors, i,
          [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t count)
              __attribute__((always_inline)) {
                typename Group::Points p;
                Group::load(x_mass.data(), group, p);
                const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
                const V r2 = dx * dx + dy * dy + dz * dz;
                V w, f;
                kernel_lanes(kernel, r2, w, f);
                store_lanes(f, n + Group::kGroupLanes <= fluid_limit, count, fluid_factors + n);
                V term, c;
                Group::select(active, p.w * w, term);
                rho += term;
                Group::select(active, inv_rho0 * (p.w * f), c);
                gx += c * dx;
                gy += c * dy;
                gz += c * dz;
                squares += (c * c) * r2;
                if constexpr (kScorr) {
                  const V ratio = inv_w_dq * w;
                  V power = ratio;
                  for (int k = 1; k < scorr_n; ++k)
                    power = power * ratio;
                  const V t = c * power;
                  sx += t * dx;
                  sy += t * dy;
                  sz += t * dz;
                }
              });
      V boundary_rho = {}, bx = {}, by = {}, bz = {};
      for_each_entry_group<Group>(
          ctx.boundary_neighbors, i,
          [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t count)
              __attribute__((always_inline)) {
                typename Group::Points p;
                Group::load(ctx.boundary.data(), group, p);
                const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
                const V r2 = dx * dx + dy * dy + dz * dz;
                V w, f;
                kernel_lanes(kernel, r2, w, f);
                store_lanes(f, n + Group::kGroupLanes <= boundary_limit, count, boundary_factors + n);
                V term, c;
                Group::select(active, p.w * w, term);
                boundary_rho += term;
                // gradient_sum's term with alpha 0 and scale 1 / rho0: the same bits as before the fusion.
                Group::select(active, inv_rho0 * ((0.0 + p.w) * f), c);
                bx += c * dx;
                by += c * dy;
                bz += c * dz;
              });
      densities[i - begin] = Group::sum(rho) + Group::sum(boundary_rho) + xi.w * self;
      const Vec3 gradient = Vec3(Group::sum(gx), Group::sum(gy), Group::sum(gz)) +
                            Vec3(Group::sum(bx), Group::sum(by), Group::sum(bz));
      denominators[i - begin] = Group::sum(squares) + gradient.squaredNorm();
      if (scorr_moves)
        scorr_moves[i - begin] = -scorr_scale * Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
    }
  };
  with_group_of_copy<HalvesGroup, WideGroup>([&](auto lanes) __attribute__((always_inline)) {
    if (scorr_moves != nullptr && scorr_scale > 0.0) {
      rows(lanes, std::true_type{});
    } else {
      rows(lanes, std::false_type{});
    }
  });
}

/// sum over the neighbors j of i in `list` of scale (alpha + w_j) f_ij (x_i - x_j), as gradient_sum
/// (sph/packed_lanes.hpp) with the gradient factors f kept by pbf_constraint at the same positions (one per
/// list entry, kFactorPadding more readable past the last): the same bits, without a square root and a
/// division per pair.
template <class Group>
[[gnu::always_inline]] inline Vec3 kept_gradient_sum(const NeighborList& list, std::size_t i,
                                                     const PackedPoint& xi, const PackedPoint* sources,
                                                     const Scalar* factors, Scalar alpha, Scalar scale) {
  typename Group::Vec sx = {}, sy = {}, sz = {};
  for_each_entry_group<Group>(
      list, i,
      [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(sources, group, p);
            typename Group::Vec f, s;
            load_lanes(factors + n, f);
            Group::select(active, scale * ((alpha + p.w) * f), s);
            sx += s * (xi.x - p.x);
            sy += s * (xi.y - p.y);
            sz += s * (xi.z - p.z);
          });
  return Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
}

/// True when every neighbor j of i in `list` has w_j = 0 (lambda_j = 0: not compressed). With w_i = 0 too,
/// every term of i's move is a zero, and their sum is +0 (the sums start at +0, and +0 + -0 = +0): the move
/// is known without the sum. Spray and the free surface are not compressed, and their moves were most of the
/// game-like level's move pass (issue 41).
template <class Points>
[[gnu::always_inline]] inline bool at_rest(const NeighborList& list, std::size_t i, const Points& x_w) {
  for (const Index* j = list.begin(i); j != list.end(i); ++j)
    if (x_w[*j].w != 0.0) return false;
  return true;
}

/// dp_i of eq. 12 for the particles [begin, end): -sum_j m_j (w_i + w_j) grad W_ij - w_i sum_b Psi_b
/// grad W_ib, with w = -lambda / rho0 in `x_w` and the gradient factors pbf_constraint kept at its positions.
/// Compiled per CPU as pbf_constraint, eight neighbors at a time in a fixed order.
/// @param mass  every particle's mass (unit: kg), > 0 (FluidContext::uniform_mass)
DRENCH_SIMD_CLONES void pbf_moves(const FluidContext& ctx, const PackedPointArray& x_w, Scalar mass,
                                  const Scalar* fluid_factors, const Scalar* boundary_factors,
                                  std::size_t begin, std::size_t end, Vec3* out) {
  with_group_of_copy<HalvesGroup, WideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPoint& pi = x_w[i];
      if (pi.w == 0.0 && at_rest(ctx.fluid_neighbors, i, x_w)) {
        out[i - begin] = -Vec3::Zero();  // the sum's bits: +0 in every lane, negated
        continue;
      }
      Vec3 move =
          -kept_gradient_sum<Group>(ctx.fluid_neighbors, i, pi, x_w.data(), fluid_factors, pi.w, mass);
      if (pi.w != 0.0)
        move -= kept_gradient_sum<Group>(ctx.boundary_neighbors, i, pi, ctx.boundary.data(), boundary_factors,
                                         0.0, pi.w);
      out[i - begin] = move;
    }
  });
}

/// The cubic spline kernel's value w (unit: 1/m^3) and gradient factor f (unit: 1/m^5) of every lane of r2
/// in single precision: CubicSplineKernel::value_and_gradient_factor_lanes' polynomial on FloatKernel's
/// constants, `gradient_scale` = 3 sigma / (4 h) (unit: 1/m^4). V is Floats8 or Floats16.
template <class V>
[[gnu::always_inline]] inline void float_kernel_lanes(const FloatKernel& k, float gradient_scale, const V& r2,
                                                      V& w, V& f) {
  V r, a, b;
  float_kernel_terms(k, r2, r, a, b);
  w = k.quarter_sigma * (a * a * a - 4.0f * b * b * b);
  const auto apart = r2 > 0.0f;
  const V g = gradient_scale * (4.0f * b * b - a * a) / (apart ? r : V{} + 1.0f);
  f = apart ? g : V{};
}
[[gnu::always_inline]] inline void float_kernel_lanes(const FloatKernel& k, float gradient_scale,
                                                      const FloatHalves& r2, FloatHalves& w, FloatHalves& f) {
  float_kernel_lanes(k, gradient_scale, r2.lo, w.lo, f.lo);
  float_kernel_lanes(k, gradient_scale, r2.hi, w.hi, f.hi);
}

/// acc |= in each lane of `active`, the bit (j >> shift) of the index j the lane holds (a bit per block of
/// 2^shift particles, at most 32 blocks); the indices are read from `group`, as many as the mask has lanes.
[[gnu::always_inline]] inline void or_blocks(const Index* group, const Ints16& active, unsigned shift,
                                             Ints16& acc) {
  Ints16 j;
  std::memcpy(&j, group, sizeof(j));
  const Ints16 one = Ints16{} + 1;
  acc |= (one << (j >> shift)) & active;
}
[[gnu::always_inline]] inline void or_blocks(const Index* group, const FloatHalvesGroup::Mask& active,
                                             unsigned shift, Ints8& acc) {
  Ints8 lo, hi;
  std::memcpy(&lo, group, sizeof(lo));
  std::memcpy(&hi, group + 8, sizeof(hi));
  const Ints8 one = Ints8{} + 1;
  acc |= ((one << (lo >> shift)) & active.lo) | ((one << (hi >> shift)) & active.hi);
}

/// The lanes of or_blocks' sum or'ed together.
template <class A>
[[gnu::always_inline]] inline std::uint32_t blocks_of(const A& acc) {
  std::uint64_t words[sizeof(A) / sizeof(std::uint64_t)];
  std::memcpy(words, &acc, sizeof(A));
  std::uint64_t any = 0;
  for (const std::uint64_t w : words)
    any |= w;
  return static_cast<std::uint32_t>(any | (any >> 32));
}

/// pbf_constraint in single precision (PbfSettings::precision): the same outputs, with the sums over
/// neighbors taken in float, sixteen neighbors at a time (sph/float_lanes.hpp), over `x_mass` and `boundary`
/// relative to an origin near the fluid, and converted to double. Kept per list entry, in float, is the
/// gradient factor times the neighbor's mass m_j f_ij (Psi_b f_ib for a boundary point; unit: kg/m^5), so
/// that the move pass needs no mass and serves particles of differing masses: wetting leaves a partly
/// absorbed particle lighter, and the game-like level's masses differ in most frames (issue 41). The self
/// term of the density is added in double, as sph_densities_float's. When `neighbor_blocks` is given, each
/// particle's blocks of fluid neighbors (or_blocks, of 2^block_shift particles) into it, for pbf_moves_float;
/// it must be given when `scorr_moves` is (std::logic_error otherwise). Every copy and thread count gives the
/// same bits.
DRENCH_SIMD_CLONES void pbf_constraint_float(const FluidContext& ctx, const PackedPointFArray& x_mass,
                                             const PackedPointFArray& boundary, Scalar inv_rho0,
                                             Scalar scorr_scale, Scalar inv_w_dq, int scorr_n,
                                             std::size_t begin, std::size_t end, Scalar* densities,
                                             Scalar* denominators, Vec3* scorr_moves, float* fluid_factors,
                                             float* boundary_factors, unsigned block_shift,
                                             std::uint32_t* neighbor_blocks) {
  const FloatKernel kernel(ctx.kernel);
  const float gradient_scale =
      static_cast<float>(3.0 * (ctx.kernel.value(0.0) / 4.0) / ctx.kernel.smoothing_length());
  const Scalar self = ctx.kernel.value(0.0);
  const float inv_rho0_f = static_cast<float>(inv_rho0);
  const float inv_w_dq_f = static_cast<float>(inv_w_dq);
  const PackedPointF* xs = x_mass.data();
  const PackedPointF* bs = boundary.data();
  // The first entries of the next chunk's particles (store_lanes).
  const std::uint32_t fluid_limit = ctx.fluid_neighbors.offsets[end];
  const std::uint32_t boundary_limit = ctx.boundary_neighbors.offsets[end];
  const auto rows = [&](auto lanes, auto with_scorr, auto with_blocks) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    using V = typename Group::Vec;
    using Blocks = std::conditional_t<std::is_same_v<typename Group::Mask, Ints16>, Ints16, Ints8>;
    constexpr bool kScorr = decltype(with_scorr)::value;
    constexpr bool kBlocks = decltype(with_blocks)::value;
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPointF& xi = xs[i];
      V rho = {}, gx = {}, gy = {}, gz = {}, squares = {}, sx = {}, sy = {}, sz = {};
      Blocks blocks = {};
      for_each_entry_group<Group>(
          ctx.fluid_neighbors, i,
          [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t count)
              __attribute__((always_inline)) {
                typename Group::Points p;
                Group::load(xs, group, p);
                const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
                const V r2 = dx * dx + dy * dy + dz * dz;
                V w, f;
                float_kernel_lanes(kernel, gradient_scale, r2, w, f);
                const V mass_f = p.w * f;
                store_lanes(mass_f, n + Group::kGroupLanes <= fluid_limit, count, fluid_factors + n);
                V term, c;
                Group::select(active, p.w * w, term);
                rho += term;
                Group::select(active, inv_rho0_f * mass_f, c);
                gx += c * dx;
                gy += c * dy;
                gz += c * dz;
                squares += (c * c) * r2;
                if constexpr (kScorr) {
                  const V ratio = inv_w_dq_f * w;
                  V power = ratio;
                  for (int k = 1; k < scorr_n; ++k)
                    power = power * ratio;
                  const V t = c * power;
                  sx += t * dx;
                  sy += t * dy;
                  sz += t * dz;
                }
                if constexpr (kBlocks) or_blocks(group, active, block_shift, blocks);
              });
      if constexpr (kBlocks) neighbor_blocks[i] = blocks_of(blocks);
      V boundary_rho = {}, bx = {}, by = {}, bz = {};
      for_each_entry_group<Group>(
          ctx.boundary_neighbors, i,
          [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t count)
              __attribute__((always_inline)) {
                typename Group::Points p;
                Group::load(bs, group, p);
                const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
                const V r2 = dx * dx + dy * dy + dz * dz;
                V w, f;
                float_kernel_lanes(kernel, gradient_scale, r2, w, f);
                const V mass_f = p.w * f;
                store_lanes(mass_f, n + Group::kGroupLanes <= boundary_limit, count, boundary_factors + n);
                V term, c;
                Group::select(active, p.w * w, term);
                boundary_rho += term;
                Group::select(active, inv_rho0_f * mass_f, c);
                bx += c * dx;
                by += c * dy;
                bz += c * dz;
              });
      densities[i - begin] = Scalar{Group::sum(rho)} + Scalar{Group::sum(boundary_rho)} + Scalar{xi.w} * self;
      const Vec3 gradient = Vec3(Group::sum(gx), Group::sum(gy), Group::sum(gz)) +
                            Vec3(Group::sum(bx), Group::sum(by), Group::sum(bz));
      denominators[i - begin] = Scalar{Group::sum(squares)} + gradient.squaredNorm();
      if (scorr_moves)
        scorr_moves[i - begin] = -scorr_scale * Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
    }
  };
  // Three loops, not four: the artificial pressure and the blocks both belong to a sub-step's first
  // iteration.
  const bool scorr = scorr_moves != nullptr && scorr_scale > 0.0;
  if (scorr && neighbor_blocks == nullptr) {
    throw std::logic_error(
        "pbf_constraint_float: the artificial pressure's pass records the neighbor blocks");
  }
  with_group_of_copy<FloatHalvesGroup, FloatWideGroup>([&](auto lanes) __attribute__((always_inline)) {
    if (scorr) {
      rows(lanes, std::true_type{}, std::true_type{});
    } else if (neighbor_blocks != nullptr) {
      rows(lanes, std::false_type{}, std::true_type{});
    } else {
      rows(lanes, std::false_type{}, std::false_type{});
    }
  });
}

/// In single precision, over float records and the products g = m_j f_ij pbf_constraint_float kept: sum
/// over the neighbors j of i in `list` of (alpha + w_j) g_ij (x_i - x_j) (kWeighted), or of g_ij (x_i - x_j)
/// (not kWeighted: the boundary's, whose w_i is a factor of the whole sum); converted to double.
template <class Group, bool kWeighted>
[[gnu::always_inline]] inline Vec3 float_kept_gradient_sum(const NeighborList& list, std::size_t i,
                                                           const PackedPointF& xi,
                                                           const PackedPointF* sources, const float* factors,
                                                           float alpha) {
  typename Group::Vec sx = {}, sy = {}, sz = {};
  for_each_entry_group<Group>(
      list, i,
      [&](const Index* group, std::uint32_t n, const typename Group::Mask& active, std::uint32_t)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(sources, group, p);
            typename Group::Vec g, s;
            Group::load_factors(factors + n, g);
            if constexpr (kWeighted) {
              Group::select(active, (alpha + p.w) * g, s);
            } else {
              Group::select(active, g, s);
            }
            sx += s * (xi.x - p.x);
            sy += s * (xi.y - p.y);
            sz += s * (xi.z - p.z);
          });
  return Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
}

/// pbf_moves in single precision, over `x_w` and `boundary` relative to the origin of pbf_constraint_float,
/// with the products m_j f_ij it kept: any particle masses. A particle none of whose blocks of fluid
/// neighbors (`neighbor_blocks`, pbf_constraint_float) is among `moving_blocks`, the blocks holding a
/// particle with w != 0, is at rest (at_rest) without a look at its neighbors: the look's loop, whose exit
/// was mispredicted at almost every particle, was most of the game-like level's move pass, where a few
/// particles are compressed at a time (bench_game_frame). Every copy and thread count gives the same bits.
DRENCH_SIMD_CLONES void pbf_moves_float(const FluidContext& ctx, const PackedPointFArray& x_w,
                                        const PackedPointFArray& boundary, const float* fluid_factors,
                                        const float* boundary_factors, const std::uint32_t* neighbor_blocks,
                                        std::uint32_t moving_blocks, std::size_t begin, std::size_t end,
                                        Vec3* out) {
  with_group_of_copy<FloatHalvesGroup, FloatWideGroup>([&](auto lanes) __attribute__((always_inline)) {
    using Group = decltype(lanes);
    for (std::size_t i = begin; i < end; ++i) {
      const PackedPointF& pi = x_w[i];
      if (pi.w == 0.0f &&
          ((neighbor_blocks[i] & moving_blocks) == 0 || at_rest(ctx.fluid_neighbors, i, x_w))) {
        out[i - begin] = -Vec3::Zero();
        continue;
      }
      Vec3 move =
          -float_kept_gradient_sum<Group, true>(ctx.fluid_neighbors, i, pi, x_w.data(), fluid_factors, pi.w);
      if (pi.w != 0.0f)
        move -= Scalar{pi.w} * float_kept_gradient_sum<Group, false>(ctx.boundary_neighbors, i, pi,
                                                                     boundary.data(), boundary_factors, 0.0f);
      out[i - begin] = move;
    }
  });
}

}  // namespace

PressurePbf::PressurePbf(const FluidSettings& settings)
    : m_settings(settings.pbf), m_rest_density(settings.rest_density) {
  const Scalar s = settings.particle_spacing;
  const CubicSplineKernel kernel(s);
  // sum_k |grad_k C|^2 of a particle in a filled lattice: (m / rho0)^2 = s^6 times sum_j |grad W_ij|^2 (the
  // neighbors' part; the particle's own, |sum_j grad W_ij|^2, vanishes by symmetry).
  Scalar sum_squared = 0.0;
  for (int k = -2; k <= 2; ++k) {
    for (int j = -2; j <= 2; ++j) {
      for (int i = -2; i <= 2; ++i)
        sum_squared += kernel.gradient(-s * Vec3(i, j, k)).squaredNorm();
    }
  }
  const Scalar lattice = std::pow(s, 6) * sum_squared;
  m_epsilon = m_settings.relaxation * lattice;
  // As DFSPH's denominator (pressure_dfsph.cpp): a particle under a tenth of the lattice's sum has lost most
  // of its neighbours or sits where their gradients cancel (caught in a moving body's shell, or between a
  // body and the cloth); dividing by that tenth keeps its move bounded, where bench_game_frame's level threw
  // particles at up to 111 m/s (CaughtParticle.DoesNotThrowItsNeighbour).
  m_min_denominator = 0.1 * lattice;
  m_scorr_scale = m_settings.scorr_k / lattice;
  m_inv_w_dq = 1.0 / kernel.value(m_settings.scorr_dq * kernel.support_radius());
}

PressureStats PressurePbf::project(const FluidContext& ctx, Scalar dt, std::size_t first_moving) {
  ParticleSet& particles = ctx.particles;
  const std::size_t n = particles.size();
  const Scalar rho0 = ctx.rest_density;
  const Scalar inv_rho0 = 1.0 / rho0;
  const NeighborList& fn = ctx.fluid_neighbors;
  const NeighborList& bn = ctx.boundary_neighbors;
  m_last_dt = dt;
  Vec3 origin;
  // Any masses: the float passes carry each particle's (pbf_constraint_float).
  const bool single = single_precision_origin(ctx, m_settings.precision, origin, false);
  m_points.resize(n);
  m_lambda_points.resize(single ? 0 : n);
  m_points_float.resize(single ? n : 0);
  m_lambda_points_float.resize(single ? n : 0);
  m_boundary_float.resize(single ? ctx.boundary.size() : 0);
  m_denominator.resize(n);
  m_scorr_moves.resize(n);
  m_lambda_sum.assign(n, 0.0);
  m_moves.resize(n);
  m_chunk_errors.resize((n + kParticleChunk - 1) / kParticleChunk);
  m_neighbor_blocks.resize(single ? n : 0);
  // The pairs of particles and moving boundary points: few (the water touching a body), found once, since
  // the lists hold for the whole projection.
  m_boundary_pushes.clear();
  if (first_moving < ctx.boundary.size()) {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::uint32_t k = bn.offsets[i]; k < bn.offsets[i + 1]; ++k) {
        if (bn.indices[k] >= first_moving)
          m_boundary_pushes.push_back({static_cast<Index>(i), static_cast<Index>(k), Vec3::Zero()});
      }
    }
  }
  PressureStats stats;
  if (n == 0) return stats;
  // Blocks of 2^block_shift particles, at most 32 (pbf_moves_float).
  unsigned block_shift = 0;
  while (((n - 1) >> block_shift) >= 32)
    ++block_shift;
  // The artificial pressure as the force it stands for (PbfSettings::scorr_substep): below the sub-step its
  // k holds at, its move shrinks as dt^2, so that it gives the same acceleration at every sub-step.
  Scalar scorr_scale = m_scorr_scale;
  if (m_settings.scorr_substep && dt < *m_settings.scorr_substep) {
    const Scalar ratio = dt / *m_settings.scorr_substep;
    scorr_scale *= ratio * ratio;
  }
  // The denominator of lambda (eq. 11, the constraint's gradients of eq. 8; boundary points have zero
  // inverse mass, so they enter only the particle's own gradient) at each iteration's positions, as the
  // densities and the moves: kept from the prediction, a particle whose gradients cancelled there (caught in
  // a moving body's shell) was divided by that small sum while its moves took the large gradient of the
  // positions it had reached, and left the shell at 39 m/s (CaughtParticle.DoesNotThrowItsNeighbour).
  // The artificial pressure's move (eq. 13-14), a nudge, once per sub-step at the prediction.
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      m_points[i] = packed(particles.positions[i], particles.masses[i]);
      if (single) {
        m_points_float[i] = packed_float(particles.positions[i] - origin, particles.masses[i]);
        m_lambda_points_float[i] = packed_float(particles.positions[i] - origin, 0.0);
      } else {
        m_lambda_points[i] = packed(particles.positions[i], 0.0);
      }
    }
  });
  if (single) {
    parallel_for(ctx.boundary.size(), kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t b = begin; b < end; ++b) {
        const PackedPoint& p = ctx.boundary[b];
        m_boundary_float[b] = packed_float(Vec3(p.x, p.y, p.z) - origin, p.w);
      }
    });
  }
  m_fluid_factors.resize(single ? 0 : fn.indices.size() + kFactorPadding);
  m_boundary_factors.resize(single ? 0 : bn.indices.size() + kFactorPadding);
  m_fluid_factors_float.resize(single ? fn.indices.size() + kFactorPadding : 0);
  m_boundary_factors_float.resize(single ? bn.indices.size() + kFactorPadding : 0);
  const Scalar max_correction = m_settings.max_compression_per_iteration
                                    ? *m_settings.max_compression_per_iteration
                                    : std::numeric_limits<Scalar>::infinity();
  for (int iteration = 0; iteration < m_settings.iterations; ++iteration) {
    // rho_i, the denominator and lambda_i at the current prediction (eq. 11), only for compression.
    for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
      Vec3* scorr_moves = iteration == 0 ? &m_scorr_moves[begin] : nullptr;
      if (single) {
        pbf_constraint_float(ctx, m_points_float, m_boundary_float, inv_rho0, scorr_scale, m_inv_w_dq,
                             m_settings.scorr_n, begin, end, &particles.densities[begin],
                             &m_denominator[begin], scorr_moves, m_fluid_factors_float.data(),
                             m_boundary_factors_float.data(), block_shift,
                             iteration == 0 ? m_neighbor_blocks.data() : nullptr);
      } else {
        pbf_constraint(ctx, m_points, inv_rho0, scorr_scale, m_inv_w_dq, m_settings.scorr_n, begin, end,
                       &particles.densities[begin], &m_denominator[begin], scorr_moves,
                       m_fluid_factors.data(), m_boundary_factors.data());
      }
      ChunkErrors errors;
      for (std::size_t i = begin; i < end; ++i) {
        m_denominator[i] = std::max(m_denominator[i] + m_epsilon, m_min_denominator);
        const Scalar violation = std::max(particles.densities[i] * inv_rho0 - 1.0, 0.0);
        const Scalar lambda = -std::min(violation, max_correction) / m_denominator[i];
        m_lambda_sum[i] += lambda;
        // dp_i = -sum_j m_j (w_i + w_j) grad W_ij - w_i sum_b Psi_b grad W_ib with w = -lambda / rho0.
        bool moving;
        if (single) {
          const float w = static_cast<float>(-lambda * inv_rho0);
          m_lambda_points_float[i].w = w;
          moving = w != 0.0f;
        } else {
          const Scalar w = -lambda * inv_rho0;
          m_lambda_points[i].w = w;
          moving = w != 0.0;
        }
        errors.moving_blocks |= std::uint32_t{moving} << (i >> block_shift);
        errors.sum += violation;
        errors.max = std::max(errors.max, violation);
      }
      m_chunk_errors[begin / kParticleChunk] = errors;
    });
    // The moving points' share of this iteration's moves, with its lambdas and the gradient factors the
    // constraint pass kept at its positions, as pbf_moves takes them. In particle order, one thread: the same
    // bits for any thread count.
    for (BoundaryPush& pair : m_boundary_pushes) {
      const Index i = pair.particle;
      const PackedPoint& b = ctx.boundary[bn.indices[pair.entry]];
      const PackedPoint& xi = m_points[i];
      // w_i Psi_b f_ib as the move pass reads them: Psi_b f_ib kept per entry in single precision, f_ib in
      // double.
      const Scalar w_factor = single
                                  ? Scalar{m_lambda_points_float[i].w} * m_boundary_factors_float[pair.entry]
                                  : m_lambda_points[i].w * b.w * m_boundary_factors[pair.entry];
      if (w_factor == 0.0) continue;
      pair.push += (particles.masses[i] / dt * w_factor) * Vec3(xi.x - b.x, xi.y - b.y, xi.z - b.z);
    }
    // dp_i (eq. 12) with the kernel's gradient at the current positions: factors frozen at the prediction,
    // as PCISPH's pressure loop uses them, made the hydrostatic tank blow up within 0.1 s at every sub-step
    // count and relaxation tried, since PBF's iterations move particles by a large part of a spacing.
    // With no particle compressed (w = 0 everywhere), every particle is at rest (at_rest), its move known
    // without a pass, with the bits each pass gives it: in a third of the game-like level's iterations
    // (bench_game_frame).
    std::uint32_t moving_blocks = 0;
    for (const ChunkErrors& errors : m_chunk_errors)
      moving_blocks |= errors.moving_blocks;
    if (moving_blocks == 0) {
      const bool negated = single || ctx.uniform_mass > 0.0;
      std::fill(m_moves.begin(), m_moves.end(), negated ? Vec3(-Vec3::Zero()) : Vec3(Vec3::Zero()));
    }
    for_each_chunk(moving_blocks == 0 ? 0 : n, [&](std::size_t begin, std::size_t end) {
      if (single) {
        pbf_moves_float(ctx, m_lambda_points_float, m_boundary_float, m_fluid_factors_float.data(),
                        m_boundary_factors_float.data(), m_neighbor_blocks.data(), moving_blocks, begin, end,
                        &m_moves[begin]);
        return;
      }
      if (ctx.uniform_mass > 0.0) {
        pbf_moves(ctx, m_lambda_points, ctx.uniform_mass, m_fluid_factors.data(), m_boundary_factors.data(),
                  begin, end, &m_moves[begin]);
        return;
      }
      for (std::size_t i = begin; i < end; ++i) {
        const PackedPoint& pi = m_lambda_points[i];
        if (pi.w == 0.0 && at_rest(fn, i, m_lambda_points)) {
          m_moves[i] = Vec3::Zero();  // the loop's bits: +0 minus zeros stays +0
          continue;
        }
        const Vec3 xi(pi.x, pi.y, pi.z);
        Vec3 move = Vec3::Zero();
        // The gradient factors pbf_constraint kept at these positions: the same bits as taking them here.
        for (std::uint32_t k = fn.offsets[i]; k < fn.offsets[i + 1]; ++k) {
          const Index j = fn.indices[k];
          const PackedPoint& pj = m_lambda_points[j];
          const Vec3 d = xi - Vec3(pj.x, pj.y, pj.z);
          move -= (m_points[j].w * (pi.w + pj.w) * m_fluid_factors[k]) * d;
        }
        if (pi.w != 0.0) {
          for (std::uint32_t k = bn.offsets[i]; k < bn.offsets[i + 1]; ++k) {
            const PackedPoint& pb = ctx.boundary[bn.indices[k]];
            const Vec3 d = xi - Vec3(pb.x, pb.y, pb.z);
            move -= (pi.w * pb.w * m_boundary_factors[k]) * d;
          }
        }
        m_moves[i] = move;
      }
    });
    // Jacobi: every move from the same prediction, then applied.
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        const Vec3 move = m_moves[i] + m_scorr_moves[i];
        PackedPoint& p = m_points[i];
        p.x += move.x();
        p.y += move.y();
        p.z += move.z();
        if (single) {
          // Rounded from the double prediction, so that the float records do not gather roundings.
          const PackedPointF x = packed_float(Vec3(p.x, p.y, p.z) - origin, p.w);
          m_points_float[i] = x;
          m_lambda_points_float[i] = {x.x, x.y, x.z, m_lambda_points_float[i].w};
        } else {
          PackedPoint& q = m_lambda_points[i];
          q.x += move.x();
          q.y += move.y();
          q.z += move.z();
        }
      }
    });
    ++stats.iterations;
  }
  ChunkErrors total;
  for (const ChunkErrors& errors : m_chunk_errors) {
    total.sum += errors.sum;
    total.max = std::max(total.max, errors.max);
  }
  stats.average_density_error = total.sum / static_cast<Scalar>(n);
  stats.max_density_error = total.max;
  parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      particles.positions[i] = Vec3(m_points[i].x, m_points[i].y, m_points[i].z);
  });
  return stats;
}

PressureStats PressurePbf::solve(const FluidContext& ctx, const Vec3Array& velocities_adv, Scalar dt,
                                 Vec3Array& accelerations) {
  Vec3Array& x = ctx.particles.positions;
  const Vec3Array start = x;
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] += dt * velocities_adv[i];
  const PressureStats stats = project(ctx, dt, ctx.boundary.size());
  accelerations.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    accelerations[i] = (x[i] - start[i] - dt * velocities_adv[i]) / (dt * dt);
  x = start;
  return stats;
}

void PressurePbf::boundary_pressure_factors(const ParticleSet& particles, ScalarArray& out) const {
  out.assign(particles.size(), 0.0);
  if (m_lambda_sum.size() != out.size() || m_last_dt <= 0.0) return;
  const Scalar scale = -1.0 / (m_rest_density * m_last_dt * m_last_dt);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = scale * m_lambda_sum[i];
}

}  // namespace drench
