#pragma once
/// Four or eight neighbors at a time: the vector types and the loads shared by the SPH pair loops over
/// PackedPoint arrays (sph/fluid_context.cpp, sph/forces/viscosity.cpp) and the grid search's scan
/// (sph/neighbor_search.cpp). Internal to those files' DRENCH_SIMD_CLONES functions; everything is in an
/// unnamed namespace and always inlined, so each copy compiles its own. A lambda in such a function must be
/// always_inline as well: out of line it is compiled for the baseline only (XSPH ran 2.7 times slower so,
/// timed in-process against the inlined version on bench_pair_loops' 59K state; that harness is not kept).
///
/// The loops that evaluate the kernel (densities, XSPH) take eight neighbors at a time: a square root of
/// eight lanes costs what one of four does on the AVX-512 copy. The densities of the 59K state ran 1.88-1.97
/// ms per pass against 2.54-2.57 ms at four lanes (`OMP_NUM_THREADS=1 build-bench/bench/bench_pair_loops
/// --benchmark_filter=densities`, this build against bf7bffb's, alternating; a third round of the old build
/// took 3.93 ms). The pressure loop, a few multiplies per pair, stays at four: an eight-lane version (not
/// kept) ran 1.1-1.4 times slower, in and out of cache, timed in-process against this one on the same state.

#include <cmath>
#include <cstdint>
#include <cstring>

#include "sph/fluid_context.hpp"

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

/// Eight doubles: the pair loops' vector. One AVX-512 register in the x86-64-v4 copy, two AVX2 registers in
/// the x86-64-v3 copy, four SSE2 registers in the baseline copy; the lanes are the same in all, so are the
/// sums.
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

/// w[l] = W(|x_i - x_l|) for the eight points of `p` (unit: 1/m^3).
[[gnu::always_inline]] inline void kernel_at_eight(const CubicSplineKernel& k, const PackedPoint& xi,
                                                   const EightPoints& p, Wide& w) {
  const Wide dx = xi.x - p.x, dy = xi.y - p.y, dz = xi.z - p.z;
  const Wide r2 = dx * dx + dy * dy + dz * dz;
  for (std::uint32_t l = 0; l < kWide; ++l)
    w[l] = k.value(std::sqrt(r2[l]));
}

/// Calls body(js, active) for the neighbors of particle i in `list`, eight at a time: `js` points to eight
/// readable indices, `active` marks the lanes that are i's neighbors (all of them but in the last group,
/// which takes the last count mod 8). The last group's other lanes hold the next particle's entries, read in
/// place (real points, whose terms the body drops); only at the very end of the list, where reading on would
/// leave the array, are they copies of its last index (test_fluid_context covers that group; without the
/// copies ASan reports an overflow). `body` must be always_inline (see above).
template <class Body>
[[gnu::always_inline]] inline void for_each_eight(const NeighborList& list, std::size_t i, Body&& body) {
  const Index* js = list.indices.data();
  std::uint32_t n = list.offsets[i];
  const std::uint32_t end = list.offsets[i + 1];
  const WideMask all = {-1, -1, -1, -1, -1, -1, -1, -1};
  for (; n + kWide <= end; n += kWide)
    body(js + n, all);
  if (n == end) return;
  const std::uint32_t count = end - n;
  const WideMask lane = {0, 1, 2, 3, 4, 5, 6, 7};
  const WideMask active = lane < static_cast<std::int64_t>(count);
  if (n + kWide <= list.indices.size()) {
    body(js + n, active);
    return;
  }
  Index padded[kWide];
  for (std::uint32_t l = 0; l < kWide; ++l)
    padded[l] = js[n + (l < count ? l : count - 1)];
  body(padded, active);
}

}  // namespace
}  // namespace drench
