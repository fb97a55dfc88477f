#include "robot/loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <iostream>
#include <thread>

namespace concert::robot {
namespace {

TEST(Loop, RunsTheRequestedTicksAsFastAsPossible) {
  int ticks = 0;
  Loop loop({0.001, false, true}, [&] { ++ticks; });
  const LoopStats stats = loop.run(500);
  EXPECT_EQ(ticks, 500);
  EXPECT_EQ(stats.cycles, 500u);
  // Reported, not asserted (no wall-clock bounds in tests): the speed of the loop without
  // real time is shown by the benchmarks (bench_robot); 500 ms here would mean it slept.
  std::cout << "500 ticks without real time: " << stats.wall_time * 1e3 << " ms of wall time\n";
}

TEST(Loop, RealTimeKeepsThePeriodOnAverage) {
  int ticks = 0;
  Loop loop({0.002, true, true}, [&] { ++ticks; });
  const LoopStats stats = loop.run(100);
  EXPECT_EQ(ticks, 100);
  // Absolute deadlines: 100 ticks take at least 99 periods, whatever the machine load.
  EXPECT_GE(stats.wall_time, 99 * 0.002 * 0.999);
  EXPECT_GT(stats.mean_period, 0.0);
  // The recorded periods' statistics are consistent (a ratio of p99 to mean depends on the load:
  // one stall of the machine raises the mean, not the p99).
  EXPECT_GT(stats.p99_period, 0.0);
  EXPECT_LE(stats.p99_period, stats.max_period);
}

TEST(Loop, StopsFromAnotherThread) {
  std::atomic<int> ticks{0};
  Loop loop({0.001, true, false}, [&] { ++ticks; });
  int at_stop = 0;
  std::thread stopper([&] {
    // Bounded wait (30 s) for 20 ticks.
    for (int i = 0; i < 30000 && ticks.load() < 20; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    loop.stop();
    at_stop = ticks.load();
  });
  const LoopStats stats = loop.run_forever();
  stopper.join();
  EXPECT_GE(stats.cycles, 20u);
  // stop() ends the loop after the tick under way: at most one tick after it was asked.
  EXPECT_LE(stats.cycles, static_cast<std::uint64_t>(at_stop) + 1);
}

// The counts a reporter thread reads while the loop runs, and what the log says of them:
// simulated time against the wall clock (each cycle steps the simulation once).
TEST(Loop, ItsProgressIsReadableWhileItRunsAndSaysHowFastSimulatedTimeRuns) {
  std::atomic<std::uint64_t> seen{0};
  Loop loop({0.001, false, false}, [&] {});
  Loop* running = &loop;
  Loop watched({0.001, false, false}, [&] { seen.store(running->progress().cycles); });
  (void)loop.run(250);
  EXPECT_EQ(loop.progress().cycles, 250u);
  EXPECT_EQ(loop.progress().overruns, 0u);  // no deadlines without real time
  running = &watched;
  (void)watched.run(10);
  EXPECT_EQ(seen.load(), 9u);  // during its 10th tick, 9 were done
  EXPECT_EQ(simulated_time_line({100, 3}, {9400, 15}, 10.0, 0.001),
            "simulated time at 0.93 x real time over the last 10.0 s (9300 cycles, 12 over their 1.0 ms "
            "wall-clock period; each steps the simulation once: none is late in simulated time)");
}

TEST(Loop, RejectsBadPeriod) { EXPECT_THROW(Loop({0.0, false, false}, [] {}), std::invalid_argument); }

}  // namespace
}  // namespace concert::robot
