#include <drench/common/parallel.hpp>

#include <atomic>
#include <cassert>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <string>
#include <thread>

#include <drench/common/error.hpp>

#if defined(__linux__)
#include <sched.h>
#endif

// A std::thread pool rather than TBB (which OpenVDB brings): the loops need only a shared chunk counter, the
// deal must not matter for the results, and the threads' waiting must be bounded and visible here; TBB's
// arenas were not measured against it.

namespace drench {

namespace {

#if defined(DRENCH_POOL_STATS)
/// The counts of detail::pool_stats, in ns where they are times; updated by a loop's caller (parallel loops:
/// one at a time, under the pool's m_busy; serial ones: any thread), so relaxed atomics.
struct Counts {
  std::atomic<std::uint64_t> parallel_loops{0}, serial_loops{0}, chunks{0}, caller_chunks{0},
      caller_alone_loops{0}, waits{0}, blocked_waits{0}, long_waits{0}, loop_ns{0}, wait_ns{0},
      max_wait_ns{0}, serial_ns{0}, solo_stretches{0}, light_loops{0}, light_ns{0};
};
Counts g_counts;

void count(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) {
  c.fetch_add(n, std::memory_order_relaxed);
}

std::uint64_t ns_since(std::chrono::steady_clock::time_point t) {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t).count());
}
#endif

/// How long an idle thread (a worker between loops, or the caller waiting for the workers' last chunks)
/// spins before it blocks. One sub-step runs many loops back to back with a little serial work between them;
/// a worker that blocked there would need a wake-up (some microseconds) per loop. Longer spins would take
/// time from other busy threads on the core, which is what OpenMP's spinning did.
constexpr std::chrono::microseconds kSpinTime{50};

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

/// Spins (with a pause instruction) until done() or kSpinTime has passed; true when done() held.
template <class Done>
bool spin_until(Done done) {
  const auto start = std::chrono::steady_clock::now();
  for (unsigned spins = 1;; ++spins) {
    if (done()) return true;
    cpu_relax();
    if (spins % 64 == 0 && std::chrono::steady_clock::now() - start > kSpinTime) return done();
  }
}

/// True on a thread that is running a loop's chunks (a pool thread, or a caller inside its loop): a loop
/// started there runs serially.
thread_local bool t_in_loop = false;

int cpu_count() {
#if defined(__linux__)
  cpu_set_t mask;
  if (sched_getaffinity(0, sizeof(mask), &mask) == 0) {
    const int n = CPU_COUNT(&mask);
    if (n > 0) return std::min(n, kMaxThreadCount);
  }
#endif
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : static_cast<int>(std::min<unsigned>(n, kMaxThreadCount));
}

/// OMP_NUM_THREADS's count (its first entry if it is a list), or 0 when it is unset or not such a count.
int omp_num_threads() {
  const char* env = std::getenv("OMP_NUM_THREADS");
  if (env == nullptr) return 0;
  char* end = nullptr;
  const long n = std::strtol(env, &end, 10);
  const bool whole = end != env && (*end == '\0' || *end == ',');
  return whole && n >= 1 && n <= kMaxThreadCount ? static_cast<int>(n) : 0;
}

int default_thread_count() {
  const int n = omp_num_threads();
  return n > 0 ? n : cpu_count();
}

/// The threads and the one loop they serve. A loop's caller holds m_busy for its whole loop; the job's
/// fields are written before its epoch is published in m_state and read by a worker only after it has
/// joined that epoch, and the caller waits for every joined worker to leave before the next job overwrites
/// them. A worker that wakes after the caller has closed the job (all chunks taken) does not join it, so a
/// thread that the scheduler keeps off its core never holds up the loop.
class Pool {
 public:
  static Pool& instance() {
    // Never destroyed: its threads are blocked when the process exits, and a destructor running while
    // another thread's loop is under way (a detached thread at exit) would have to wait for it.
    static Pool* pool = new Pool;
    return *pool;
  }

  /// Sets the thread count; a stretch of loops on the callers alone ends, and the next late wait starts a
  /// short one (a new count starts afresh, and the caller of set_thread_count(2) gets two threads).
  void set_wanted(int n) {
    m_wanted.store(n, std::memory_order_relaxed);
    m_forget_late.store(true, std::memory_order_relaxed);
    m_solo_until.store(0, std::memory_order_relaxed);
  }

  int wanted() const { return m_wanted.load(std::memory_order_relaxed); }

