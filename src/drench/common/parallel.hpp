#pragma once
/// How drench's particle loops are cut for OpenMP, and compiled for the CPU they run on.

#include <algorithm>
#include <cstddef>

namespace drench {

/// Particles per chunk in loops over neighbor pairs, each chunk taken by the next free thread
/// (`schedule(dynamic, kParticleChunk)`, for_each_chunk). Particles are z-ordered, so contiguous halves of
/// the array are regions of space with unequal work (the one on the floor has the boundary neighbors, the one
/// at the free surface half-empty neighborhoods); chunks interleave the regions and keep each chunk's
/// neighbors in cache. Every loop using them writes per-particle (or per-chunk) results only, so results stay
/// bit-identical for any thread count, whichever thread takes a chunk.
inline constexpr std::size_t kParticleChunk = 256;

/// Calls body(begin, end) for the chunks [k kParticleChunk, min(n, (k + 1) kParticleChunk)) of n particles,
/// each chunk going to the next free thread (`schedule(dynamic, 1)` over chunks). For loops whose body per
/// chunk is a DRENCH_SIMD_CLONES function: one dispatch per chunk, not per particle. A chunk's results do not
/// depend on the thread that computes it (the body writes per-particle or per-chunk results only), so the
/// dynamic deal keeps runs bit-identical; it lets a thread whose core runs slower (the other core busy on a
/// shared host) take fewer chunks, where the static deal made the other wait at every loop's end
/// (bench_pair_loops densities, counter chunks_last_thread; bench_dam_break pcisph_59k on 2 threads).
template <class Body>
void for_each_chunk(std::size_t n, Body body) {
  const std::size_t chunks = (n + kParticleChunk - 1) / kParticleChunk;
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t k = 0; k < chunks; ++k)
    body(k * kParticleChunk, std::min(n, (k + 1) * kParticleChunk));
}

}  // namespace drench

/// Marks a hot loop function to be compiled three times, for x86-64-v4 (AVX-512: eight doubles per vector),
/// x86-64-v3 (AVX2: four) and the baseline x86-64 that the build targets, the copy being chosen once at load
/// time by the CPU (GCC's target_clones, an ifunc). Every thread runs the same copy, so runs stay
/// bit-identical. A loop that fixes its lanes and summation order (sph/packed_lanes.hpp) gives the same bits
/// in every copy as well: drench_core is built with -ffp-contract=off, so no copy fuses a multiply and an add
/// (the dam break's frames are identical with the clones disabled, built for x86-64 or x86-64-v3; the
/// PackedLanes and FloatLanes tests of test_fluid_context compare the group types). Only for non-inline,
/// non-template functions: what they inline is compiled into each copy.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(DRENCH_NO_SIMD_CLONES)
#define DRENCH_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#define DRENCH_HAS_SIMD_CLONES 1
#else
#define DRENCH_SIMD_CLONES
#define DRENCH_HAS_SIMD_CLONES 0
#endif

namespace drench {

/// True when the running copy of a DRENCH_SIMD_CLONES function is the x86-64-v3 (AVX2) one, the loader
/// picking it by the same tests; without clones, when the build targets AVX2 but not AVX-512. Loops over
/// eight lanes pick their vector type by it (sph/packed_lanes.hpp). Tested once; a read of a static after
/// that.
inline bool avx2_copy() {
#if DRENCH_HAS_SIMD_CLONES
  static const bool v3 = __builtin_cpu_supports("x86-64-v3") && !__builtin_cpu_supports("x86-64-v4");
  return v3;
#elif defined(__AVX2__) && !defined(__AVX512F__)
  return true;
#else
  return false;
#endif
}

/// True when the CPU runs the x86-64-v4 (AVX-512) copy of DRENCH_SIMD_CLONES functions, the loader picking it
/// by the same test; without clones, when the build targets AVX-512. The grid search's scans check it, and
/// avx2_copy(), to pick the AVX-512 or AVX2 scan (sph/candidate_scan.hpp). Tested once; a read of a static
/// after that.
inline bool avx512_copy() {
#if DRENCH_HAS_SIMD_CLONES
  static const bool v4 = __builtin_cpu_supports("x86-64-v4");
  return v4;
#elif defined(__AVX512F__) && defined(__AVX512VL__) && defined(__BMI2__)
  return true;
#else
  return false;
#endif
}

}  // namespace drench
