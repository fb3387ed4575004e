// drench's parallel loops (common/parallel.hpp): the thread count decides how many threads run chunks, bad
// counts are refused naming the value, every index is visited once, nested and concurrent loops complete,
// an exception in a body reaches the caller, reductions fold in chunk order, light loops up to kLightSerial
// stay on the caller, and the rule that runs loops on their callers alone after a late worker.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <drench/common/error.hpp>
#include <drench/common/parallel.hpp>

namespace drench {
namespace {

/// Sets the thread count for one test and restores the previous one.
class ThreadCountScope {
 public:
  explicit ThreadCountScope(int n) : m_saved(thread_count()) { set_thread_count(n); }
  ~ThreadCountScope() { set_thread_count(m_saved); }
  ThreadCountScope(const ThreadCountScope&) = delete;
  ThreadCountScope& operator=(const ThreadCountScope&) = delete;

 private:
  int m_saved;
};

/// The distinct threads that ran chunks of a loop over `chunks` chunks whose first chunk waits (up to
/// `patience`) until a chunk has run on another thread: with two threads the other thread must take a chunk
/// while the first waits, however loaded the machine is; with one it never can, and the wait times out.
std::set<std::thread::id> threads_running_chunks(std::size_t chunks, std::chrono::milliseconds patience) {
  std::mutex mutex;
  std::condition_variable arrived;
  std::set<std::thread::id> ids;
  parallel_for(chunks, 1, [&](std::size_t begin, std::size_t /*end*/) {
    std::unique_lock<std::mutex> lock(mutex);
    ids.insert(std::this_thread::get_id());
    arrived.notify_all();
    if (begin == 0) arrived.wait_for(lock, patience, [&] { return ids.size() > 1; });
  });
  return ids;
}

TEST(ThreadPool, OneThreadRunsEveryChunkOnTheCaller) {
  const ThreadCountScope scope(1);
  const std::set<std::thread::id> ids = threads_running_chunks(64, std::chrono::milliseconds(50));
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(*ids.begin(), std::this_thread::get_id());
}

TEST(ThreadPool, TwoThreadsRunChunksOnTwoThreads) {
  const ThreadCountScope scope(2);
  // 10 s: the second thread needs only to be scheduled once, even on a machine busy with other builds.
  const std::set<std::thread::id> ids = threads_running_chunks(64, std::chrono::seconds(10));
  EXPECT_EQ(ids.size(), 2u);
  EXPECT_EQ(ids.count(std::this_thread::get_id()), 1u) << "the caller takes part in the loop";
}

TEST(ThreadPool, ThreadCountIsWhatWasSet) {
  const ThreadCountScope scope(3);
  EXPECT_EQ(thread_count(), 3);
  set_thread_count(1);
  EXPECT_EQ(thread_count(), 1);
  set_thread_count(kMaxThreadCount);
  EXPECT_EQ(thread_count(), kMaxThreadCount);
}

TEST(ThreadPool, RefusesThreadCountsOutsideOneToMaxNamingTheValue) {
  const int before = thread_count();
  for (const int bad : {0, -1, 100000}) {
    try {
      set_thread_count(bad);
      ADD_FAILURE() << "set_thread_count(" << bad << ") did not throw";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()), "thread count must be in [1, 1024], got " + std::to_string(bad));
    }
  }
  EXPECT_EQ(thread_count(), before) << "a refused value leaves the count alone";
}

TEST(ThreadPool, VisitsEveryIndexExactlyOnceForAwkwardSizes) {
  for (const int threads : {1, 2, 3}) {
    const ThreadCountScope scope(threads);
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, kParticleChunk - 1, kParticleChunk,
                                kParticleChunk + 1, 7 * kParticleChunk + 3}) {
      std::vector<std::atomic<int>> visits(n);
      for_each_chunk(n, [&](std::size_t begin, std::size_t end) {
        EXPECT_LT(begin, end);
        EXPECT_LE(end - begin, kParticleChunk);
        EXPECT_EQ(begin % kParticleChunk, 0u) << "chunks start at multiples of kParticleChunk";
        for (std::size_t i = begin; i < end; ++i)
          visits[i].fetch_add(1);
      });
      for (std::size_t i = 0; i < n; ++i)
        ASSERT_EQ(visits[i].load(), 1) << "index " << i << " of " << n << ", " << threads << " threads";
    }
  }
}