  void run(std::size_t n, std::size_t grain, int slots, detail::ChunkFunction fn, void* body) {
    assert(grain > 0);
    const std::size_t chunks = (n + grain - 1) / grain;
    if (chunks <= 1 || slots <= 1 || t_in_loop || m_wanted.load(std::memory_order_relaxed) <= 1 ||
        (grain == kLightChunk && n <= kLightSerial) || solo() || !m_busy.try_lock()) {
#if defined(DRENCH_POOL_STATS)
      const bool outer = !t_in_loop;
      const auto serial_start = std::chrono::steady_clock::now();
      run_serially(n, grain, chunks, fn, body);
      if (outer) {
        count(g_counts.serial_loops);
        count(g_counts.serial_ns, ns_since(serial_start));
      }
#else
      run_serially(n, grain, chunks, fn, body);
#endif
      return;
    }
    const std::lock_guard<std::mutex> busy(m_busy, std::adopt_lock);
#if defined(DRENCH_POOL_STATS)
    const auto loop_start = std::chrono::steady_clock::now();
#endif
    const int wanted = m_wanted.load(std::memory_order_relaxed);
    if (static_cast<int>(m_workers.size()) != wanted - 1) resize(wanted - 1);
    m_fn = fn;
    m_body = body;
    m_n = n;
    m_grain = grain;
    m_chunks = chunks;
    m_slots = slots;
    m_next.store(0, std::memory_order_relaxed);
    m_error = nullptr;
    m_failed.store(false, std::memory_order_relaxed);
    const std::uint64_t epoch = (m_state.load(std::memory_order_relaxed) >> kEpochShift) + 1;
    m_state.store(epoch << kEpochShift, std::memory_order_seq_cst);
    if (m_sleepers.load(std::memory_order_seq_cst) > 0) {
      const std::lock_guard<std::mutex> lock(m_sleep_mutex);
      m_wake.notify_all();
    }
    t_in_loop = true;
    const std::size_t taken = take_chunks(0);
    t_in_loop = false;
    const std::uint64_t closed = m_state.fetch_or(kClosed, std::memory_order_seq_cst) | kClosed;
#if defined(DRENCH_POOL_STATS)
    const auto wait_start = std::chrono::steady_clock::now();
    bool blocked = false;
    if ((closed & kJoinedMask) != 0) blocked = !wait_for_workers();
    const std::uint64_t waited = (closed & kJoinedMask) != 0 ? ns_since(wait_start) : 0;
    count(g_counts.parallel_loops);
    count(g_counts.chunks, chunks);
    count(g_counts.caller_chunks, taken);
    if (taken >= chunks) count(g_counts.caller_alone_loops);
    if ((closed & kJoinedMask) != 0) count(g_counts.waits);
    if (blocked) count(g_counts.blocked_waits);
    if (waited > 1000000) count(g_counts.long_waits);
    count(g_counts.wait_ns, waited);
    count(g_counts.loop_ns, ns_since(loop_start));
    if (grain == kLightChunk) {
      count(g_counts.light_loops);
      count(g_counts.light_ns, ns_since(loop_start));
    }
    if (waited > g_counts.max_wait_ns.load(std::memory_order_relaxed))
      g_counts.max_wait_ns.store(waited, std::memory_order_relaxed);
#else
    (void)taken;
    if ((closed & kJoinedMask) != 0) wait_for_workers();
#endif
    if (m_failed.load(std::memory_order_relaxed)) std::rethrow_exception(m_error);
  }

 private:
  static constexpr std::uint64_t kJoinedMask = 0xffff;  // workers inside the job (<= kMaxThreadCount)
  static constexpr std::uint64_t kClosed = 1u << 16;    // every chunk taken: no worker may join
  static constexpr int kEpochShift = 17;                // the job's number above

  static void run_serially(std::size_t n, std::size_t grain, std::size_t chunks, detail::ChunkFunction fn,
                           void* body) {
    const bool outer = t_in_loop;
    t_in_loop = true;
    try {
      for (std::size_t k = 0; k < chunks; ++k)
        fn(body, k * grain, std::min(n, (k + 1) * grain), 0);
    } catch (...) {
      t_in_loop = outer;
      throw;
    }
    t_in_loop = outer;
  }

