#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace concert::robot {

/// Parameters of the control loop.
struct LoopParams {
  double period{0.001};   ///< [s] (1 kHz)
  bool real_time{true};   ///< false: as fast as possible (simulated time only, for tests)
  bool record_periods{false};  ///< keep every measured wall-clock period (benchmarks)
  /// Real-time mode: sleep until this long before each deadline, then spin [s]. 0.0002 cuts
  /// wake-up jitter on a non-RT kernel to microseconds for 20 % of a core; off by default.
  double spin_time{0.0};
  /// SCHED_FIFO priority for the thread calling run() (1..99); 0 leaves the scheduler alone.
  int fifo_priority{0};
};

/// Wall-clock period statistics of a loop run [s].
struct LoopStats {
  std::uint64_t cycles{0};
  std::uint64_t overruns{0};   ///< cycles whose tick took longer than the period
  double mean_period{0.0};
  double max_period{0.0};
  double p99_period{0.0};      ///< only with record_periods
  double mean_jitter{0.0};     ///< mean |period - nominal| (only with record_periods)
  double p99_jitter{0.0};      ///< (only with record_periods)
  double wall_time{0.0};       ///< wall-clock duration of the run
};

/// A running loop's counts so far, readable from any thread.
struct LoopProgress {
  std::uint64_t cycles{0};
  std::uint64_t overruns{0};  ///< cycles whose tick took longer than the wall-clock period
};

/// What simulated time did over a stretch of wall time: each cycle steps the simulation by one
/// period, so no cycle is late in simulated time; a loaded machine slows simulated time instead.
/// "simulated time at 0.93 x real time over the last 10.0 s (9300 cycles, 12 over their 1.0 ms
/// wall-clock period; each steps the simulation once: none is late in simulated time)".
std::string simulated_time_line(const LoopProgress& from, const LoopProgress& to, double wall_seconds,
                                double period);

/// Fixed-rate loop: calls `tick` every period, on deadlines period apart (absolute, so
/// no drift) in real-time mode, or back-to-back otherwise. The tick advances simulated time.
class Loop {
 public:
  Loop(LoopParams params, std::function<void()> tick);

  /// Runs `cycles` ticks (or until stop()). Returns the statistics of this run.
  LoopStats run(std::uint64_t cycles);
  /// Runs until stop() is called from another thread or a signal handler.
  LoopStats run_forever();
  /// True if the last run() got the requested SCHED_FIFO priority.
  [[nodiscard]] bool fifo_applied() const { return fifo_applied_; }
  /// Asks a running loop to return after the current tick.
  void stop() { stop_.store(true); }
  /// The running (or the last) run's cycles and overruns so far (any thread).
  [[nodiscard]] LoopProgress progress() const {
    return {cycles_.load(std::memory_order_relaxed), overruns_.load(std::memory_order_relaxed)};
  }

 private:
  LoopParams params_;
  std::function<void()> tick_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> cycles_{0};
  std::atomic<std::uint64_t> overruns_{0};
  bool fifo_applied_{false};
};

}  // namespace concert::robot