TEST(ThreadPool, NestedLoopsCompleteAndVisitEveryPair) {
  const ThreadCountScope scope(2);
  constexpr std::size_t kOuter = 40, kInner = 1000;
  std::vector<std::atomic<int>> visits(kOuter * kInner);
  parallel_for(kOuter, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t o = begin; o < end; ++o) {
      parallel_for(kInner, 10, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i)
          visits[o * kInner + i].fetch_add(1);
      });
    }
  });
  for (std::size_t k = 0; k < visits.size(); ++k)
    ASSERT_EQ(visits[k].load(), 1) << "pair " << k;
}

TEST(ThreadPool, LoopsFromTwoUserThreadsAtOnceComplete) {
  const ThreadCountScope scope(2);
  constexpr std::size_t kN = 100000;
  std::vector<std::atomic<int>> a(kN), b(kN);
  const auto fill = [](std::vector<std::atomic<int>>& v) {
    for (int round = 0; round < 50; ++round) {
      parallel_for(v.size(), 512, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
          v[i].fetch_add(1);
      });
    }
  };
  std::thread other([&] { fill(b); });
  fill(a);
  other.join();
  for (std::size_t i = 0; i < kN; ++i) {
    ASSERT_EQ(a[i].load(), 50) << "index " << i;
    ASSERT_EQ(b[i].load(), 50) << "index " << i;
  }
}

TEST(ThreadPool, ExceptionInABodyReachesTheCallerAndThePoolStillWorks) {
  for (const int threads : {1, 2}) {
    const ThreadCountScope scope(threads);
    EXPECT_THROW(
        {
          parallel_for(100 * kParticleChunk, kParticleChunk, [&](std::size_t begin, std::size_t) {
            if (begin == 37 * kParticleChunk) throw std::runtime_error("chunk 37");
          });
        },
        std::runtime_error);
    std::atomic<std::size_t> sum{0};
    parallel_for(1000, 10, [&](std::size_t begin, std::size_t end) { sum += end - begin; });
    EXPECT_EQ(sum.load(), 1000u) << threads << " threads";
  }
}

TEST(ThreadPool, ReductionFoldsInChunkOrderForAnyThreadCount) {
  // A floating-point sum whose rounding depends on the order: the same bits for 1, 2 and 3 threads, and
  // exactly the serial fold over the chunks.
  constexpr std::size_t kN = 50000, kGrain = 333;
  std::vector<double> x(kN);
  for (std::size_t i = 0; i < kN; ++i)
    x[i] = 1.0 / static_cast<double>(i + 1) * ((i % 7 == 0) ? 1e8 : 1.0);
  const auto chunk_sum = [&](std::size_t begin, std::size_t end) {
    double s = 0.0;
    for (std::size_t i = begin; i < end; ++i)
      s += x[i];
    return s;
  };
  double expected = 0.0;
  for (std::size_t begin = 0; begin < kN; begin += kGrain)
    expected += chunk_sum(begin, std::min(kN, begin + kGrain));
  for (const int threads : {1, 2, 3}) {
    const ThreadCountScope scope(threads);
    const double got = parallel_reduce(kN, kGrain, 0.0, chunk_sum, [](double a, double b) { return a + b; });
    EXPECT_EQ(got, expected) << threads << " threads";
  }
  EXPECT_EQ(parallel_reduce(0, kGrain, 5.0, chunk_sum, [](double a, double b) { return a + b; }), 5.0);
}

TEST(ThreadPool, SlotsStayBelowTheGivenBound) {
  const ThreadCountScope scope(3);
  std::atomic<int> highest{-1};
  parallel_for_slots(64 * kParticleChunk, kParticleChunk, 2, [&](std::size_t, std::size_t, int slot) {
    int seen = highest.load();
    while (slot > seen && !highest.compare_exchange_weak(seen, slot)) {
    }
  });
  EXPECT_GE(highest.load(), 0);
  EXPECT_LT(highest.load(), 2);
}

