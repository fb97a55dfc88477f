#include "robot/loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <thread>

#include <pthread.h>
#include <sched.h>

namespace concert::robot {

Loop::Loop(LoopParams params, std::function<void()> tick) : params_(params), tick_(std::move(tick)) {
  if (params_.period <= 0.0) {
    throw std::invalid_argument("loop period must be positive");
  }
}

std::string simulated_time_line(const LoopProgress& from, const LoopProgress& to, double wall_seconds,
                                double period) {
  const std::uint64_t cycles = to.cycles - from.cycles;
  const std::uint64_t over = to.overruns - from.overruns;
  const double factor = wall_seconds > 0.0 ? static_cast<double>(cycles) * period / wall_seconds : 0.0;
  char line[256];
  std::snprintf(line, sizeof line,
                "simulated time at %.2f x real time over the last %.1f s (%llu cycles, %llu over their "
                "%.1f ms wall-clock period; each steps the simulation once: none is late in simulated time)",
                factor, wall_seconds, static_cast<unsigned long long>(cycles),
                static_cast<unsigned long long>(over), period * 1e3);
  return line;
}

LoopStats Loop::run_forever() { return run(std::numeric_limits<std::uint64_t>::max()); }

LoopStats Loop::run(std::uint64_t cycles) {
  using Clock = std::chrono::steady_clock;
  stop_.store(false);
  cycles_.store(0, std::memory_order_relaxed);
  overruns_.store(0, std::memory_order_relaxed);
  fifo_applied_ = false;
  int old_policy = SCHED_OTHER;
  sched_param old_param{};
  pthread_getschedparam(pthread_self(), &old_policy, &old_param);
  if (params_.real_time && params_.fifo_priority > 0) {
    sched_param sp{};
    sp.sched_priority = params_.fifo_priority;
    fifo_applied_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
  }
  const auto spin = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(params_.spin_time));
  LoopStats stats;
  std::vector<double> periods;
  if (params_.record_periods && cycles < (1u << 26)) {
    periods.reserve(static_cast<std::size_t>(cycles));
  }
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(params_.period));
  const auto start = Clock::now();
  auto deadline = start;
  auto last = start;
  double sum = 0.0;
  for (std::uint64_t k = 0; k < cycles && !stop_.load(std::memory_order_relaxed); ++k) {
    if (params_.real_time) {
      std::this_thread::sleep_until(deadline - spin);
      while (Clock::now() < deadline) {
      }
    }
    const auto now = Clock::now();
    if (k > 0) {
      const double p = std::chrono::duration<double>(now - last).count();
      sum += p;
      stats.max_period = std::max(stats.max_period, p);
      if (params_.record_periods) {
        periods.push_back(p);
      }
    }
    last = now;
    tick_();
    cycles_.store(++stats.cycles, std::memory_order_relaxed);
    deadline += period;
    if (params_.real_time && Clock::now() > deadline) {
      overruns_.store(++stats.overruns, std::memory_order_relaxed);
      deadline = Clock::now();  // do not try to catch up with a burst of ticks
    }
  }
  stats.wall_time = std::chrono::duration<double>(Clock::now() - start).count();
  if (fifo_applied_) {
    pthread_setschedparam(pthread_self(), old_policy, &old_param);
  }
  if (stats.cycles > 1) {
    stats.mean_period = sum / static_cast<double>(stats.cycles - 1);
  }
  if (!periods.empty()) {
    std::vector<double> jitter(periods.size());
    double jsum = 0.0;
    for (std::size_t i = 0; i < periods.size(); ++i) {
      jitter[i] = std::abs(periods[i] - params_.period);
      jsum += jitter[i];
    }
    stats.mean_jitter = jsum / static_cast<double>(jitter.size());
    const auto idx = static_cast<std::size_t>(0.99 * static_cast<double>(periods.size() - 1));
    std::nth_element(periods.begin(), periods.begin() + static_cast<std::ptrdiff_t>(idx), periods.end());
    stats.p99_period = periods[idx];
    std::nth_element(jitter.begin(), jitter.begin() + static_cast<std::ptrdiff_t>(idx), jitter.end());
    stats.p99_jitter = jitter[idx];
  }
  return stats;
}

}  // namespace concert::robot
