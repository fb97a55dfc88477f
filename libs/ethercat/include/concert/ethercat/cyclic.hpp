#pragma once
// The master's cyclic exchange at a fixed period (1 kHz for the robot): one LRW per cycle on an
// absolute-time schedule (clock_nanosleep, TIMER_ABSTIME), with what a cycle watchdog needs:
// frames lost, working counters short of the expected one, and the period's spread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "concert/ethercat/master.hpp"

namespace concert::ethercat {

struct CycleParams {
  std::chrono::nanoseconds period{1'000'000};
  std::chrono::nanoseconds duration{1'000'000'000};  ///< 0: until stop
};

/// What a run of cycles measured.
struct CycleStats {
  uint64_t cycles = 0;
  uint64_t lost = 0;         ///< frames that did not come back within the frame timeout
  uint64_t short_wkc = 0;    ///< came back with a working counter other than the expected one
  uint16_t expected_wkc = 0;
  double period_mean_us = 0;
  double period_p50_us = 0;
  double period_p99_us = 0;
  double period_max_us = 0;
  double jitter_p99_us = 0;  ///< |period - nominal|, 99th percentile
  double cpu_per_cycle_us = 0;  ///< the master thread's CPU time per cycle
  /// One line: "60000 cycles at 1000 us: period p50 1000.1 us, p99 ..., lost 0, ...".
  std::string summary() const;
};

/// Called every cycle after the inputs came back (or did not), before the next outputs go: fill
/// outputs, read inputs, watch the result. Returns false to end the run.
using CycleBody = std::function<bool(ProcessImage& image, const CycleResult& result)>;

/// Runs cycles on `image` (mapped, the ring in OP) every `params.period` for `params.duration`
/// or until `stop`. Allocates nothing per cycle besides what `body` does.
CycleStats run_cycles(Master& master, ProcessImage& image, const CycleParams& params,
                      const std::atomic<bool>& stop, const CycleBody& body = {});

}  // namespace concert::ethercat
