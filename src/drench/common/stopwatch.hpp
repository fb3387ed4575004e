#pragma once
/// Wall-clock timing of pipeline stages, reported as the summary's `timings_s`.

#include <chrono>

namespace drench {

/// Adds the wall time of its own lifetime to a seconds accumulator.
class ScopedTimer {
 public:
  explicit ScopedTimer(double& seconds) : m_seconds(seconds), m_start(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() {
    m_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
  }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;

 private:
  double& m_seconds;
  std::chrono::steady_clock::time_point m_start;
};

}  // namespace drench
