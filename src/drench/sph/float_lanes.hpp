#pragma once
/// Sixteen neighbors at a time in single precision: the vector types and loops of PCISPH's and DFSPH's
/// iterations (sph_densities_float and pressure_accelerations_float, sph/fluid_context.cpp;
/// density_change_float, sph/pressure/pressure_dfsph.cpp), over PackedPointF records.
/// Internal to those DRENCH_SIMD_CLONES functions and their tests, as sph/packed_lanes.hpp (whose notes on
/// always_inline apply here too).
///
/// Why single precision: a record is 16 bytes instead of 32, and a vector holds twice the lanes, so the
/// densities pass runs about 1.4 times faster than in double for a largest relative difference of a few
/// 1e-6 (bench_pair_loops densities_float, its counter max_relative_difference; solver-level figures in
/// docs/performance.md). Positions in float carry 2^-24 of their magnitude: 0.24 um at 4 m, 1e-5 of a
/// 25 mm spacing, against PCISPH's tolerance of 5e-4 on the average density.
///
/// A group of sixteen lanes is one of two types with the same lanes, arithmetic and summation order, so the
/// same bits, as the eight-lane groups of packed_lanes.hpp: FloatHalvesGroup, two vectors of eight floats,
/// for the AVX2 copy (a 64-byte vector would go through the stack there), FloatWideGroup, one vector of
/// sixteen, for the others.
#include <cmath>
#include <cstdint>
#include <cstring>

#include <drench/common/parallel.hpp>
#include <drench/sph/fluid_context.hpp>
#include <drench/sph/packed_lanes.hpp>

