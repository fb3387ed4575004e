#pragma once
/// The grid search's inner loop (sph/neighbor_search.cpp): of a run of candidate points, keep the indices of
/// those within the support radius of one query, in their order. Three versions with the same result, the
/// fastest the CPU has being used: eight candidates at a time with AVX-512's compress, eight at a time with
/// AVX2's lane permute and a table of permutations, and four at a time in GCC's vector extension (every copy
/// of DRENCH_SIMD_CLONES, the only one on CPUs before AVX2). Internal to neighbor_search.cpp and its tests,
/// which run them all against each other.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>

#include <drench/common/parallel.hpp>
#include <drench/sph/packed_lanes.hpp>

// The AVX-512 scan needs AVX-512 (F, VL) and BMI2, the AVX2 scan AVX2 and BMI2: each is compiled for its
// x86-64 level by a target attribute where the build makes DRENCH_SIMD_CLONES, or with no attribute where the
// whole build targets such a CPU. They are not clones: NeighborSearch picks one at run time
// (avx512_copy(), avx2_copy(); NeighborSearch::set_candidate_scan).
#if DRENCH_HAS_SIMD_CLONES
#define DRENCH_HAS_AVX512_SCAN 1
#define DRENCH_HAS_AVX2_SCAN 1
#define DRENCH_TARGET_X86_64_V4 __attribute__((target("arch=x86-64-v4")))
#define DRENCH_TARGET_X86_64_V3 __attribute__((target("arch=x86-64-v3")))
#else
#if defined(__x86_64__) && defined(__AVX512F__) && defined(__AVX512VL__) && defined(__BMI2__)
#define DRENCH_HAS_AVX512_SCAN 1
#define DRENCH_TARGET_X86_64_V4
#else
#define DRENCH_HAS_AVX512_SCAN 0
#endif
#if defined(__x86_64__) && defined(__AVX2__) && defined(__BMI2__)
#define DRENCH_HAS_AVX2_SCAN 1
#define DRENCH_TARGET_X86_64_V3
#else
#define DRENCH_HAS_AVX2_SCAN 0
#endif
#endif

#if DRENCH_HAS_AVX512_SCAN || DRENCH_HAS_AVX2_SCAN
#include <immintrin.h>
#endif

