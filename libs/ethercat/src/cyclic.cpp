#include "concert/ethercat/cyclic.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "concert/common/thread_cpu_clock.hpp"

namespace concert::ethercat {
namespace {

timespec add(timespec t, std::chrono::nanoseconds d) {
  const int64_t ns = static_cast<int64_t>(t.tv_nsec) + d.count();
  t.tv_sec += static_cast<time_t>(ns / 1'000'000'000);
  t.tv_nsec = static_cast<long>(ns % 1'000'000'000);
  return t;
}

int64_t to_ns(const timespec& t) { return static_cast<int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec; }

double percentile(std::vector<double>& v, double p) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size() - 1), std::ceil(p * static_cast<double>(v.size())) - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

std::string CycleStats::summary() const {
  char text[320];
  std::snprintf(text, sizeof text,
                "%llu cycles: period mean %.1f us, p50 %.1f us, p99 %.1f us, max %.1f us; jitter p99 "
                "%.1f us; %llu frames lost, %llu working counters short of %u; master CPU %.1f us per cycle",
                static_cast<unsigned long long>(cycles), period_mean_us, period_p50_us, period_p99_us,
                period_max_us, jitter_p99_us, static_cast<unsigned long long>(lost),
                static_cast<unsigned long long>(short_wkc), expected_wkc, cpu_per_cycle_us);
  return text;
}

CycleStats run_cycles(Master& master, ProcessImage& image, const CycleParams& params,
                      const std::atomic<bool>& stop, const CycleBody& body) {
  CycleStats stats;
  stats.expected_wkc = image.expected_wkc;
  const int64_t nominal = params.period.count();
  const uint64_t planned = params.duration.count() > 0
                               ? static_cast<uint64_t>(params.duration.count() / nominal)
                               : 0;
  // Periods kept in a buffer sized once: a run "until stop" keeps the last hour's at most.
  const std::size_t keep = planned ? planned : static_cast<std::size_t>(3'600'000'000'000LL / nominal);
  std::vector<double> periods;
  periods.reserve(std::min<std::size_t>(keep, 4'000'000));
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  int64_t last_start = -1;
  const auto cpu0 = ThreadCpuClock::now();
  while (!stop.load(std::memory_order_relaxed) && (planned == 0 || stats.cycles < planned)) {
    next = add(next, params.period);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
      if (stop.load(std::memory_order_relaxed)) break;
    }
    timespec started{};
    clock_gettime(CLOCK_MONOTONIC, &started);
    const int64_t now = to_ns(started);
    if (last_start >= 0 && periods.size() < periods.capacity()) {
      periods.push_back(static_cast<double>(now - last_start) / 1000.0);
    }
    last_start = now;
    const CycleResult r = master.cycle(image);
    ++stats.cycles;
    if (!r.returned) {
      ++stats.lost;
    } else if (r.wkc != image.expected_wkc) {
      ++stats.short_wkc;
    }
    if (body && !body(image, r)) break;
    // Behind by more than a period (the machine was busy): start again from now rather than
    // sending a burst of late frames.
    timespec after{};
    clock_gettime(CLOCK_MONOTONIC, &after);
    if (to_ns(after) > to_ns(next) + nominal) next = after;
  }
  const double cpu_us = std::chrono::duration<double, std::micro>(ThreadCpuClock::now() - cpu0).count();
  stats.cpu_per_cycle_us = stats.cycles ? cpu_us / static_cast<double>(stats.cycles) : 0;
  if (!periods.empty()) {
    double sum = 0;
    for (const double p : periods) sum += p;
    stats.period_mean_us = sum / static_cast<double>(periods.size());
    stats.period_max_us = *std::max_element(periods.begin(), periods.end());
    std::vector<double> jitter(periods.size());
    for (std::size_t i = 0; i < periods.size(); ++i) {
      jitter[i] = std::abs(periods[i] - static_cast<double>(nominal) / 1000.0);
    }
    stats.period_p50_us = percentile(periods, 0.50);
    stats.period_p99_us = percentile(periods, 0.99);
    stats.jitter_p99_us = percentile(jitter, 0.99);
  }
  return stats;
}

}  // namespace concert::ethercat