  /// Runs chunks until none is left; returns how many it ran.
  std::size_t take_chunks(int slot) {
    for (std::size_t taken = 0;; ++taken) {
      const std::size_t k = m_next.fetch_add(1, std::memory_order_relaxed);
      if (k >= m_chunks) return taken;
      try {
        m_fn(m_body, k * m_grain, std::min(m_n, (k + 1) * m_grain), slot);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(m_error_mutex);
        if (!m_failed.load(std::memory_order_relaxed)) {
          m_error = std::current_exception();
          m_failed.store(true, std::memory_order_relaxed);
        }
        m_next.store(m_chunks, std::memory_order_relaxed);  // skip the chunks not yet taken
        return taken + 1;
      }
    }
  }

  /// True while the loops run on their callers alone (after a late wait, detail::LateWorkerPolicy); reads
  /// the clock only while a stretch is set.
  bool solo() {
    std::int64_t until = m_solo_until.load(std::memory_order_relaxed);
    if (until == 0) return false;
    if (std::chrono::steady_clock::now().time_since_epoch().count() < until) return true;
    m_solo_until.compare_exchange_strong(until, 0, std::memory_order_relaxed);  // not a newer stretch's
    return false;
  }

  /// Waits until every joined worker has left the job; false when it had to block. A late wait starts a
  /// stretch of loops on the callers alone (detail::LateWorkerPolicy). With m_busy held.
  bool wait_for_workers() {
    const auto all_left = [this] { return (m_state.load(std::memory_order_seq_cst) & kJoinedMask) == 0; };
    const auto start = std::chrono::steady_clock::now();
    if (spin_until(all_left)) return true;
    {
      std::unique_lock<std::mutex> lock(m_sleep_mutex);
      m_caller_waiting.store(true, std::memory_order_seq_cst);
      m_done.wait(lock, all_left);
      m_caller_waiting.store(false, std::memory_order_relaxed);
    }
    const auto now = std::chrono::steady_clock::now();
    if (m_forget_late.exchange(false, std::memory_order_relaxed)) m_late.reset();
    if (m_late.on_wait(now - start, now)) {
      m_solo_until.store(m_late.solo_until().time_since_epoch().count(), std::memory_order_relaxed);
#if defined(DRENCH_POOL_STATS)
      count(g_counts.solo_stretches);
#endif
    }
    return false;
  }

  /// A worker's life: wait for a job newer than `seen`, join it while it is open, take chunks, leave.
  void work(int index, std::uint64_t seen) {
    t_in_loop = true;
    for (;;) {
      const auto new_job = [&] {
        return (m_state.load(std::memory_order_seq_cst) >> kEpochShift) != seen ||
               m_stop.load(std::memory_order_relaxed);
      };
      if (!spin_until(new_job)) {
        std::unique_lock<std::mutex> lock(m_sleep_mutex);
        m_sleepers.fetch_add(1, std::memory_order_seq_cst);
        m_wake.wait(lock, new_job);
        m_sleepers.fetch_sub(1, std::memory_order_relaxed);
      }
      if (m_stop.load(std::memory_order_relaxed)) return;
      std::uint64_t state = m_state.load(std::memory_order_acquire);
      seen = state >> kEpochShift;
      bool joined = false;
      while ((state & kClosed) == 0 && (state >> kEpochShift) == seen) {
        if (m_state.compare_exchange_weak(state, state + 1, std::memory_order_seq_cst)) {
          joined = true;
          break;
        }
      }
      if (!joined) continue;
      if (index < m_slots) take_chunks(index);
      const std::uint64_t left = m_state.fetch_sub(1, std::memory_order_seq_cst) - 1;
      if ((left & kJoinedMask) == 0 && (left & kClosed) != 0 &&
          m_caller_waiting.load(std::memory_order_seq_cst)) {
        const std::lock_guard<std::mutex> lock(m_sleep_mutex);
        m_done.notify_all();
      }
    }
  }

  /// Stops the threads and starts `workers` new ones; with m_busy held, so no job is under way.
  void resize(int workers) {
    {
      const std::lock_guard<std::mutex> lock(m_sleep_mutex);
      m_stop.store(true, std::memory_order_relaxed);
      m_wake.notify_all();
    }
    for (std::thread& t : m_workers)
      t.join();
    m_workers.clear();
    m_stop.store(false, std::memory_order_relaxed);
    // The epoch before the caller publishes its job: a thread that starts late still joins that job.
    const std::uint64_t seen = m_state.load(std::memory_order_relaxed) >> kEpochShift;
    for (int i = 1; i <= workers; ++i)
      m_workers.emplace_back([this, i, seen] { work(i, seen); });
  }