namespace drench {
namespace {

/// Entries each candidate array holds after its last candidate (the scans read whole groups of up to eight),
/// and that the destination holds after `end`.
constexpr std::uint32_t kScanPadding = 7;

/// Writes the indices of the candidates q < end with |p_q - x|^2 < r2 and indices[q] != self to dst, in their
/// order, and returns how many. Four candidates at a time: their coordinates are contiguous, so the distances
/// are vector arithmetic without gathers; the distance is the same expression in every lane (source minus
/// query, summed x, y, z) and in every copy, so the kept set does not depend on the CPU.
/// Precondition: xs, ys, zs and indices hold end + kScanPadding entries, dst has room for as many.
[[gnu::always_inline]] inline std::size_t scan_candidates_lanes(const Scalar* xs, const Scalar* ys,
                                                                const Scalar* zs, const Index* indices,
                                                                std::uint32_t end, const Vec3& x, Scalar r2,
                                                                Index self, Index* dst) {
  const Scalar x0 = x.x(), x1 = x.y(), x2 = x.z();
  std::size_t count = 0;
  for (std::uint32_t q = 0; q < end; q += kLanes) {
    Lanes px, py, pz;
    std::memcpy(&px, xs + q, sizeof(Lanes));
    std::memcpy(&py, ys + q, sizeof(Lanes));
    std::memcpy(&pz, zs + q, sizeof(Lanes));
    const Lanes d0 = px - x0, d1 = py - x1, d2 = pz - x2;
    const auto inside = d0 * d0 + d1 * d1 + d2 * d2 < r2;
    // Every candidate is written and kept only if it is a neighbor: whether a point of a neighbouring cell
    // lies inside the radius is a coin toss, and a mispredicted branch costs more than the write. The lanes
    // are written out one by one: in a loop over l the compiler spilled the mask and reloaded each lane.
    const Index* js = indices + q;
    const std::uint32_t left = end - q;
    dst[count] = js[0];
    count += static_cast<std::size_t>((inside[0] != 0) & (js[0] != self));
    dst[count] = js[1];
    count += static_cast<std::size_t>((inside[1] != 0) & (js[1] != self) & (left > 1));
    dst[count] = js[2];
    count += static_cast<std::size_t>((inside[2] != 0) & (js[2] != self) & (left > 2));
    dst[count] = js[3];
    count += static_cast<std::size_t>((inside[3] != 0) & (js[3] != self) & (left > 3));
  }
  return count;
}

/// The signature of the scans above and below.
using CandidateScanFunction = std::size_t (*)(const Scalar*, const Scalar*, const Scalar*, const Index*,
                                              std::uint32_t, const Vec3&, Scalar, Index, Index*);

/// `Scan` over the runs [begins[r], ends[r]), r < runs, of the arrays, in place, the kept indices one after
/// the other in dst: no copy of the candidates into one array first. Inlined into one function per scan,
/// compiled for that scan's CPU (scan_runs_compress, scan_runs_permute, and neighbor_search.cpp's
/// scan_runs_lanes), so that the scan inlines and its set-up is hoisted out of the runs. Precondition: xs,
/// ys, zs and indices hold kScanPadding entries after every run's end; dst has room for all the runs'
/// candidates + kScanPadding.
template <CandidateScanFunction Scan>
[[gnu::always_inline]] inline std::size_t scan_runs(const Scalar* xs, const Scalar* ys, const Scalar* zs,
                                                    const Index* indices, const std::uint32_t* begins,
                                                    const std::uint32_t* ends, int runs, const Vec3& x,
                                                    Scalar r2, Index self, Index* dst) {
  std::size_t count = 0;
  for (int r = 0; r < runs; ++r) {
    const std::uint32_t b = begins[r];
    count += Scan(xs + b, ys + b, zs + b, indices + b, ends[r] - b, x, r2, self, dst + count);
  }
  return count;
}

#if DRENCH_HAS_AVX512_SCAN
/// scan_candidates_lanes' result, eight candidates at a time: the kept lanes' indices are packed to the front
/// of one vector (vpcompressd, register form: its memory form is microcoded on AMD's Zen 4) and the vector is
/// stored whole at dst + count. The four-lane version spends a compare, an and and a dependent add per
/// candidate on the packing. The distances are the same expression, rounded the same way, so the kept set is
/// the same: GCC treats these intrinsics as plain vector arithmetic and would fuse the multiplies and adds
/// under its default -ffp-contract=fast, so every target including this header must be compiled with
/// -ffp-contract=off (drench_core and the unit tests are). Call only when the CPU has AVX-512
/// (avx512_copy()). Precondition: as scan_candidates_lanes.
DRENCH_TARGET_X86_64_V4 inline std::size_t scan_candidates_compress(const Scalar* xs, const Scalar* ys,
                                                                    const Scalar* zs, const Index* indices,
                                                                    std::uint32_t end, const Vec3& x,
                                                                    Scalar r2, Index self, Index* dst) {
  const __m512d x0 = _mm512_set1_pd(x.x()), x1 = _mm512_set1_pd(x.y()), x2 = _mm512_set1_pd(x.z());
  const __m512d radius2 = _mm512_set1_pd(r2);
  const __m256i self_lanes = _mm256_set1_epi32(static_cast<int>(self));
  std::size_t count = 0;
  for (std::uint32_t q = 0; q < end; q += 8) {
    const __m512d d0 = _mm512_sub_pd(_mm512_loadu_pd(xs + q), x0);
    const __m512d d1 = _mm512_sub_pd(_mm512_loadu_pd(ys + q), x1);
    const __m512d d2 = _mm512_sub_pd(_mm512_loadu_pd(zs + q), x2);
    const __m512d d_sq =
        _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(d0, d0), _mm512_mul_pd(d1, d1)), _mm512_mul_pd(d2, d2));
    const __m256i js = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(indices + q));
    // Ordered, non-signalling less-than: false for NaN, as the vector extension's `<`.
    __mmask8 keep = _mm512_cmp_pd_mask(d_sq, radius2, _CMP_LT_OQ) & _mm256_cmpneq_epi32_mask(js, self_lanes);
    keep &= static_cast<__mmask8>(_bzhi_u32(0xffu, std::min(end - q, 8u)));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + count), _mm256_maskz_compress_epi32(keep, js));
    count += static_cast<std::size_t>(__builtin_popcount(keep));
  }
  return count;
}

/// scan_runs with scan_candidates_compress, compiled for x86-64-v4.
DRENCH_TARGET_X86_64_V4 inline std::size_t scan_runs_compress(
    const Scalar* xs, const Scalar* ys, const Scalar* zs, const Index* indices, const std::uint32_t* begins,
    const std::uint32_t* ends, int runs, const Vec3& x, Scalar r2, Index self, Index* dst) {
  return scan_runs<scan_candidates_compress>(xs, ys, zs, indices, begins, ends, runs, x, r2, self, dst);
}
#endif

