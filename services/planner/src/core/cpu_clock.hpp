// The clock the planner's time budgets are measured in: the calling thread's CPU time.
#pragma once

#include <time.h>

#include <chrono>

namespace concert::planner::detail {

// A std::chrono clock over the calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID).
//
// The planner's budgets (planning_time, path_attempt_time, nspg_time) are CPU seconds of the
// planning thread, not wall seconds: with wall-clock budgets a plan that fits on an idle
// machine runs out of time while the simulator's cameras hold both cores (the demo's drilling
// approach then fails about one time in four), so the same request gives different answers
// under load. CPU time makes the search's reach depend on the request and the seed only. Iteration
// counts would do that too, but seconds keep the configuration meaningful to a user and the
// same budget covers the posture search, sampling and collision checking alike.
//
// Time points are only comparable within one thread; every plan runs in one thread (OMPL's
// RRT-Connect evaluates its termination condition in the thread that calls solve()).
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

// CPU seconds of the calling thread since `t0`.
inline double cpu_seconds_since(ThreadCpuClock::time_point t0) {
  return std::chrono::duration<double>(ThreadCpuClock::now() - t0).count();
}

}  // namespace concert::planner::detail