  std::atomic<int> m_wanted{default_thread_count()};
  // The stretch of loops on the callers alone: its end in steady_clock's ticks (0: none) read by every
  // caller; its length and end, written under m_busy.
  std::atomic<std::int64_t> m_solo_until{0};
  detail::LateWorkerPolicy m_late;         // under m_busy
  std::atomic<bool> m_forget_late{false};  // set_thread_count was called: reset m_late
  std::mutex m_busy;                       // held by the caller whose loop the workers serve
  std::vector<std::thread> m_workers;
  std::atomic<bool> m_stop{false};

  // The job, written by its caller before it publishes the epoch.
  detail::ChunkFunction m_fn = nullptr;
  void* m_body = nullptr;
  std::size_t m_n = 0, m_grain = 1, m_chunks = 0;
  int m_slots = 1;
  alignas(64) std::atomic<std::size_t> m_next{0};     // the next chunk to take
  alignas(64) std::atomic<std::uint64_t> m_state{0};  // epoch << kEpochShift | kClosed | workers joined
  std::atomic<bool> m_failed{false};
  std::exception_ptr m_error;
  std::mutex m_error_mutex;

  // Blocking: workers wait on m_wake for a new epoch, the caller on m_done for the joined workers to leave.
  std::mutex m_sleep_mutex;
  std::condition_variable m_wake, m_done;
  std::atomic<int> m_sleepers{0};
  std::atomic<bool> m_caller_waiting{false};
};

}  // namespace

void set_thread_count(int n) {
  if (n < 1 || n > kMaxThreadCount)
    throw Error("thread count must be in [1, " + std::to_string(kMaxThreadCount) + "], got " +
                std::to_string(n));
  Pool::instance().set_wanted(n);
}

int thread_count() {
  return Pool::instance().wanted();
}

std::string omp_num_threads_problem() {
  const char* env = std::getenv("OMP_NUM_THREADS");
  if (env == nullptr || omp_num_threads() > 0) return "";
  std::string value(env);
  if (value.size() > 40) value = value.substr(0, 40) + "...";
  return "OMP_NUM_THREADS='" + value + "' is not a whole number in [1, " + std::to_string(kMaxThreadCount) +
         "]";
}

namespace detail {

void run_chunks(std::size_t n, std::size_t grain, int slots, ChunkFunction fn, void* body) {
  Pool::instance().run(n, grain, slots, fn, body);
}

PoolStats pool_stats() {
  PoolStats stats;
#if defined(DRENCH_POOL_STATS)
  const auto get = [](const std::atomic<std::uint64_t>& c) { return c.load(std::memory_order_relaxed); };
  stats.counted = true;
  stats.parallel_loops = get(g_counts.parallel_loops);
  stats.serial_loops = get(g_counts.serial_loops);
  stats.chunks = get(g_counts.chunks);
  stats.caller_chunks = get(g_counts.caller_chunks);
  stats.caller_alone_loops = get(g_counts.caller_alone_loops);
  stats.waits = get(g_counts.waits);
  stats.blocked_waits = get(g_counts.blocked_waits);
  stats.long_waits = get(g_counts.long_waits);
  stats.loop_seconds = 1e-9 * static_cast<double>(get(g_counts.loop_ns));
  stats.wait_seconds = 1e-9 * static_cast<double>(get(g_counts.wait_ns));
  stats.max_wait_seconds = 1e-9 * static_cast<double>(get(g_counts.max_wait_ns));
  stats.serial_seconds = 1e-9 * static_cast<double>(get(g_counts.serial_ns));
  stats.solo_stretches = get(g_counts.solo_stretches);
  stats.light_loops = get(g_counts.light_loops);
  stats.light_seconds = 1e-9 * static_cast<double>(get(g_counts.light_ns));
#endif
  return stats;
}

void reset_pool_stats() {
#if defined(DRENCH_POOL_STATS)
  for (std::atomic<std::uint64_t>* c :
       {&g_counts.parallel_loops, &g_counts.serial_loops, &g_counts.chunks, &g_counts.caller_chunks,
        &g_counts.caller_alone_loops, &g_counts.waits, &g_counts.blocked_waits, &g_counts.long_waits,
        &g_counts.loop_ns, &g_counts.wait_ns, &g_counts.max_wait_ns, &g_counts.serial_ns,
        &g_counts.solo_stretches, &g_counts.light_loops, &g_counts.light_ns})
    c->store(0, std::memory_order_relaxed);
#endif
}

}  // namespace detail

}  // namespace drench
