#pragma once
/// Four or eight neighbors at a time: the vector types and the loads shared by the SPH pair loops over
/// PackedPoint arrays (sph/fluid_context.cpp, sph/forces/viscosity.cpp) and the grid search's four-lane scan
/// (sph/candidate_scan.hpp). Internal to those files' DRENCH_SIMD_CLONES functions (and their tests, which
/// run both eight-lane group types); everything is in an unnamed namespace and always inlined, so each copy
/// compiles its own. A lambda in such a function must be always_inline as well: out of line it is compiled
/// for the baseline only, which made XSPH about 2.7 times slower (bench_pair_loops xsph).
///
/// The double-precision loops that evaluate the kernel (densities, XSPH) take eight neighbors at a time (the
/// single-precision ones of sph/float_lanes.hpp, sixteen, through the same for_each_group and kernel_sum): a
/// square root of eight lanes costs what one of four does on the AVX-512 copy, which makes the densities
/// pass about 1.3 times faster than at four lanes (bench_pair_loops densities). The pressure loop, a few
/// multiplies per pair, stays at four lanes: at eight it ran slower, in and out of cache (bench_pair_loops
/// pressure_accelerations).
///
/// An eight-lane group is one of two types with the same lanes, arithmetic and summation order, so the same
/// bits: HalvesGroup, two vectors of four doubles, for the AVX2 copy, and WideGroup, one vector of eight, for
/// the others (avx2_copy() tells which copy runs). GCC lowers an eight-double vector on AVX2 through the
/// stack, which made the AVX2 copy of the densities several times slower than the AVX-512 copy; hence the
/// halves there. In the baseline copy (SSE2) the halves were no faster for the densities and slower for
/// XSPH, so it keeps WideGroup (bench_pair_loops densities and xsph, in a build without clones).
#include <cmath>
#include <cstdint>
#include <cstring>

#include <drench/common/parallel.hpp>
#include <drench/sph/fluid_context.hpp>