namespace drench {
namespace {

typedef float Floats4 __attribute__((vector_size(4 * sizeof(float))));
typedef float Floats8 __attribute__((vector_size(8 * sizeof(float))));
typedef float Floats16 __attribute__((vector_size(16 * sizeof(float))));
typedef std::int32_t Ints8 __attribute__((vector_size(8 * sizeof(std::int32_t))));
typedef std::int32_t Ints16 __attribute__((vector_size(16 * sizeof(std::int32_t))));
constexpr std::uint32_t kFloatLanes = 16;

/// The cubic spline kernel (CubicSplineKernel::value's branch-free polynomial) in single precision.
struct FloatKernel {
  float inv_h;          ///< 1 / smoothing length (unit: 1/m)
  float quarter_sigma;  ///< sigma / 4 (unit: 1/m^3)
  explicit FloatKernel(const CubicSplineKernel& k)
      // W(0) = sigma / 4 (2^3 - 4 * 1^3) = sigma: the division by 4 is exact.
      : inv_h(static_cast<float>(1.0 / k.smoothing_length())),
        quarter_sigma(static_cast<float>(k.value(0.0) / 4.0)) {}
};

/// r = sqrt(r2) (unit: m) and the cubic spline's terms a = max(2 - q, 0), b = max(1 - q, 0) at q = r / h,
/// lane by lane: its value and its gradient are polynomials in them. V is Floats8 or Floats16.
template <class V>
[[gnu::always_inline]] inline void float_kernel_terms(const FloatKernel& k, const V& r2, V& r, V& a, V& b) {
  for (std::uint32_t l = 0; l < sizeof(V) / sizeof(float); ++l)
    r[l] = std::sqrt(r2[l]);
  const V q = r * k.inv_h;
  a = 2.0f - q;
  b = 1.0f - q;
  // std::max(a, 0) as written for double: NaN lanes keep a (the comparison is false).
  a = a < 0.0f ? V{} : a;
  b = b < 0.0f ? V{} : b;
}

/// w = W(sqrt(r2)) lane by lane (unit: 1/m^3); V is Floats8 or Floats16. NaN stays NaN, as in double.
template <class V>
[[gnu::always_inline]] inline void float_kernel_values(const FloatKernel& k, const V& r2, V& w) {
  V r, a, b;
  float_kernel_terms(k, r2, r, a, b);
  w = k.quarter_sigma * (a * a * a - 4.0f * b * b * b);
}

/// The records js[0..3] as one vector of sixteen floats: x y z w of the first, then of the second, ...
[[gnu::always_inline]] inline void load_four_records(const PackedPointF* points, const Index* js,
                                                     Floats16& out) {
  Floats4 a, b, c, d;
  std::memcpy(&a, &points[js[0]], sizeof(Floats4));
  std::memcpy(&b, &points[js[1]], sizeof(Floats4));
  std::memcpy(&c, &points[js[2]], sizeof(Floats4));
  std::memcpy(&d, &points[js[3]], sizeof(Floats4));
  const Floats8 ab = __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7);
  const Floats8 cd = __builtin_shufflevector(c, d, 0, 1, 2, 3, 4, 5, 6, 7);
  out = __builtin_shufflevector(ab, cd, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
}

/// x, y, z and w of sixteen packed points as four vectors.
struct SixteenPoints {
  Floats16 x, y, z, w;
};

/// Loads the points js[0..15] and transposes them in registers: lane l holds point js[l].
[[gnu::always_inline]] inline void load_sixteen(const PackedPointF* points, const Index* js,
                                                SixteenPoints& out) {
  Floats16 a, b, c, d;
  load_four_records(points, js, a);
  load_four_records(points, js + 4, b);
  load_four_records(points, js + 8, c);
  load_four_records(points, js + 12, d);
  // x of points 0-7, then y of points 0-7; z and w likewise; then the same for points 8-15.
  const Floats16 ab_xy =
      __builtin_shufflevector(a, b, 0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
  const Floats16 ab_zw =
      __builtin_shufflevector(a, b, 2, 6, 10, 14, 18, 22, 26, 30, 3, 7, 11, 15, 19, 23, 27, 31);
  const Floats16 cd_xy =
      __builtin_shufflevector(c, d, 0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
  const Floats16 cd_zw =
      __builtin_shufflevector(c, d, 2, 6, 10, 14, 18, 22, 26, 30, 3, 7, 11, 15, 19, 23, 27, 31);
  out.x = __builtin_shufflevector(ab_xy, cd_xy, 0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23);
  out.y = __builtin_shufflevector(ab_xy, cd_xy, 8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31);
  out.z = __builtin_shufflevector(ab_zw, cd_zw, 0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23);
  out.w = __builtin_shufflevector(ab_zw, cd_zw, 8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31);
}

/// x, y, z and w of eight packed points as four vectors.
struct EightPointsF {
  Floats8 x, y, z, w;
};

/// Loads the points js[0..7] with eight-float vectors only: lane l holds point js[l]. The same transpose as
/// packed_lanes.hpp's load_eight, kept apart because the two types want different loads: a shared template
/// with load_eight's named loads slowed the float passes of the AVX2 copy, and with this array it halved the
/// speed of the double densities of the AVX-512 copy (bench_pair_loops densities_float/0 and densities/0).
[[gnu::always_inline]] inline void load_eight_float(const PackedPointF* points, const Index* js,
                                                    EightPointsF& out) {
  Floats4 r[8];
  for (int l = 0; l < 8; ++l)
    std::memcpy(&r[l], &points[js[l]], sizeof(Floats4));
  const Floats8 ab = __builtin_shufflevector(r[0], r[1], 0, 1, 2, 3, 4, 5, 6, 7);
  const Floats8 cd = __builtin_shufflevector(r[2], r[3], 0, 1, 2, 3, 4, 5, 6, 7);
  const Floats8 ef = __builtin_shufflevector(r[4], r[5], 0, 1, 2, 3, 4, 5, 6, 7);
  const Floats8 gh = __builtin_shufflevector(r[6], r[7], 0, 1, 2, 3, 4, 5, 6, 7);
  const Floats8 abcd_xy = __builtin_shufflevector(ab, cd, 0, 4, 8, 12, 1, 5, 9, 13);
  const Floats8 abcd_zw = __builtin_shufflevector(ab, cd, 2, 6, 10, 14, 3, 7, 11, 15);
  const Floats8 efgh_xy = __builtin_shufflevector(ef, gh, 0, 4, 8, 12, 1, 5, 9, 13);
  const Floats8 efgh_zw = __builtin_shufflevector(ef, gh, 2, 6, 10, 14, 3, 7, 11, 15);
  out.x = __builtin_shufflevector(abcd_xy, efgh_xy, 0, 1, 2, 3, 8, 9, 10, 11);
  out.y = __builtin_shufflevector(abcd_xy, efgh_xy, 4, 5, 6, 7, 12, 13, 14, 15);
  out.z = __builtin_shufflevector(abcd_zw, efgh_zw, 0, 1, 2, 3, 8, 9, 10, 11);
  out.w = __builtin_shufflevector(abcd_zw, efgh_zw, 4, 5, 6, 7, 12, 13, 14, 15);
}

/// ((s0 + s1) + (s2 + s3)) of the four-lane sum lo + hi of eight lanes.
[[gnu::always_inline]] inline float float_sum_of_eight(const Floats8& v) {
  const Floats4 s = __builtin_shufflevector(v, v, 0, 1, 2, 3) + __builtin_shufflevector(v, v, 4, 5, 6, 7);
  return (s[0] + s[1]) + (s[2] + s[3]);
}

/// What the sixteen-lane float groups share: lane count, kernel, record and sum types (for_each_group,
/// kernel_sum).
struct SixteenFloatLanes {
  static constexpr std::uint32_t kGroupLanes = kFloatLanes;
  using Kernel = FloatKernel;
  using Record = PackedPointF;
  using Sum = float;
};

/// Sixteen lanes as one vector: one AVX-512 register in the x86-64-v4 copy, four SSE registers in the
/// baseline copy.
struct FloatWideGroup : SixteenFloatLanes {
  using Vec = Floats16;
  using Mask = Ints16;
  using Points = SixteenPoints;
  /// out = the first `count` lanes.
  [[gnu::always_inline]] static void first(std::int32_t count, Mask& out) {
    const Ints16 lane = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    out = lane < count;
  }
  [[gnu::always_inline]] static void load(const PackedPointF* points, const Index* js, Points& out) {
    load_sixteen(points, js, out);
  }
  [[gnu::always_inline]] static void load_factors(const float* factors, Vec& out) {
    std::memcpy(&out, factors, sizeof(Vec));
  }
  [[gnu::always_inline]] static void kernel(const FloatKernel& k, const PackedPointF& xi, const Points& p,
                                            Vec& w) {
    const Vec dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
    float_kernel_values(k, dx * dx + dy * dy + dz * dz, w);
  }
  /// out = v in the active lanes, 0 in the others.
  [[gnu::always_inline]] static void select(const Mask& active, const Vec& v, Vec& out) {
    out = active ? v : Vec{};
  }
  /// Lanes 0-7 plus lanes 8-15, then float_sum_of_eight.
  [[gnu::always_inline]] static float sum(const Vec& v) {
    return float_sum_of_eight(__builtin_shufflevector(v, v, 0, 1, 2, 3, 4, 5, 6, 7) +
                              __builtin_shufflevector(v, v, 8, 9, 10, 11, 12, 13, 14, 15));
  }
};

/// Sixteen floats as two vectors of eight (lanes 0-7 and 8-15).
using FloatHalves = LanePair<Floats8>;

/// Sixteen lanes as two vectors of eight floats: two registers in the AVX2 copy.
struct FloatHalvesGroup : SixteenFloatLanes {
  using Vec = FloatHalves;
  struct Mask {
    Ints8 lo, hi;
  };
  struct Points {
    FloatHalves x, y, z, w;
  };
  [[gnu::always_inline]] static void first(std::int32_t count, Mask& out) {
    const Ints8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
    out = {lane < count, lane + 8 < count};
  }
  [[gnu::always_inline]] static void load(const PackedPointF* points, const Index* js, Points& out) {
    EightPointsF a, b;
    load_eight_float(points, js, a);
    load_eight_float(points, js + 8, b);
    out = {{a.x, b.x}, {a.y, b.y}, {a.z, b.z}, {a.w, b.w}};
  }
  [[gnu::always_inline]] static void load_factors(const float* factors, Vec& out) {
    std::memcpy(&out.lo, factors, sizeof(Floats8));
    std::memcpy(&out.hi, factors + 8, sizeof(Floats8));
  }
  [[gnu::always_inline]] static void kernel(const FloatKernel& k, const PackedPointF& xi, const Points& p,
                                            Vec& w) {
    const Floats8 dx_lo = xi.x - p.x.lo, dy_lo = xi.y - p.y.lo, dz_lo = xi.z - p.z.lo;
    const Floats8 dx_hi = xi.x - p.x.hi, dy_hi = xi.y - p.y.hi, dz_hi = xi.z - p.z.hi;
    float_kernel_values(k, dx_lo * dx_lo + dy_lo * dy_lo + dz_lo * dz_lo, w.lo);
    float_kernel_values(k, dx_hi * dx_hi + dy_hi * dy_hi + dz_hi * dz_hi, w.hi);
  }
  [[gnu::always_inline]] static void select(const Mask& active, const Vec& v, Vec& out) {
    out = {active.lo ? v.lo : Floats8{}, active.hi ? v.hi : Floats8{}};
  }
  /// As FloatWideGroup::sum.
  [[gnu::always_inline]] static float sum(const Vec& v) { return float_sum_of_eight(v.lo + v.hi); }
};

/// Subtracts sum_j a (alpha + w_j) f_j (x_i - x_j) over the neighbors j of i in `list` from (sx, sy, sz), in
/// single precision; `factors` are the gradient factors f of the list's entries. The pressure loop's sum:
/// a = m (uniform mass) and alpha = p_i / rho_i^2 for fluid neighbors, a = p_i / rho_i^2 and alpha = 0 for
/// boundary ones (w_j = Psi_b).
template <class Group>
[[gnu::always_inline]] inline void float_subtract_gradient_sum(const PackedPointF& xi, float alpha, float a,
                                                               const PackedPointF* points,
                                                               const NeighborList& list, std::size_t i,
                                                               const float* factors, float& sx, float& sy,
                                                               float& sz) {
  typename Group::Vec ax = {}, ay = {}, az = {};
  for_each_group<Group>(
      list, i, factors,
      [&](const Index* group, const float* fs, const typename Group::Mask& active)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(points, group, p);
            typename Group::Vec f;
            Group::load_factors(fs, f);
            // The products are masked, not the coefficient: the padding lanes hold the next particle's
            // neighbors, and 0 x NaN from one of those would make this particle NaN.
            const typename Group::Vec s = a * (alpha + p.w) * f;
            typename Group::Vec tx, ty, tz;
            Group::select(active, s * (xi.x - p.x), tx);
            Group::select(active, s * (xi.y - p.y), ty);
            Group::select(active, s * (xi.z - p.z), tz);
            ax -= tx;
            ay -= ty;
            az -= tz;
          });
  sx += Group::sum(ax);
  sy += Group::sum(ay);
  sz += Group::sum(az);
}

/// sum_j f_j (v_i - v_j) . (x_i - x_j) over the fluid neighbors j of i in `list` (kBoundary false), or
/// sum_b w_b f_b v_i . (x_i - x_b) over its boundary neighbors (kBoundary true: boundary points at rest,
/// `velocities` not read), in single precision; `factors` are the gradient factors f of the list's entries.
/// DFSPH's rate of density change (density_change_float) without the fluid's uniform mass.
template <class Group, bool kBoundary>
[[gnu::always_inline]] inline float float_density_change_sum(const PackedPointF& xi, const PackedPointF& vi,
                                                             const PackedPointF* points,
                                                             const PackedPointF* velocities,
                                                             const NeighborList& list, std::size_t i,
                                                             const float* factors) {
  typename Group::Vec sum = {};
  for_each_group<Group>(
      list, i, factors,
      [&](const Index* group, const float* fs, const typename Group::Mask& active)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(points, group, p);
            typename Group::Vec f, dot, term;
            Group::load_factors(fs, f);
            if constexpr (kBoundary) {
              dot = vi.x * (xi.x - p.x);
              dot += vi.y * (xi.y - p.y);
              dot += vi.z * (xi.z - p.z);
              f = p.w * f;
            } else {
              typename Group::Points v;
              Group::load(velocities, group, v);
              dot = (vi.x - v.x) * (xi.x - p.x);
              dot += (vi.y - v.y) * (xi.y - p.y);
              dot += (vi.z - v.z) * (xi.z - p.z);
            }
            // Masked after the product, as float_subtract_gradient_sum: a padding lane's NaN must not reach
            // the sum.
            Group::select(active, f * dot, term);
            sum += term;
          });
  return Group::sum(sum);
}

}  // namespace
}  // namespace drench
