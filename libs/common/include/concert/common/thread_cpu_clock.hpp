#pragma once
// The clock of time budgets that decide an outcome: the calling thread's CPU time.
//
// A search given wall seconds reaches less while other processes hold the cores, so the same
// request gives different answers on a loaded machine. Given CPU seconds of its own thread it
// reaches as far whatever runs beside it: a loaded machine makes it slower, never different.
// Time points are only comparable within one thread.

#include <time.h>

#include <chrono>

namespace concert {

/// A std::chrono clock over the calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID).
struct ThreadCpuClock {
  using duration = std::chrono::nanoseconds;
  using rep = duration::rep;
  using period = duration::period;
  using time_point = std::chrono::time_point<ThreadCpuClock>;
  static constexpr bool is_steady = true;

  static time_point now() noexcept {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return time_point(duration(static_cast<rep>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec));
  }
};

/// CPU seconds of the calling thread since `t0`.
inline double cpu_seconds_since(ThreadCpuClock::time_point t0) {
  return std::chrono::duration<double>(ThreadCpuClock::now() - t0).count();
}

}  // namespace concert