namespace drench {
namespace {

/// Four doubles as one vector: an AVX2 register (in the AVX-512 copy too), or two SSE2 registers in the
/// baseline copy. GCC's and clang's vector extension, so one source serves every copy of DRENCH_SIMD_CLONES.
typedef Scalar Lanes __attribute__((vector_size(4 * sizeof(Scalar))));
constexpr std::uint32_t kLanes = 4;
/// Four floats: four stored gradient factors (GradientFactorArray), widened to Lanes after the load.
typedef float FloatLanes __attribute__((vector_size(4 * sizeof(float))));

/// x, y, z and w of four packed points as four vectors.
struct FourPoints {
  Lanes x, y, z, w;
};

/// Loads the points js[0..3] and transposes the four records in registers (a 4 x 4 transpose: unpack within
/// 128-bit halves, then exchange halves).
[[gnu::always_inline]] inline void load_four(const PackedPoint* points, const Index* js, FourPoints& out) {
  Lanes a, b, c, d;
  std::memcpy(&a, &points[js[0]], sizeof(Lanes));
  std::memcpy(&b, &points[js[1]], sizeof(Lanes));
  std::memcpy(&c, &points[js[2]], sizeof(Lanes));
  std::memcpy(&d, &points[js[3]], sizeof(Lanes));
  const Lanes ab_xz = __builtin_shufflevector(a, b, 0, 4, 2, 6);  // ax bx az bz
  const Lanes ab_yw = __builtin_shufflevector(a, b, 1, 5, 3, 7);  // ay by aw bw
  const Lanes cd_xz = __builtin_shufflevector(c, d, 0, 4, 2, 6);
  const Lanes cd_yw = __builtin_shufflevector(c, d, 1, 5, 3, 7);
  out.x = __builtin_shufflevector(ab_xz, cd_xz, 0, 1, 4, 5);
  out.z = __builtin_shufflevector(ab_xz, cd_xz, 2, 3, 6, 7);
  out.y = __builtin_shufflevector(ab_yw, cd_yw, 0, 1, 4, 5);
  out.w = __builtin_shufflevector(ab_yw, cd_yw, 2, 3, 6, 7);
}

/// The lanes summed in a fixed order, (a0 + a1) + (a2 + a3), whatever the vector width of the copy.
[[gnu::always_inline]] inline Scalar lane_sum(const Lanes& a) {
  return (a[0] + a[1]) + (a[2] + a[3]);
}

/// Eight doubles: the pair loops' vector in WideGroup. One AVX-512 register in the x86-64-v4 copy, four SSE2
/// registers in the baseline copy (the x86-64-v3 copy uses HalvesGroup instead, see above); the lanes are the
/// same in all, so are the sums.
typedef Scalar Wide __attribute__((vector_size(8 * sizeof(Scalar))));
/// A mask of Wide lanes: all bits set where true.
typedef std::int64_t WideMask __attribute__((vector_size(8 * sizeof(std::int64_t))));
constexpr std::uint32_t kWide = 8;

/// x, y, z and w of eight packed points as four vectors.
struct EightPoints {
  Wide x, y, z, w;
};

/// Loads the points js[0..7] and transposes the eight records in registers: records paired into vectors,
/// then two rounds of two-source permutes.
[[gnu::always_inline]] inline void load_eight(const PackedPoint* points, const Index* js, EightPoints& out) {
  // Named loads, not an array filled in a loop: GCC kept such an array in memory and reloaded it.
  Lanes a, b, c, d, e, f, g, h;
  std::memcpy(&a, &points[js[0]], sizeof(Lanes));
  std::memcpy(&b, &points[js[1]], sizeof(Lanes));
  std::memcpy(&c, &points[js[2]], sizeof(Lanes));
  std::memcpy(&d, &points[js[3]], sizeof(Lanes));
  std::memcpy(&e, &points[js[4]], sizeof(Lanes));
  std::memcpy(&f, &points[js[5]], sizeof(Lanes));
  std::memcpy(&g, &points[js[6]], sizeof(Lanes));
  std::memcpy(&h, &points[js[7]], sizeof(Lanes));
  const Wide ab = __builtin_shufflevector(a, b, 0, 1, 2, 3, 4, 5, 6, 7);
  const Wide cd = __builtin_shufflevector(c, d, 0, 1, 2, 3, 4, 5, 6, 7);
  const Wide ef = __builtin_shufflevector(e, f, 0, 1, 2, 3, 4, 5, 6, 7);
  const Wide gh = __builtin_shufflevector(g, h, 0, 1, 2, 3, 4, 5, 6, 7);
  const Wide abcd_xy = __builtin_shufflevector(ab, cd, 0, 4, 8, 12, 1, 5, 9, 13);
  const Wide abcd_zw = __builtin_shufflevector(ab, cd, 2, 6, 10, 14, 3, 7, 11, 15);
  const Wide efgh_xy = __builtin_shufflevector(ef, gh, 0, 4, 8, 12, 1, 5, 9, 13);
  const Wide efgh_zw = __builtin_shufflevector(ef, gh, 2, 6, 10, 14, 3, 7, 11, 15);
  out.x = __builtin_shufflevector(abcd_xy, efgh_xy, 0, 1, 2, 3, 8, 9, 10, 11);
  out.y = __builtin_shufflevector(abcd_xy, efgh_xy, 4, 5, 6, 7, 12, 13, 14, 15);
  out.z = __builtin_shufflevector(abcd_zw, efgh_zw, 0, 1, 2, 3, 8, 9, 10, 11);
  out.w = __builtin_shufflevector(abcd_zw, efgh_zw, 4, 5, 6, 7, 12, 13, 14, 15);
}

/// The lanes summed in a fixed order, ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7)).
[[gnu::always_inline]] inline Scalar wide_sum(const Wide& a) {
  return ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
}

/// w[l] = W(|x_i - x_l|) for the points of `p` (unit: 1/m^3): four (FourPoints, V = Lanes) or eight
/// (EightPoints, V = Wide).
template <class Points, class V>
[[gnu::always_inline]] inline void kernel_at(const CubicSplineKernel& k, const PackedPoint& xi,
                                             const Points& p, V& w) {
  const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
  const V r2 = dx * dx + dy * dy + dz * dz;
  for (std::uint32_t l = 0; l < sizeof(V) / sizeof(Scalar); ++l)
    w[l] = k.value(std::sqrt(r2[l]));
}

/// f[l] with grad W(x_i - x_l) = f[l] (x_i - x_l) for the points of `p` (unit: 1/m^5), as kernel_at.
template <class Points, class V>
[[gnu::always_inline]] inline void gradient_factor_at(const CubicSplineKernel& k, const PackedPoint& xi,
                                                      const Points& p, V& f) {
  const V dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
  const V r2 = dx * dx + dy * dy + dz * dz;
  for (std::uint32_t l = 0; l < sizeof(V) / sizeof(Scalar); ++l)
    f[l] = k.gradient_factor(r2[l]);
}

/// What the eight-lane double groups share: lane count, kernel, record and sum types (for_each_group,
/// kernel_sum).
struct EightDoubleLanes {
  static constexpr std::uint32_t kGroupLanes = kWide;
  using Kernel = CubicSplineKernel;
  using Record = PackedPoint;
  using Sum = Scalar;
};

/// Eight lanes as one vector of eight doubles: one register in the AVX-512 copy, four in the baseline copy.
struct WideGroup : EightDoubleLanes {
  using Vec = Wide;
  using Mask = WideMask;
  using Points = EightPoints;
  /// out = the first `count` lanes (an out parameter: a 64-byte vector returned by value makes GCC warn of
  /// the ABI in the copies without AVX-512, -Wpsabi).
  [[gnu::always_inline]] static void first(std::int64_t count, Mask& out) {
    const WideMask lane = {0, 1, 2, 3, 4, 5, 6, 7};
    out = lane < count;
  }
  [[gnu::always_inline]] static void load(const PackedPoint* points, const Index* js, Points& out) {
    load_eight(points, js, out);
  }
  [[gnu::always_inline]] static void kernel(const CubicSplineKernel& k, const PackedPoint& xi,
                                            const Points& p, Vec& w) {
    kernel_at(k, xi, p, w);
  }
  [[gnu::always_inline]] static void gradient_factor(const CubicSplineKernel& k, const PackedPoint& xi,
                                                     const Points& p, Vec& f) {
    gradient_factor_at(k, xi, p, f);
  }
  /// out = v in the active lanes, 0 in the others.
  [[gnu::always_inline]] static void select(const Mask& active, const Vec& v, Vec& out) {
    out = active ? v : Vec{};
  }
  [[gnu::always_inline]] static Scalar sum(const Vec& v) { return wide_sum(v); }
};

/// Two vectors V as one of twice the lanes (lo: the first half), with the wide vector's arithmetic lane by
/// lane: the halves groups' vector (HalvesGroup here, FloatHalvesGroup in float_lanes.hpp). Only the
/// operators the loops use; S is a scalar.
template <class V>
struct LanePair {
  V lo, hi;
};
template <class V>
[[gnu::always_inline]] inline LanePair<V> operator*(const LanePair<V>& a, const LanePair<V>& b) {
  return {a.lo * b.lo, a.hi * b.hi};
}
template <class V, class S>
[[gnu::always_inline]] inline LanePair<V> operator*(S a, const LanePair<V>& b) {
  return {a * b.lo, a * b.hi};
}
template <class V>
[[gnu::always_inline]] inline LanePair<V> operator+(const LanePair<V>& a, const LanePair<V>& b) {
  return {a.lo + b.lo, a.hi + b.hi};
}
template <class V, class S>
[[gnu::always_inline]] inline LanePair<V> operator+(S a, const LanePair<V>& b) {
  return {a + b.lo, a + b.hi};
}
template <class V, class S>
[[gnu::always_inline]] inline LanePair<V> operator-(S a, const LanePair<V>& b) {
  return {a - b.lo, a - b.hi};
}
template <class V, class S>
[[gnu::always_inline]] inline LanePair<V> operator-(const LanePair<V>& a, S b) {
  return {a.lo - b, a.hi - b};
}
template <class V>
[[gnu::always_inline]] inline LanePair<V>& operator+=(LanePair<V>& a, const LanePair<V>& b) {
  a.lo += b.lo;
  a.hi += b.hi;
  return a;
}
template <class V>
[[gnu::always_inline]] inline LanePair<V>& operator-=(LanePair<V>& a, const LanePair<V>& b) {
  a.lo -= b.lo;
  a.hi -= b.hi;
  return a;
}

/// Eight doubles as two vectors of four (lanes 0-3 and 4-7).
using Halves = LanePair<Lanes>;

/// Eight lanes as two vectors of four: two registers in the AVX2 copy.
struct HalvesGroup : EightDoubleLanes {
  typedef std::int64_t LaneMask __attribute__((vector_size(4 * sizeof(std::int64_t))));
  using Vec = Halves;
  struct Mask {
    LaneMask lo, hi;
  };
  struct Points {
    Halves x, y, z, w;
  };
  [[gnu::always_inline]] static void first(std::int64_t count, Mask& out) {
    const LaneMask lane = {0, 1, 2, 3};
    out = {lane < count, lane + 4 < count};
  }
  [[gnu::always_inline]] static void load(const PackedPoint* points, const Index* js, Points& out) {
    FourPoints a, b;
    load_four(points, js, a);
    load_four(points, js + kLanes, b);
    out = {{a.x, b.x}, {a.y, b.y}, {a.z, b.z}, {a.w, b.w}};
  }
  [[gnu::always_inline]] static void kernel(const CubicSplineKernel& k, const PackedPoint& xi,
                                            const Points& p, Vec& w) {
    kernel_at(k, xi, FourPoints{p.x.lo, p.y.lo, p.z.lo, p.w.lo}, w.lo);
    kernel_at(k, xi, FourPoints{p.x.hi, p.y.hi, p.z.hi, p.w.hi}, w.hi);
  }
  [[gnu::always_inline]] static void gradient_factor(const CubicSplineKernel& k, const PackedPoint& xi,
                                                     const Points& p, Vec& f) {
    gradient_factor_at(k, xi, FourPoints{p.x.lo, p.y.lo, p.z.lo, p.w.lo}, f.lo);
    gradient_factor_at(k, xi, FourPoints{p.x.hi, p.y.hi, p.z.hi, p.w.hi}, f.hi);
  }
  [[gnu::always_inline]] static void select(const Mask& active, const Vec& v, Vec& out) {
    out = {active.lo ? v.lo : Lanes{}, active.hi ? v.hi : Lanes{}};
  }
  /// ((a0 + a1) + (a2 + a3)) + ((a4 + a5) + (a6 + a7)), as wide_sum.
  [[gnu::always_inline]] static Scalar sum(const Vec& v) { return lane_sum(v.lo) + lane_sum(v.hi); }
};

/// Calls body(js, fs, active) for the neighbors of particle i in `list`, Group::kGroupLanes (8 or 16) at a
/// time: `js` points to kGroupLanes readable indices and, when `factors` (one per entry of `list`) is given,
/// `fs` to their kGroupLanes factors (else nullptr); `active` (a Group::Mask) marks the lanes that are i's
/// neighbors (all of them but in the last group, which takes the last count mod kGroupLanes). The last
/// group's other lanes hold the next particle's entries, read in place (real points, whose terms the body
/// drops); only at the very end of the list, where reading on would leave the array, are they copies of its
/// last entry (test_fluid_context covers that group; without the copies ASan reports an overflow). `body`
/// must be always_inline (see above).
template <class Group, class Body>
[[gnu::always_inline]] inline void for_each_group(const NeighborList& list, std::size_t i,
                                                  const float* factors, Body&& body) {
  constexpr std::uint32_t lanes = Group::kGroupLanes;
  const Index* js = list.indices.data();
  std::uint32_t n = list.offsets[i];
  const std::uint32_t end = list.offsets[i + 1];
  typename Group::Mask all, active;
  Group::first(lanes, all);
  for (; n + lanes <= end; n += lanes)
    body(js + n, factors ? factors + n : nullptr, all);
  if (n == end) return;
  const std::uint32_t count = end - n;
  Group::first(count, active);
  if (n + lanes <= list.indices.size()) {
    body(js + n, factors ? factors + n : nullptr, active);
    return;
  }
  Index padded[lanes];
  float padded_factors[lanes];
  for (std::uint32_t l = 0; l < lanes; ++l) {
    const std::uint32_t entry = n + (l < count ? l : count - 1);
    padded[l] = js[entry];
    padded_factors[l] = factors ? factors[entry] : 0.0f;
  }
  body(padded, factors ? padded_factors : nullptr, active);
}

/// sum over the neighbors j of i in `list` of w_j W(|x_i - x_j|), for `sources` packed with their weights, in
/// the group's precision (Scalar for the eight-lane double groups here, float for the sixteen-lane groups of
/// float_lanes.hpp). Group::kGroupLanes neighbors at a time, the last (count mod kGroupLanes) as one more
/// group with its padding lanes dropped, in that order. The densities' loop (sph_densities,
/// sph_densities_float); here so that the tests run it with every group type.
template <class Group>
[[gnu::always_inline]] inline typename Group::Sum kernel_sum(const typename Group::Kernel& k,
                                                             const NeighborList& list, std::size_t i,
                                                             const typename Group::Record& xi,
                                                             const typename Group::Record* sources) {
  typename Group::Vec sum = {};
  for_each_group<Group>(
      list, i, nullptr,
      [&](const Index* group, const float*, const typename Group::Mask& active)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(sources, group, p);
            typename Group::Vec w;
            Group::kernel(k, xi, p, w);
            typename Group::Vec term;
            Group::select(active, p.w * w, term);
            sum += term;
          });
  return Group::sum(sum);
}

/// sum over the neighbors j of i in `list` of V_j W(|x_i - x_j|) (v_j - v_i), for `xs` packed with the
/// volumes V_j = m_j / rho_j and `vs` with the velocities (unit: m/s). Eight neighbors at a time as
/// kernel_sum. XSPH's loop (sph/forces/viscosity.cpp); here so that the tests run it with either group type.
template <class Group>
[[gnu::always_inline]] inline Vec3 xsph_sum(const CubicSplineKernel& k, const NeighborList& list,
                                            std::size_t i, const PackedPoint* xs, const PackedPoint* vs) {
  const PackedPoint& xi = xs[i];
  const PackedPoint& vi = vs[i];
  typename Group::Vec sx = {}, sy = {}, sz = {};
  for_each_group<Group>(
      list, i, nullptr,
      [&](const Index* group, const float*, const typename Group::Mask& active)
          __attribute__((always_inline)) {
            typename Group::Points p, v;
            Group::load(xs, group, p);
            Group::load(vs, group, v);
            typename Group::Vec w, s;
            Group::kernel(k, xi, p, w);
            Group::select(active, p.w * w, s);
            sx += s * (v.x - vi.x);
            sy += s * (v.y - vi.y);
            sz += s * (v.z - vi.z);
          });
  return Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
}

/// sum over the neighbors j of i in `list` of scale (alpha + w_j) grad W(x_i - x_j), the kernel's gradient
/// taken at the points' positions (no stored factors), for `sources` packed with their w_j. Eight neighbors
/// at a time as kernel_sum. PBF's move (pressure/pressure_pbf.cpp): its iterations move the particles too far
/// for the gradient factors of the neighbor search.
template <class Group>
[[gnu::always_inline]] inline Vec3 gradient_sum(const CubicSplineKernel& k, const NeighborList& list,
                                                std::size_t i, const PackedPoint& xi,
                                                const PackedPoint* sources, Scalar alpha, Scalar scale) {
  typename Group::Vec sx = {}, sy = {}, sz = {};
  for_each_group<Group>(
      list, i, nullptr,
      [&](const Index* group, const float*, const typename Group::Mask& active)
          __attribute__((always_inline)) {
            typename Group::Points p;
            Group::load(sources, group, p);
            typename Group::Vec f, s;
            Group::gradient_factor(k, xi, p, f);
            Group::select(active, scale * ((alpha + p.w) * f), s);
            sx += s * (xi.x - p.x);
            sy += s * (xi.y - p.y);
            sz += s * (xi.z - p.z);
          });
  return Vec3(Group::sum(sx), Group::sum(sy), Group::sum(sz));
}

/// Calls loop(HalvesType{}) in the AVX2 copy of a DRENCH_SIMD_CLONES function and loop(WideType{}) in the
/// others: a pair of group types with the same bits (HalvesGroup and WideGroup here, the float pair in
/// float_lanes.hpp). `loop` must be always_inline (see above).
template <class HalvesType, class WideType, class Loop>
[[gnu::always_inline]] inline void with_group_of_copy(Loop&& loop) {
  if (avx2_copy()) {
    loop(HalvesType{});
  } else {
    loop(WideType{});
  }
}

}  // namespace
}  // namespace drench
