#pragma once
/// The progress line of the commands that work through a run's frames (`drench reconstruct`, `drench
/// render`): one self-overwriting line on a terminal, nothing in a log or a pipe.

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>

namespace drench {

/// `frame 3 / 31   2.10 frames/s   ETA 13 s` on stderr, at most five times a second; silent unless
/// `wanted` and stderr is a terminal. The destructor ends the line, so that the next output starts clean.
class ProgressLine {
 public:
  /// @param frames  how many frames the command will do, > 0
  ProgressLine(bool wanted, std::size_t frames)
      : m_enabled(wanted && ::isatty(STDERR_FILENO)), m_frames(frames) {}
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  /// @param done  frames finished so far
  /// @param wall  seconds since the command started (unit: s)
  void update(std::size_t done, double wall) {
    if (!m_enabled || wall - m_last < 0.2) return;
    m_last = wall;
    const double rate = done / std::max(wall, 1e-9);
    std::fprintf(stderr, "\r  frame %zu / %zu   %.2f frames/s   ETA %.0f s   ", done, m_frames, rate,
                 (m_frames - done) / std::max(rate, 1e-9));
    std::fflush(stderr);
  }
  ~ProgressLine() {
    if (m_enabled && m_last > 0) std::fprintf(stderr, "\n");
  }

 private:
  bool m_enabled;
  std::size_t m_frames;
  double m_last = 0;
};

}  // namespace drench
