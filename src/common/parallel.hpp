#pragma once
/// How drench's particle loops are cut for OpenMP.

#include <cstddef>

namespace drench {

/// Particles per chunk in loops over neighbor pairs, dealt round-robin to the threads
/// (`schedule(static, kParticleChunk)`). Particles are z-ordered, so contiguous halves of the array are
/// regions of space with unequal work (the one on the floor has the boundary neighbors, the one at the free
/// surface half-empty neighborhoods); chunks interleave the regions and keep each chunk's neighbors in cache.
/// A static schedule assigns the same chunks to the same threads on every run, and every loop using it writes
/// per-particle results only, so results stay bit-identical for any thread count.
inline constexpr std::size_t kParticleChunk = 256;

}  // namespace drench
