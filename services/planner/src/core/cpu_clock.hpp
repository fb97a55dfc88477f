// The clock the planner's time budgets are measured in: the calling thread's CPU time.
#pragma once

#include "concert/common/thread_cpu_clock.hpp"

namespace concert::planner::detail {

// The planner's budgets (planning_time, path_attempt_time, nspg_time) are CPU seconds of the
// planning thread, not wall seconds: with wall-clock budgets a plan that fits on an idle
// machine runs out of time while the simulator's cameras hold both cores (the demo's drilling
// approach then fails about one time in four), so the same request gives different answers
// under load. CPU time makes the search's reach depend on the request and the seed only. Iteration
// counts would do that too, but seconds keep the configuration meaningful to a user and the
// same budget covers the posture search, sampling and collision checking alike. Every plan runs
// in one thread (OMPL's RRT-Connect evaluates its termination condition in the thread that calls
// solve()).
using concert::cpu_seconds_since;
using concert::ThreadCpuClock;

}  // namespace concert::planner::detail
