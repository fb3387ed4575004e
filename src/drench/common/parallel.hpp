#pragma once
/// drench's parallel loops: a thread pool of its own, how particle loops are cut into chunks for it, and how
/// hot loops are compiled for the CPU they run on.
///
/// Why not OpenMP: libgomp's threads spin at every barrier for up to 300,000 spins before they sleep, and its
/// wait policy can only be set in the environment before the program loads it, so a library cannot choose it
/// for the program that embeds it. Beside one busy thread on a 2-core machine a jet on a cloth ran 5.7x
/// slower on two threads than on one. This pool's idle threads spin for at most 50 us (parallel.cpp's
/// kSpinTime), then block; after a worker came late to a loop's end (preempted by another busy thread), the
/// loops run on their callers alone for a while (detail::LateWorkerPolicy).

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace drench {

/// Largest thread count set_thread_count accepts.
inline constexpr int kMaxThreadCount = 1024;

/// Sets the number of threads drench's parallel loops use, the calling thread included, for every thread of
/// the process from the next loop on (threads beyond the first are started on first use, stopped and
/// restarted when the number changes). Safe to call from any thread at any time; a loop already running
/// finishes with the threads it has. Results do not depend on it: every loop gives the same bits for any
/// thread count.
/// @param n  threads, in [1, kMaxThreadCount]
/// @throws Error naming n when it is outside [1, kMaxThreadCount]
void set_thread_count(int n);

/// The number of threads drench's parallel loops use (>= 1). Until set_thread_count is called: the value of
/// the environment variable OMP_NUM_THREADS when it is an integer in [1, kMaxThreadCount] (its first entry if
/// it is a list; read once, at the first call, so scripts written for drench's OpenMP builds keep their
/// meaning; any other value is ignored, as libgomp ignores it), else the CPUs this process may run on (its
/// affinity mask; std::thread::hardware_concurrency where that is not available).
int thread_count();

/// What is wrong with the environment variable OMP_NUM_THREADS as thread_count reads it, e.g.
/// "OMP_NUM_THREADS='abc' is not a whole number in [1, 256]"; "" when it is unset or a count thread_count
/// uses. A command tells the user, since thread_count ignores such a value without a word.
std::string omp_num_threads_problem();

namespace detail {

/// One chunk of a loop: calls the body at `body` on [begin, end) as participant `slot`.
using ChunkFunction = void (*)(void* body, std::size_t begin, std::size_t end, int slot);

/// Runs fn on the chunks [k grain, min(n, (k + 1) grain)), each taken by the next free participant (the
/// calling thread is participant 0, the pool's threads 1, 2, ...; only those below `slots` take chunks), and
/// returns when every chunk is done. Runs the chunks in order on the calling thread when there is one chunk,
/// one thread, when called from inside a loop's body (a nested loop) or while another thread's loop holds
/// the pool. The first exception a chunk throws is rethrown here once every running chunk has finished; the
/// chunks not yet started are skipped.
void run_chunks(std::size_t n, std::size_t grain, int slots, ChunkFunction fn, void* body);

/// When the pool's loops run on their callers alone, the workers sleeping: beside busy threads (a game's, a
/// renderer's) a worker that the scheduler preempts while it holds a chunk stops the whole loop until its
/// core is given back, a time slice of the other thread (about a millisecond or more: EEVDF's base slice is
/// 0.75 ms times 1 + log2(CPUs)), and a sub-step runs some tens of loops. A caller that waited longer than
/// kLateWait at a loop's end (a chunk takes some tens of microseconds) starts a stretch of loops on callers
/// alone: kMinSolo at first, so that a passing load (another program's burst) costs little; a late wait soon
/// after a stretch ended (within the stretch's length) doubles the next, up to kMaxSolo, so that a lasting
/// busy thread costs one late wait per kMaxSolo. Results do not change: every loop gives the same bits on
/// any number of threads. Times are passed in, so that the rule is tested without a clock.
class LateWorkerPolicy {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr Clock::duration kLateWait = std::chrono::microseconds(500);
  static constexpr Clock::duration kMinSolo = std::chrono::milliseconds(4);
  static constexpr Clock::duration kMaxSolo = std::chrono::milliseconds(128);

  /// A caller waited `waited` at a loop's end for the workers, the wait ending at `now`. True when that
  /// starts a stretch (then solo_until() is its end).
  bool on_wait(Clock::duration waited, Clock::time_point now) {
    if (waited <= kLateWait) return false;
    const bool again = m_solo_end != Clock::time_point{} && now - m_solo_end < m_solo_time;
    m_solo_time = again ? std::min<Clock::duration>(2 * m_solo_time, kMaxSolo) : kMinSolo;
    m_solo_end = now + m_solo_time;
    return true;
  }

  /// The end of the last stretch (Clock::time_point{} before the first): loops started before it run on
  /// their callers alone.
  Clock::time_point solo_until() const { return m_solo_end; }

  /// Forgets the stretches (a new thread count starts afresh).
  void reset() {
    m_solo_time = kMinSolo;
    m_solo_end = Clock::time_point{};
  }

 private:
  Clock::duration m_solo_time = kMinSolo;
  Clock::time_point m_solo_end{};
};

/// What the pool did since the last reset_pool_stats, counted only in a build configured with
/// DRENCH_POOL_STATS=ON (a measuring option: it compiles two clock reads per loop into parallel.cpp alone);
/// in any other build every field stays 0 and `counted` false. For bench/bench_game_frame's counters: how
/// many loops a frame runs, and how long their ends wait for a thread that another busy thread keeps off its
/// core.
struct PoolStats {
  bool counted = false;              ///< the build counts (DRENCH_POOL_STATS)
  std::uint64_t parallel_loops = 0;  ///< loops dealt to the pool's threads
  std::uint64_t serial_loops = 0;    ///< loops outside any other run on their caller alone (one chunk, ...)
  std::uint64_t chunks = 0;          ///< chunks of the parallel loops
  std::uint64_t caller_chunks = 0;   ///< of those, taken by the calling thread
  std::uint64_t caller_alone_loops = 0;  ///< parallel loops whose every chunk the caller took (workers late)
  std::uint64_t waits = 0;           ///< parallel loops whose caller waited for a worker after its last chunk
  std::uint64_t blocked_waits = 0;   ///< of those, waits that outlasted the spin and blocked
  std::uint64_t long_waits = 0;      ///< of those, waits over 1 ms (a worker off its core)
  double loop_seconds = 0.0;         ///< wall time of the parallel loops, start to end (unit: s)
  double wait_seconds = 0.0;         ///< of it, the callers' waits after their last chunk (unit: s)
  double max_wait_seconds = 0.0;     ///< the longest such wait (unit: s)
  double serial_seconds = 0.0;       ///< wall time of the serial loops (unit: s)
  std::uint64_t solo_stretches = 0;  ///< stretches of loops on the caller alone begun after a late wait
  std::uint64_t light_loops = 0;     ///< parallel loops of grain kLightChunk
  double light_seconds = 0.0;        ///< their wall time (unit: s)
};

/// The pool's counts since the last reset (all 0 unless built with DRENCH_POOL_STATS).
PoolStats pool_stats();

/// Sets the pool's counts to 0.
void reset_pool_stats();

template <class Body>
void call_chunk(void* body, std::size_t begin, std::size_t end, int slot) {
  Body& b = *static_cast<Body*>(body);
  if constexpr (std::is_invocable_v<Body&, std::size_t, std::size_t, int>) {
    b(begin, end, slot);
  } else {
    (void)slot;
    b(begin, end);
  }
}

}  // namespace detail

/// Particles per chunk in loops over neighbor pairs, each chunk taken by the next free thread
/// (for_each_chunk). Particles are z-ordered, so contiguous halves of the array are regions of space with
/// unequal work (the one on the floor has the boundary neighbors, the one at the free surface half-empty
/// neighborhoods); chunks interleave the regions and keep each chunk's neighbors in cache. Every loop using
/// them writes per-particle (or per-chunk) results only, so results stay bit-identical for any thread count,
/// whichever thread takes a chunk.
inline constexpr std::size_t kParticleChunk = 256;

/// Elements per chunk of light loops (a few nanoseconds per element: copies, an equation of state, an
/// integration step): large enough that taking a chunk (one atomic add) costs under a percent of it, small
/// enough that a thread slowed by another busy thread on its core takes fewer chunks instead of holding up
/// the loop's end. A loop of at most kLightSerial elements runs on the calling thread alone, waking nobody.
inline constexpr std::size_t kLightChunk = 2048;

/// Light loops (grain kLightChunk) of at most this many elements run on the calling thread alone. A light
/// loop of 2 to 16 chunks took 1.2-1.3x as long on two threads as on one (Vec3 axpy, 2-core VM, median of
/// 2,000 loops); bench_game_frame's 4,000-particle level ran 370 light loops per DFSPH frame, 31-38 ms on two
/// threads against 12-14 ms on the caller alone (DRENCH_POOL_STATS counters): waking a worker and moving
/// the chunk's cache lines to its core cost more than the chunk. Larger ones (the 59K dam break's 29
/// chunks) stay parallel.
inline constexpr std::size_t kLightSerial = 8 * kLightChunk;

/// Calls body(begin, end) (or body(begin, end, slot)) for the chunks [k grain, min(n, (k + 1) grain)) of
/// [0, n), each chunk going to the next free thread; returns when all are done. The body must write results
/// per element or per chunk only (never in an order that depends on the thread), so that the results are the
/// same for any thread count and any deal. `slot` in [0, thread_count()) names the participant running the
/// chunk, for per-thread scratch space: no two chunks run at once with the same slot. A loop started inside
/// a body, or while another thread's loop holds the pool (two user threads, e.g. render/'s LiveSimulation and
/// LiveSurface), a light loop of at most kLightSerial elements, and the loops of a stretch after a worker
/// came late (detail::LateWorkerPolicy) run serially on their caller, chunk by chunk in order, with the same
/// results. An exception thrown by the body
/// reaches the caller, after the chunks already running have finished (the others are skipped).
/// @param n  elements; 0 calls nothing
/// @param grain  elements per chunk, > 0
template <class Body>
void parallel_for(std::size_t n, std::size_t grain, Body body) {
  detail::run_chunks(n, grain, thread_count(), &detail::call_chunk<Body>, &body);
}

/// parallel_for with slots in [0, slots) only: for a caller that sized its per-thread scratch space before
/// the loop (thread_count() may change in between, from another thread).
/// @param slots  participants at most, >= 1
template <class Body>
void parallel_for_slots(std::size_t n, std::size_t grain, int slots, Body body) {
  detail::run_chunks(n, grain, slots, &detail::call_chunk<Body>, &body);
}

/// Calls body(begin, end) for the chunks [k kParticleChunk, min(n, (k + 1) kParticleChunk)) of n particles,
/// each chunk going to the next free thread. For loops whose body per chunk is a DRENCH_SIMD_CLONES function:
/// one dispatch per chunk, not per particle. A chunk's results do not depend on the thread that computes it
/// (the body writes per-particle or per-chunk results only), so the dynamic deal keeps runs bit-identical; it
/// lets a thread whose core runs slower (the other core busy on a shared host) take fewer chunks, where a
/// static deal made the other wait at every loop's end (bench_pair_loops densities, counter
/// chunks_last_thread; bench_dam_break pcisph_59k on 2 threads).
template <class Body>
void for_each_chunk(std::size_t n, Body body) {
  parallel_for(n, kParticleChunk, std::move(body));
}

/// Reduces [0, n) in chunks of `grain`: map(begin, end) gives each chunk's partial result, and the partials
/// are folded in chunk order, combine(combine(identity, p_0), p_1) ..., whatever thread computed them: a
/// floating-point sum gives the same bits for any thread count. The calls of map run in parallel as
/// parallel_for's body.
/// @param n  elements; 0 returns identity
/// @param grain  elements per chunk, > 0
template <class T, class Map, class Combine>
T parallel_reduce(std::size_t n, std::size_t grain, T identity, Map map, Combine combine) {
  static_assert(!std::is_same_v<T, bool>, "chunks write their partials concurrently: use int, not bool");
  const std::size_t chunks = (n + grain - 1) / grain;
  if (chunks <= 1) return chunks == 0 ? identity : combine(identity, map(std::size_t{0}, n));
  std::vector<T> partial(chunks, identity);
  parallel_for(n, grain,
               [&](std::size_t begin, std::size_t end) { partial[begin / grain] = map(begin, end); });
  T result = identity;
  for (const T& p : partial)
    result = combine(result, p);
  return result;
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