TEST(ThreadPool, LightLoopsUpToTheThresholdRunOnTheCallerAlone) {
  const ThreadCountScope scope(2);
  // Each chunk's first element waits (up to 2 s) for a chunk on another thread: a light loop at the
  // threshold never gets one; a larger one gets its worker, however loaded the machine is.
  const auto threads_of = [](std::size_t n, std::chrono::milliseconds patience) {
    std::mutex mutex;
    std::condition_variable arrived;
    std::set<std::thread::id> ids;
    parallel_for(n, kLightChunk, [&](std::size_t begin, std::size_t) {
      std::unique_lock<std::mutex> lock(mutex);
      ids.insert(std::this_thread::get_id());
      arrived.notify_all();
      if (begin == 0) arrived.wait_for(lock, patience, [&] { return ids.size() > 1; });
    });
    return ids.size();
  };
  EXPECT_EQ(threads_of(kLightSerial, std::chrono::milliseconds(20)), 1u);
  EXPECT_EQ(threads_of(kLightSerial + kLightChunk, std::chrono::seconds(10)), 2u);
}

using Clock = detail::LateWorkerPolicy::Clock;
using Policy = detail::LateWorkerPolicy;

TEST(LateWorkerPolicy, AWaitWithinTheLimitStartsNoStretch) {
  Policy policy;
  const Clock::time_point now = Clock::time_point{} + std::chrono::seconds(10);
  EXPECT_FALSE(policy.on_wait(Policy::kLateWait, now));
  EXPECT_EQ(policy.solo_until(), Clock::time_point{});
}

TEST(LateWorkerPolicy, ALateWaitStartsTheShortestStretch) {
  Policy policy;
  const Clock::time_point now = Clock::time_point{} + std::chrono::seconds(10);
  EXPECT_TRUE(policy.on_wait(Policy::kLateWait + std::chrono::microseconds(1), now));
  EXPECT_EQ(policy.solo_until(), now + Policy::kMinSolo);
}

TEST(LateWorkerPolicy, LateWaitsRightAfterAStretchDoubleItUpToTheLongest) {
  Policy policy;
  Clock::time_point now = Clock::time_point{} + std::chrono::seconds(10);
  const Clock::duration late = std::chrono::milliseconds(2);
  ASSERT_TRUE(policy.on_wait(late, now));
  Clock::duration expected = Policy::kMinSolo;
  for (int k = 0; k < 10; ++k) {
    // The first parallel loop after the stretch is late again (a lasting busy thread).
    now = policy.solo_until() + std::chrono::microseconds(100);
    ASSERT_TRUE(policy.on_wait(late, now));
    expected = std::min<Clock::duration>(2 * expected, Policy::kMaxSolo);
    EXPECT_EQ(policy.solo_until() - now, expected) << "stretch " << k + 1;
  }
  EXPECT_EQ(policy.solo_until() - now, Policy::kMaxSolo);
}

TEST(LateWorkerPolicy, ALateWaitLongAfterTheLastStretchStartsAShortOne) {
  Policy policy;
  Clock::time_point now = Clock::time_point{} + std::chrono::seconds(10);
  const Clock::duration late = std::chrono::milliseconds(2);
  Clock::duration last = Clock::duration::zero();
  for (int k = 0; k < 4; ++k) {
    ASSERT_TRUE(policy.on_wait(late, now));
    last = policy.solo_until() - now;
    now = policy.solo_until() + std::chrono::microseconds(100);
  }
  ASSERT_EQ(last, 8 * Policy::kMinSolo);
  // The busy threads left: a late wait a second later is a passing load.
  now += std::chrono::seconds(1);
  ASSERT_TRUE(policy.on_wait(late, now));
  EXPECT_EQ(policy.solo_until() - now, Policy::kMinSolo);
  policy.reset();
  EXPECT_EQ(policy.solo_until(), Clock::time_point{});
}

}  // namespace
}  // namespace drench
