#pragma once
/// How drench's particle loops are cut for OpenMP, and compiled for the CPU they run on.

#include <algorithm>
#include <cstddef>

namespace drench {

/// Particles per chunk in loops over neighbor pairs, dealt round-robin to the threads
/// (`schedule(static, kParticleChunk)`). Particles are z-ordered, so contiguous halves of the array are
/// regions of space with unequal work (the one on the floor has the boundary neighbors, the one at the free
/// surface half-empty neighborhoods); chunks interleave the regions and keep each chunk's neighbors in cache.
/// A static schedule assigns the same chunks to the same threads on every run, and every loop using it writes
/// per-particle results only, so results stay bit-identical for any thread count.
inline constexpr std::size_t kParticleChunk = 256;

/// Calls body(begin, end) for the chunks [k kParticleChunk, min(n, (k + 1) kParticleChunk)) of n particles,
/// dealt to the threads as `schedule(static, kParticleChunk)` deals particles. For loops whose body per chunk
/// is a DRENCH_SIMD_CLONES function: one dispatch per chunk, not per particle.
template <class Body>
void for_each_chunk(std::size_t n, Body body) {
  const std::size_t chunks = (n + kParticleChunk - 1) / kParticleChunk;
#pragma omp parallel for schedule(static, 1)
  for (std::size_t k = 0; k < chunks; ++k)
    body(k * kParticleChunk, std::min(n, (k + 1) * kParticleChunk));
}

}  // namespace drench

/// Marks a hot loop function to be compiled twice, for x86-64-v3 (AVX2: four doubles per vector, hardware
/// gathers) and for the baseline x86-64 that the build targets, the copy being chosen once at load time by
/// the CPU (GCC's target_clones, an ifunc). The SPH pair loops gather neighbor coordinates by index, which
/// the baseline can only do two doubles at a time with scalar loads; the AVX2 copy ran PCISPH's pressure
/// solve 1.3x faster (measured, README). Every thread runs the same copy, so runs stay bit-identical; the
/// copies may differ in the last bits between CPUs, as vectorized sums are added in another order
/// (drench_core is built with -ffp-contract=off, so no copy fuses a multiply and an add). Only for
/// non-inline, non-template functions: what they inline is compiled into each copy.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(DRENCH_NO_SIMD_CLONES)
#define DRENCH_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define DRENCH_SIMD_CLONES
#endif