#if DRENCH_HAS_AVX2_SCAN
/// Entry m: the positions of the set bits of m (0-7) in increasing order, one per byte from the lowest,
/// padded with zeros; the lane permutation that moves the kept lanes of mask m to the front.
constexpr std::array<std::uint64_t, 256> make_kept_lane_permutations() {
  std::array<std::uint64_t, 256> table{};
  for (unsigned m = 0; m < 256; ++m) {
    unsigned byte = 0;
    for (unsigned lane = 0; lane < 8; ++lane) {
      if (m & (1u << lane)) table[m] |= std::uint64_t{lane} << (8 * byte++);
    }
  }
  return table;
}
constexpr std::array<std::uint64_t, 256> kKeptLanePermutations = make_kept_lane_permutations();

/// Bit l set where the squared distance of point l of the four at xs, ys, zs from (x0, x1, x2) (broadcast)
/// is below radius2: ordered, so false for NaN.
DRENCH_TARGET_X86_64_V3 [[gnu::always_inline]] inline unsigned four_inside(const Scalar* xs, const Scalar* ys,
                                                                           const Scalar* zs, __m256d x0,
                                                                           __m256d x1, __m256d x2,
                                                                           __m256d radius2) {
  const __m256d d0 = _mm256_sub_pd(_mm256_loadu_pd(xs), x0);
  const __m256d d1 = _mm256_sub_pd(_mm256_loadu_pd(ys), x1);
  const __m256d d2 = _mm256_sub_pd(_mm256_loadu_pd(zs), x2);
  const __m256d d_sq =
      _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(d0, d0), _mm256_mul_pd(d1, d1)), _mm256_mul_pd(d2, d2));
  return static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(d_sq, radius2, _CMP_LT_OQ)));
}

/// scan_candidates_lanes' result, eight candidates at a time on AVX2: the two halves' comparisons become one
/// 8-bit mask, whose entry in kKeptLanePermutations moves the kept lanes' indices to the front of one vector
/// (vpermd), stored whole at dst + count (AVX2 has no compress). The same distances, rounded the same way
/// (as scan_candidates_compress), so the same kept set. Call only when the CPU has AVX2 and BMI2.
/// Precondition: as scan_candidates_lanes.
DRENCH_TARGET_X86_64_V3 inline std::size_t scan_candidates_permute(const Scalar* xs, const Scalar* ys,
                                                                   const Scalar* zs, const Index* indices,
                                                                   std::uint32_t end, const Vec3& x,
                                                                   Scalar r2, Index self, Index* dst) {
  const __m256d x0 = _mm256_set1_pd(x.x()), x1 = _mm256_set1_pd(x.y()), x2 = _mm256_set1_pd(x.z());
  const __m256d radius2 = _mm256_set1_pd(r2);
  const __m256i self_lanes = _mm256_set1_epi32(static_cast<int>(self));
  std::size_t count = 0;
  for (std::uint32_t q = 0; q < end; q += 8) {
    const __m256i js = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(indices + q));
    const unsigned is_self =
        static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(js, self_lanes))));
    const unsigned inside = four_inside(xs + q, ys + q, zs + q, x0, x1, x2, radius2) |
                            four_inside(xs + q + 4, ys + q + 4, zs + q + 4, x0, x1, x2, radius2) << 4;
    const unsigned keep = inside & ~is_self & _bzhi_u32(0xffu, std::min(end - q, 8u));
    const __m256i order =
        _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(static_cast<long long>(kKeptLanePermutations[keep])));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + count), _mm256_permutevar8x32_epi32(js, order));
    count += static_cast<std::size_t>(__builtin_popcount(keep));
  }
  return count;
}

/// scan_runs with scan_candidates_permute, compiled for x86-64-v3.
DRENCH_TARGET_X86_64_V3 inline std::size_t scan_runs_permute(
    const Scalar* xs, const Scalar* ys, const Scalar* zs, const Index* indices, const std::uint32_t* begins,
    const std::uint32_t* ends, int runs, const Vec3& x, Scalar r2, Index self, Index* dst) {
  return scan_runs<scan_candidates_permute>(xs, ys, zs, indices, begins, ends, runs, x, r2, self, dst);
}
#endif

}  // namespace
}  // namespace drench
